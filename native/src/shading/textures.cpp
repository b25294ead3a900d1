// Procedural textures as Cycles 3.4 computes them (see textures.h). The formulas follow the Cycles
// files named at each section; the operation order is kept where it changes the float result.
#include "shading/textures.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "shading/sky.h"

namespace lt {

namespace {

// floor(x) as an int, clamped to int's range (NaN: 0): Cycles casts directly, which C++ leaves
// undefined beyond the range (a fuzzed or infinite coordinate).
int floor_int(float x) {
  const float f = std::floor(x);
  if (!(f == f)) return 0;
  return f >= 2147483520.0f ? 2147483520 : (f <= -2147483520.0f ? -2147483520 : int(f));
}

constexpr float kTwoPi = 6.2831853071795864f;
constexpr float kHalfPi = 1.5707963267948966f;

// A point of 1-4 dimensions; the unused components stay zero.
struct P4 {
  float c[4] = {0, 0, 0, 0};
};

inline uint32_t float_bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
inline float bits_float(uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
inline float saturate(float x) { return std::min(std::max(x, 0.0f), 1.0f); }
inline float mixf(float a, float b, float t) { return a + t * (b - a); }  // util/math.h mix
inline float smoothstep01(float x) {
  if (x < 0.0f) return 0.0f;
  if (x >= 1.0f) return 1.0f;
  return (3.0f - 2.0f * x) * (x * x);
}
inline float ensure_finite(float v) { return std::isfinite(v) ? v : 0.0f; }

}  // namespace

// ---- util/hash.h: Jenkins lookup3 ----
namespace tex {

namespace {
inline uint32_t rot(uint32_t x, int k) { return (x << k) | (x >> (32 - k)); }
inline void hash_final(uint32_t& a, uint32_t& b, uint32_t& c) {
  c ^= b;
  c -= rot(b, 14);
  a ^= c;
  a -= rot(c, 11);
  b ^= a;
  b -= rot(a, 25);
  c ^= b;
  c -= rot(b, 16);
  a ^= c;
  a -= rot(c, 4);
  b ^= a;
  b -= rot(a, 14);
  c ^= b;
  c -= rot(b, 24);
}
inline void hash_mix(uint32_t& a, uint32_t& b, uint32_t& c) {
  a -= c;
  a ^= rot(c, 4);
  c += b;
  b -= a;
  b ^= rot(a, 6);
  a += c;
  c -= b;
  c ^= rot(b, 8);
  b += a;
  a -= c;
  a ^= rot(c, 16);
  c += b;
  b -= a;
  b ^= rot(a, 19);
  a += c;
  c -= b;
  c ^= rot(b, 4);
  b += a;
}
}  // namespace

uint32_t hash_uint(uint32_t kx) {
  uint32_t a, b, c;
  a = b = c = 0xdeadbeefu + (1u << 2) + 13u;
  a += kx;
  hash_final(a, b, c);
  return c;
}
uint32_t hash_uint2(uint32_t kx, uint32_t ky) {
  uint32_t a, b, c;
  a = b = c = 0xdeadbeefu + (2u << 2) + 13u;
  b += ky;
  a += kx;
  hash_final(a, b, c);
  return c;
}
uint32_t hash_uint3(uint32_t kx, uint32_t ky, uint32_t kz) {
  uint32_t a, b, c;
  a = b = c = 0xdeadbeefu + (3u << 2) + 13u;
  c += kz;
  b += ky;
  a += kx;
  hash_final(a, b, c);
  return c;
}
uint32_t hash_uint4(uint32_t kx, uint32_t ky, uint32_t kz, uint32_t kw) {
  uint32_t a, b, c;
  a = b = c = 0xdeadbeefu + (4u << 2) + 13u;
  a += kx;
  b += ky;
  c += kz;
  hash_mix(a, b, c);
  a += kw;
  hash_final(a, b, c);
  return c;
}

}  // namespace tex

namespace {

using tex::hash_uint;
using tex::hash_uint2;
using tex::hash_uint3;
using tex::hash_uint4;

inline float uint_to_float_incl(uint32_t n) { return (float)n * (1.0f / (float)0xFFFFFFFFu); }
inline float hash1(float x) { return uint_to_float_incl(hash_uint(float_bits(x))); }
inline float hash2(float x, float y) { return uint_to_float_incl(hash_uint2(float_bits(x), float_bits(y))); }
inline float hash3(float x, float y, float z) {
  return uint_to_float_incl(hash_uint3(float_bits(x), float_bits(y), float_bits(z)));
}
inline float hash4(float x, float y, float z, float w) {
  return uint_to_float_incl(hash_uint4(float_bits(x), float_bits(y), float_bits(z), float_bits(w)));
}

// hash_floatN_to_float
inline float hash_n(int n, const P4& k) {
  const float* c = k.c;
  switch (n) {
    case 1:
      return hash1(c[0]);
    case 2:
      return hash2(c[0], c[1]);
    case 3:
      return hash3(c[0], c[1], c[2]);
    default:
      return hash4(c[0], c[1], c[2], c[3]);
  }
}

// hash_floatN_to_floatN (hash_float_to_float for N = 1)
inline P4 hash_n_to_n(int n, const P4& k) {
  const float* c = k.c;
  P4 r;
  switch (n) {
    case 1:
      r.c[0] = hash1(c[0]);
      break;
    case 2:
      r.c[0] = hash2(c[0], c[1]);
      r.c[1] = hash3(c[0], c[1], 1.0f);
      break;
    case 3:
      r.c[0] = hash3(c[0], c[1], c[2]);
      r.c[1] = hash4(c[0], c[1], c[2], 1.0f);
      r.c[2] = hash4(c[0], c[1], c[2], 2.0f);
      break;
    default:
      r.c[0] = hash4(c[0], c[1], c[2], c[3]);
      r.c[1] = hash4(c[3], c[0], c[1], c[2]);
      r.c[2] = hash4(c[2], c[3], c[0], c[1]);
      r.c[3] = hash4(c[1], c[2], c[3], c[0]);
      break;
  }
  return r;
}

// hash_floatN_to_float3
inline Vec3 hash_n_to_3(int n, const P4& k) {
  const float* c = k.c;
  switch (n) {
    case 1:
      return {hash1(c[0]), hash2(c[0], 1.0f), hash2(c[0], 2.0f)};
    case 2:
      return {hash2(c[0], c[1]), hash3(c[0], c[1], 1.0f), hash3(c[0], c[1], 2.0f)};
    case 3:
      return {hash3(c[0], c[1], c[2]), hash4(c[0], c[1], c[2], 1.0f), hash4(c[0], c[1], c[2], 2.0f)};
    default:
      return {hash4(c[0], c[1], c[2], c[3]), hash4(c[2], c[0], c[3], c[1]), hash4(c[3], c[2], c[1], c[0])};
  }
}

// ---- kernel/svm/noise.h: Perlin noise (the scalar path) ----
inline float fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }
inline float negate_if(float v, uint32_t cond) { return cond ? -v : v; }
inline float floorfrac(float x, int* i) {
  float f = std::floor(x);
  *i = (int)f;
  return x - f;
}

inline float grad1(uint32_t hash, float x) {
  uint32_t h = hash & 15;
  float g = 1 + (h & 7);
  return negate_if(g, h & 8) * x;
}
inline float grad2(uint32_t hash, float x, float y) {
  uint32_t h = hash & 7;
  float u = h < 4 ? x : y;
  float v = 2.0f * (h < 4 ? y : x);
  return negate_if(u, h & 1) + negate_if(v, h & 2);
}
inline float grad3(uint32_t hash, float x, float y, float z) {
  uint32_t h = hash & 15;
  float u = h < 8 ? x : y;
  float vt = ((h == 12) || (h == 14)) ? x : z;
  float v = h < 4 ? y : vt;
  return negate_if(u, h & 1) + negate_if(v, h & 2);
}
inline float grad4(uint32_t hash, float x, float y, float z, float w) {
  uint32_t h = hash & 31;
  float u = h < 24 ? x : y;
  float v = h < 16 ? y : z;
  float s = h < 8 ? z : w;
  return negate_if(u, h & 1) + negate_if(v, h & 2) + negate_if(s, h & 4);
}
inline float bi_mix(float v0, float v1, float v2, float v3, float x, float y) {
  float x1 = 1.0f - x;
  return (1.0f - y) * (v0 * x1 + v1 * x) + y * (v2 * x1 + v3 * x);
}
inline float tri_mix(float v0, float v1, float v2, float v3, float v4, float v5, float v6, float v7, float x, float y,
                     float z) {
  float x1 = 1.0f - x, y1 = 1.0f - y, z1 = 1.0f - z;
  return z1 * (y1 * (v0 * x1 + v1 * x) + y * (v2 * x1 + v3 * x)) +
         z * (y1 * (v4 * x1 + v5 * x) + y * (v6 * x1 + v7 * x));
}

float perlin_1d(float x) {
  int X;
  float fx = floorfrac(x, &X);
  float u = fade(fx);
  return mixf(grad1(hash_uint(X), fx), grad1(hash_uint(X + 1), fx - 1.0f), u);
}
float perlin_2d(float x, float y) {
  int X, Y;
  float fx = floorfrac(x, &X), fy = floorfrac(y, &Y);
  float u = fade(fx), v = fade(fy);
  return bi_mix(grad2(hash_uint2(X, Y), fx, fy), grad2(hash_uint2(X + 1, Y), fx - 1.0f, fy),
                grad2(hash_uint2(X, Y + 1), fx, fy - 1.0f), grad2(hash_uint2(X + 1, Y + 1), fx - 1.0f, fy - 1.0f), u,
                v);
}
float perlin_3d(float x, float y, float z) {
  int X, Y, Z;
  float fx = floorfrac(x, &X), fy = floorfrac(y, &Y), fz = floorfrac(z, &Z);
  float u = fade(fx), v = fade(fy), w = fade(fz);
  return tri_mix(
      grad3(hash_uint3(X, Y, Z), fx, fy, fz), grad3(hash_uint3(X + 1, Y, Z), fx - 1.0f, fy, fz),
      grad3(hash_uint3(X, Y + 1, Z), fx, fy - 1.0f, fz), grad3(hash_uint3(X + 1, Y + 1, Z), fx - 1.0f, fy - 1.0f, fz),
      grad3(hash_uint3(X, Y, Z + 1), fx, fy, fz - 1.0f), grad3(hash_uint3(X + 1, Y, Z + 1), fx - 1.0f, fy, fz - 1.0f),
      grad3(hash_uint3(X, Y + 1, Z + 1), fx, fy - 1.0f, fz - 1.0f),
      grad3(hash_uint3(X + 1, Y + 1, Z + 1), fx - 1.0f, fy - 1.0f, fz - 1.0f), u, v, w);
}
float perlin_4d(float x, float y, float z, float w) {
  int X, Y, Z, W;
  float fx = floorfrac(x, &X), fy = floorfrac(y, &Y), fz = floorfrac(z, &Z), fw = floorfrac(w, &W);
  float u = fade(fx), v = fade(fy), t = fade(fz), s = fade(fw);
  float g[16];
  for (int l = 0; l < 2; l++) {
    for (int k = 0; k < 2; k++) {
      for (int j = 0; j < 2; j++) {
        for (int i = 0; i < 2; i++) {
          g[i + 2 * j + 4 * k + 8 * l] = grad4(hash_uint4(X + i, Y + j, Z + k, W + l), fx - i, fy - j, fz - k, fw - l);
        }
      }
    }
  }
  return mixf(tri_mix(g[0], g[1], g[2], g[3], g[4], g[5], g[6], g[7], u, v, t),
              tri_mix(g[8], g[9], g[10], g[11], g[12], g[13], g[14], g[15], u, v, t), s);
}

// snoise_Nd: signed noise remapped to about [-1, 1] with OSL's scales.
inline float snoise(int n, const P4& p) {
  const float* c = p.c;
  switch (n) {
    case 1:
      return 0.2500f * ensure_finite(perlin_1d(c[0]));
    case 2:
      return 0.6616f * ensure_finite(perlin_2d(c[0], c[1]));
    case 3:
      return 0.9820f * ensure_finite(perlin_3d(c[0], c[1], c[2]));
    default:
      return 0.8344f * ensure_finite(perlin_4d(c[0], c[1], c[2], c[3]));
  }
}
inline float unoise(int n, const P4& p) { return 0.5f * snoise(n, p) + 0.5f; }

inline P4 scaled(int n, const P4& p, float s) {
  P4 r;
  for (int i = 0; i < n; i++) r.c[i] = s * p.c[i];
  return r;
}

// ---- kernel/svm/fractal_noise.h ----
float fractal_noise(int n, const P4& p, float octaves, float roughness) {
  float fscale = 1.0f, amp = 1.0f, maxamp = 0.0f, sum = 0.0f;
  octaves = clamp(octaves, 0.0f, 15.0f);
  int count = (int)octaves;
  for (int i = 0; i <= count; i++) {
    float t = unoise(n, scaled(n, p, fscale));
    sum += t * amp;
    maxamp += amp;
    amp *= clamp(roughness, 0.0f, 1.0f);
    fscale *= 2.0f;
  }
  float rmd = octaves - std::floor(octaves);
  if (rmd != 0.0f) {
    float t = unoise(n, scaled(n, p, fscale));
    float sum2 = sum + t * amp;
    sum /= maxamp;
    sum2 /= maxamp + amp;
    return (1.0f - rmd) * sum + rmd * sum2;
  }
  return sum / maxamp;
}

// ---- kernel/svm/noisetex.h ----
// random_floatN_offset: component i of the seed's offset (the 1D one hashes the seed alone).
inline float random_offset(int n, float seed, int i) {
  if (n == 1) return 100.0f + hash1(seed) * 100.0f;
  return 100.0f + hash2(seed, (float)i) * 100.0f;
}
inline P4 offset_by(int n, const P4& p, float seed) {
  P4 r = p;
  for (int i = 0; i < n; i++) r.c[i] += random_offset(n, seed, i);
  return r;
}

void noise_texture_n(int n, const P4& co, float detail, float roughness, float distortion, float* value, Vec3* color) {
  P4 p = co;
  if (distortion != 0.0f) {
    // The distortion of each component uses its own seed; all read the undistorted point.
    P4 d;
    for (int i = 0; i < n; i++) d.c[i] = snoise(n, offset_by(n, p, (float)i)) * distortion;
    for (int i = 0; i < n; i++) p.c[i] += d.c[i];
  }
  *value = fractal_noise(n, p, detail, roughness);
  if (color) {
    // Colour seeds continue after the distortion seeds (1D: 1, 2; 2D: 2, 3; 3D: 3, 4; 4D: 4, 5).
    float s = (float)n;
    *color = {*value, fractal_noise(n, offset_by(n, p, s), detail, roughness),
              fractal_noise(n, offset_by(n, p, s + 1.0f), detail, roughness)};
  }
}

// ---- kernel/svm/voronoi.h ----
struct VoronoiOut {
  float distance = 0, w = 0, radius = 0;
  Vec3 color{0, 0, 0};
  P4 position;
};

inline float voronoi_distance(int n, const P4& a, const P4& b, uint32_t metric, float exponent) {
  if (n == 1) return std::fabs(b.c[0] - a.c[0]);  // 1D ignores the metric
  float d[4];
  for (int i = 0; i < n; i++) d[i] = a.c[i] - b.c[i];
  switch (metric) {
    case kVoronoiEuclidean: {
      float s = 0;
      for (int i = 0; i < n; i++) s += d[i] * d[i];
      return std::sqrt(s);
    }
    case kVoronoiManhattan: {
      float s = 0;
      for (int i = 0; i < n; i++) s += std::fabs(d[i]);
      return s;
    }
    case kVoronoiChebychev: {
      // Cycles nests max from the last component inwards; max is exact, so order does not matter.
      float s = std::fabs(d[0]);
      for (int i = 1; i < n; i++) s = std::max(s, std::fabs(d[i]));
      return s;
    }
    case kVoronoiMinkowski: {
      float s = 0;
      for (int i = 0; i < n; i++) s += std::pow(std::fabs(d[i]), exponent);
      return std::pow(s, 1.0f / exponent);
    }
    default:
      return 0.0f;
  }
}
inline float euclid(int n, const P4& a, const P4& b) { return voronoi_distance(n, a, b, kVoronoiEuclidean, 0); }

// Calls f(offset) for every cell offset in [-r, r]^n, first component fastest (Cycles' loop order).
template <typename F>
inline void for_cells(int n, int r, F&& f) {
  int lo[4] = {0, 0, 0, 0}, hi[4] = {0, 0, 0, 0};
  for (int i = 0; i < n; i++) lo[i] = -r, hi[i] = r;
  for (int u = lo[3]; u <= hi[3]; u++)
    for (int k = lo[2]; k <= hi[2]; k++)
      for (int j = lo[1]; j <= hi[1]; j++)
        for (int i = lo[0]; i <= hi[0]; i++) {
          P4 o;
          o.c[0] = (float)i;
          o.c[1] = (float)j;
          o.c[2] = (float)k;
          o.c[3] = (float)u;
          f(o);
        }
}

inline P4 add(int n, const P4& a, const P4& b) {
  P4 r;
  for (int i = 0; i < n; i++) r.c[i] = a.c[i] + b.c[i];
  return r;
}
inline P4 sub(int n, const P4& a, const P4& b) {
  P4 r;
  for (int i = 0; i < n; i++) r.c[i] = a.c[i] - b.c[i];
  return r;
}
inline float dotn(int n, const P4& a, const P4& b) {
  float s = 0;
  for (int i = 0; i < n; i++) s += a.c[i] * b.c[i];
  return s;
}
// cellOffset + hash(cellPosition + cellOffset) * randomness
inline P4 point_in_cell(int n, const P4& cell, const P4& offset, float randomness) {
  P4 h = hash_n_to_n(n, add(n, cell, offset));
  P4 r;
  for (int i = 0; i < n; i++) r.c[i] = offset.c[i] + h.c[i] * randomness;
  return r;
}

void voronoi_f1(int n, const P4& coord, float exponent, float randomness, uint32_t metric, VoronoiOut* out) {
  P4 cell, local;
  for (int i = 0; i < n; i++) cell.c[i] = std::floor(coord.c[i]), local.c[i] = coord.c[i] - cell.c[i];
  float min_distance = 8.0f;
  P4 target_offset, target_position;
  for_cells(n, 1, [&](const P4& o) {
    P4 pp = point_in_cell(n, cell, o, randomness);
    float d = voronoi_distance(n, pp, local, metric, exponent);
    if (d < min_distance) {
      target_offset = o;
      min_distance = d;
      target_position = pp;
    }
  });
  out->distance = min_distance;
  out->color = hash_n_to_3(n, add(n, cell, target_offset));
  out->position = add(n, target_position, cell);
}

void voronoi_smooth_f1(int n, const P4& coord, float smoothness, float exponent, float randomness, uint32_t metric,
                       VoronoiOut* out) {
  P4 cell, local;
  for (int i = 0; i < n; i++) cell.c[i] = std::floor(coord.c[i]), local.c[i] = coord.c[i] - cell.c[i];
  float smooth_distance = 8.0f;
  Vec3 smooth_color{0, 0, 0};
  P4 smooth_position;
  for_cells(n, 2, [&](const P4& o) {
    P4 pp = point_in_cell(n, cell, o, randomness);
    float d = voronoi_distance(n, pp, local, metric, exponent);
    float h = smoothstep01(0.5f + 0.5f * (smooth_distance - d) / smoothness);
    float correction = smoothness * h * (1.0f - h);
    smooth_distance = mixf(smooth_distance, d, h) - correction;
    correction /= 1.0f + 3.0f * smoothness;
    Vec3 cc = hash_n_to_3(n, add(n, cell, o));
    smooth_color = {mixf(smooth_color.x, cc.x, h) - correction, mixf(smooth_color.y, cc.y, h) - correction,
                    mixf(smooth_color.z, cc.z, h) - correction};
    for (int i = 0; i < n; i++) smooth_position.c[i] = mixf(smooth_position.c[i], pp.c[i], h) - correction;
  });
  out->distance = smooth_distance;
  out->color = smooth_color;
  out->position = add(n, cell, smooth_position);
}

void voronoi_f2(int n, const P4& coord, float exponent, float randomness, uint32_t metric, VoronoiOut* out) {
  P4 cell, local;
  for (int i = 0; i < n; i++) cell.c[i] = std::floor(coord.c[i]), local.c[i] = coord.c[i] - cell.c[i];
  float d1 = 8.0f, d2 = 8.0f;
  P4 offset1, position1, offset2, position2;
  for_cells(n, 1, [&](const P4& o) {
    P4 pp = point_in_cell(n, cell, o, randomness);
    float d = voronoi_distance(n, pp, local, metric, exponent);
    if (d < d1) {
      d2 = d1;
      d1 = d;
      offset2 = offset1;
      offset1 = o;
      position2 = position1;
      position1 = pp;
    } else if (d < d2) {
      d2 = d;
      offset2 = o;
      position2 = pp;
    }
  });
  out->distance = d2;
  out->color = hash_n_to_3(n, add(n, cell, offset2));
  out->position = add(n, position2, cell);
}

float voronoi_distance_to_edge(int n, const P4& coord, float randomness) {
  P4 cell, local;
  for (int i = 0; i < n; i++) cell.c[i] = std::floor(coord.c[i]), local.c[i] = coord.c[i] - cell.c[i];
  if (n == 1) {
    float x = local.c[0], c = cell.c[0];
    float mid = hash1(c) * randomness;
    float left = -1.0f + hash1(c - 1.0f) * randomness;
    float right = 1.0f + hash1(c + 1.0f) * randomness;
    return std::min(std::fabs((mid + left) / 2.0f - x), std::fabs((mid + right) / 2.0f - x));
  }
  P4 to_closest;
  float min_distance = 8.0f;
  for_cells(n, 1, [&](const P4& o) {
    P4 v = sub(n, point_in_cell(n, cell, o, randomness), local);
    float d = dotn(n, v, v);
    if (d < min_distance) {
      min_distance = d;
      to_closest = v;
    }
  });
  min_distance = 8.0f;
  for_cells(n, 1, [&](const P4& o) {
    P4 v = sub(n, point_in_cell(n, cell, o, randomness), local);
    P4 perp = sub(n, v, to_closest);
    float pp = dotn(n, perp, perp);
    if (pp > 0.0001f) {
      float len = std::sqrt(pp);
      P4 mid, dir;
      for (int i = 0; i < n; i++) mid.c[i] = (to_closest.c[i] + v.c[i]) / 2.0f, dir.c[i] = perp.c[i] / len;
      min_distance = std::min(min_distance, dotn(n, mid, dir));
    }
  });
  return min_distance;
}

float voronoi_n_sphere_radius(int n, const P4& coord, float randomness) {
  P4 cell, local;
  for (int i = 0; i < n; i++) cell.c[i] = std::floor(coord.c[i]), local.c[i] = coord.c[i] - cell.c[i];
  P4 closest, closest_offset;
  float min_distance = 8.0f;
  for_cells(n, 1, [&](const P4& o) {
    P4 pp = point_in_cell(n, cell, o, randomness);
    float d = euclid(n, pp, local);
    if (d < min_distance) {
      min_distance = d;
      closest = pp;
      closest_offset = o;
    }
  });
  min_distance = 8.0f;
  P4 closest_to_closest;
  for_cells(n, 1, [&](const P4& o) {
    if (o.c[0] == 0 && o.c[1] == 0 && o.c[2] == 0 && o.c[3] == 0) return;
    P4 off = add(n, o, closest_offset);
    P4 pp = point_in_cell(n, cell, off, randomness);
    float d = euclid(n, closest, pp);
    if (d < min_distance) {
      min_distance = d;
      closest_to_closest = pp;
    }
  });
  return euclid(n, closest_to_closest, closest) / 2.0f;
}

// ---- kernel/svm/musgrave.h ----
inline P4 times(int n, P4 p, float s) {
  for (int i = 0; i < n; i++) p.c[i] *= s;
  return p;
}

float musgrave_fbm(int n, P4 p, float H, float lacunarity, float octaves) {
  float value = 0.0f, pwr = 1.0f, pwHL = std::pow(lacunarity, -H);
  for (int i = 0; i < (int)octaves; i++) {
    value += snoise(n, p) * pwr;
    pwr *= pwHL;
    p = times(n, p, lacunarity);
  }
  float rmd = octaves - std::floor(octaves);
  if (rmd != 0.0f) value += rmd * snoise(n, p) * pwr;
  return value;
}
float musgrave_multi_fractal(int n, P4 p, float H, float lacunarity, float octaves) {
  float value = 1.0f, pwr = 1.0f, pwHL = std::pow(lacunarity, -H);
  for (int i = 0; i < (int)octaves; i++) {
    value *= (pwr * snoise(n, p) + 1.0f);
    pwr *= pwHL;
    p = times(n, p, lacunarity);
  }
  float rmd = octaves - std::floor(octaves);
  if (rmd != 0.0f) value *= (rmd * pwr * snoise(n, p) + 1.0f);
  return value;
}
float musgrave_hetero_terrain(int n, P4 p, float H, float lacunarity, float octaves, float offset) {
  float pwHL = std::pow(lacunarity, -H), pwr = pwHL;
  float value = offset + snoise(n, p);
  p = times(n, p, lacunarity);
  for (int i = 1; i < (int)octaves; i++) {
    float increment = (snoise(n, p) + offset) * pwr * value;
    value += increment;
    pwr *= pwHL;
    p = times(n, p, lacunarity);
  }
  float rmd = octaves - std::floor(octaves);
  if (rmd != 0.0f) {
    float increment = (snoise(n, p) + offset) * pwr * value;
    value += rmd * increment;
  }
  return value;
}
float musgrave_hybrid_multi_fractal(int n, P4 p, float H, float lacunarity, float octaves, float offset, float gain) {
  float pwHL = std::pow(lacunarity, -H), pwr = 1.0f, value = 0.0f, weight = 1.0f;
  for (int i = 0; (weight > 0.001f) && (i < (int)octaves); i++) {
    if (weight > 1.0f) weight = 1.0f;
    float signal = (snoise(n, p) + offset) * pwr;
    pwr *= pwHL;
    value += weight * signal;
    weight *= gain * signal;
    p = times(n, p, lacunarity);
  }
  float rmd = octaves - std::floor(octaves);
  if ((rmd != 0.0f) && (weight > 0.001f)) {
    if (weight > 1.0f) weight = 1.0f;
    float signal = (snoise(n, p) + offset) * pwr;
    value += rmd * weight * signal;
  }
  return value;
}
float musgrave_ridged_multi_fractal(int n, P4 p, float H, float lacunarity, float octaves, float offset, float gain) {
  float pwHL = std::pow(lacunarity, -H), pwr = pwHL;
  float signal = offset - std::fabs(snoise(n, p));
  signal *= signal;
  float value = signal, weight = 1.0f;
  for (int i = 1; i < (int)octaves; i++) {
    p = times(n, p, lacunarity);
    weight = saturate(signal * gain);
    signal = offset - std::fabs(snoise(n, p));
    signal *= signal;
    signal *= weight;
    value += signal * pwr;
    pwr *= pwHL;
  }
  return value;
}

// ---- kernel/svm/wave.h ----
float wave(uint32_t type, uint32_t bands_dir, uint32_t rings_dir, uint32_t profile, Vec3 p, float distortion,
           float detail, float dscale, float droughness, float phase) {
  p = Vec3{(p.x + 0.000001f) * 0.999999f, (p.y + 0.000001f) * 0.999999f, (p.z + 0.000001f) * 0.999999f};
  float n;
  if (type == 0) {
    if (bands_dir == 0)
      n = p.x * 20.0f;
    else if (bands_dir == 1)
      n = p.y * 20.0f;
    else if (bands_dir == 2)
      n = p.z * 20.0f;
    else
      n = (p.x + p.y + p.z) * 10.0f;
  } else {
    Vec3 rp = p;
    if (rings_dir == 0)
      rp.x = 0.0f;
    else if (rings_dir == 1)
      rp.y = 0.0f;
    else if (rings_dir == 2)
      rp.z = 0.0f;
    n = std::sqrt(rp.x * rp.x + rp.y * rp.y + rp.z * rp.z) * 20.0f;
  }
  n += phase;
  if (distortion != 0.0f) {
    P4 q;
    q.c[0] = p.x * dscale;
    q.c[1] = p.y * dscale;
    q.c[2] = p.z * dscale;
    n += distortion * (fractal_noise(3, q, detail, droughness) * 2.0f - 1.0f);
  }
  if (profile == 0) return 0.5f + 0.5f * std::sin(n - kHalfPi);
  n /= kTwoPi;
  if (profile == 1) return n - std::floor(n);
  return std::fabs(n - std::floor(n + 0.5f)) * 2.0f;
}

// ---- kernel/svm/magic.h ----
Vec3 magic(Vec3 p, float scale, int depth, float distortion) {
  // fmod keeps sin/cos arguments small (Cycles: avoids NaNs and banding at large coordinates).
  float px = std::fmod(p.x, kTwoPi), py = std::fmod(p.y, kTwoPi), pz = std::fmod(p.z, kTwoPi);
  float x = std::sin((px + py + pz) * 5.0f * scale);
  float y = std::cos((-px + py - pz) * 5.0f * scale);
  float z = -std::cos((-px - py + pz) * 5.0f * scale);
  if (depth > 0) {
    x *= distortion;
    y *= distortion;
    z *= distortion;
    y = -std::cos(x - y + z);
    y *= distortion;
    if (depth > 1) {
      x = std::cos(x - y - z);
      x *= distortion;
      if (depth > 2) {
        z = std::sin(-x - y - z);
        z *= distortion;
        if (depth > 3) {
          x = -std::cos(-x + y - z);
          x *= distortion;
          if (depth > 4) {
            y = -std::sin(-x + y + z);
            y *= distortion;
            if (depth > 5) {
              y = -std::cos(-x + y + z);
              y *= distortion;
              if (depth > 6) {
                x = std::cos(x + y + z);
                x *= distortion;
                if (depth > 7) {
                  z = std::sin(x + y - z);
                  z *= distortion;
                  if (depth > 8) {
                    x = -std::cos(-x - y + z);
                    x *= distortion;
                    if (depth > 9) {
                      y = -std::sin(x - y + z);
                      y *= distortion;
                    }
                  }
                }
              }
            }
          }
        }
      }
    }
  }
  if (distortion != 0.0f) {
    distortion *= 2.0f;
    x /= distortion;
    y /= distortion;
    z /= distortion;
  }
  return {0.5f - x, 0.5f - y, 0.5f - z};
}

// ---- kernel/svm/checker.h ----
float checker(Vec3 p) {
  p.x = (p.x + 0.000001f) * 0.999999f;
  p.y = (p.y + 0.000001f) * 0.999999f;
  p.z = (p.z + 0.000001f) * 0.999999f;
  int xi = std::abs(floor_int(p.x));
  int yi = std::abs(floor_int(p.y));
  int zi = std::abs(floor_int(p.z));
  return ((int)(xi % 2 == yi % 2) == (zi % 2)) ? 1.0f : 0.0f;
}

// ---- kernel/svm/brick.h ----
float brick_noise(uint32_t n) {
  n = (n + 1013) & 0x7fffffffu;
  n = (n >> 13) ^ n;
  uint32_t nn = (n * (n * n * 60493u + 19990303u) + 1376312589u) & 0x7fffffffu;
  return 0.5f * ((float)nn / 1073741824.0f);
}

// Returns (tint, mortar).
void brick(Vec3 p, float mortar_size, float mortar_smooth, float bias, float brick_width, float row_height,
           float offset_amount, int offset_frequency, float squash_amount, int squash_frequency, float* tint,
           float* mortar) {
  float offset = 0.0f;
  int rownum = floor_int(p.y / row_height);
  if (offset_frequency && squash_frequency) {
    brick_width *= (rownum % squash_frequency) ? 1.0f : squash_amount;
    offset = (rownum % offset_frequency) ? 0.0f : (brick_width * offset_amount);
  }
  int bricknum = floor_int((p.x + offset) / brick_width);
  float x = (p.x + offset) - brick_width * bricknum;
  float y = p.y - row_height * rownum;
  *tint = saturate(brick_noise(((uint32_t)rownum << 16) + (uint32_t)(bricknum & 0xFFFF)) + bias);
  float min_dist = std::min(std::min(x, y), std::min(brick_width - x, row_height - y));
  if (min_dist >= mortar_size) {
    *mortar = 0.0f;
  } else if (mortar_smooth == 0.0f) {
    *mortar = 1.0f;
  } else {
    min_dist = 1.0f - min_dist / mortar_size;
    float t = min_dist / mortar_smooth;
    *mortar = (min_dist < mortar_smooth) ? (3.0f * t * t - 2.0f * t * t * t) : 1.0f;
  }
}

// ---- kernel/svm/gradient.h ----
float gradient(Vec3 p, uint32_t type) {
  float x = p.x, y = p.y, z = p.z;
  switch (type) {
    case kGradientLinear:
      return x;
    case kGradientQuadratic: {
      float r = std::max(x, 0.0f);
      return r * r;
    }
    case kGradientEasing: {
      float r = std::min(std::max(x, 0.0f), 1.0f);
      float t = r * r;
      return (3.0f * t - 2.0f * t * r);
    }
    case kGradientDiagonal:
      return (x + y) * 0.5f;
    case kGradientRadial:
      return std::atan2(y, x) / kTwoPi + 0.5f;
    case kGradientQuadraticSphere:
    case kGradientSpherical: {
      // The bias gives exactly zero on unit vectors.
      float r = std::max(0.999999f - std::sqrt(x * x + y * y + z * z), 0.0f);
      return type == kGradientQuadraticSphere ? r * r : r;
    }
    default:
      return 0.0f;
  }
}

inline int dims_of(uint32_t p) { return (int)clamp<uint32_t>(p, 1, 4); }

// Point of the given dimension from Cycles' (vector, w) inputs: 1D is w, 2D xy, 3D xyz, 4D xyzw.
inline P4 point_of(int n, const Vec3& v, float w) {
  P4 p;
  if (n == 1) {
    p.c[0] = w;
  } else {
    p.c[0] = v.x;
    p.c[1] = v.y;
    if (n >= 3) p.c[2] = v.z;
    if (n == 4) p.c[3] = w;
  }
  return p;
}

// Every texture is pure: it reads nothing but its operands.
const OpSignature kSignatures[] = {
    {"vfffff", "fv", "i", true},         // noise
    {"vfffff", "fvvff", "iii", true},    // voronoi
    {"vfffffff", "f", "ii", true},       // musgrave
    {"vffffff", "vf", "iiii", true},     // wave
    {"vff", "vf", "i", true},            // magic
    {"vvvf", "vf", "", true},            // checker
    {"vvvvffffff", "vf", "iiii", true},  // brick (the amounts are float bits: any word is valid)
    {"v", "vf", "i", true},              // gradient
    {"vf", "fv", "i", true},             // white noise
    {"v", "v", "iiiiiiiiiit", true},     // sky (settings as float bits; the table the loader's)
};
static_assert(sizeof(kSignatures) / sizeof(kSignatures[0]) == kTexturesFamilyEnd - kFamilyTexturesBegin,
              "one signature per texture opcode");

}  // namespace

const OpSignature* textures_family_signature(uint32_t op) {
  if (op < kFamilyTexturesBegin || op >= kTexturesFamilyEnd) return nullptr;
  return &kSignatures[op - kFamilyTexturesBegin];
}

namespace tex {
float hash_float_to_float(float k) { return hash1(k); }
float perlin(int dims, const float* p) {
  switch (dims) {
    case 1:
      return perlin_1d(p[0]);
    case 2:
      return perlin_2d(p[0], p[1]);
    case 3:
      return perlin_3d(p[0], p[1], p[2]);
    default:
      return perlin_4d(p[0], p[1], p[2], p[3]);
  }
}
void noise_texture(int dims, const float p[4], float detail, float roughness, float distortion, float* fac,
                   Vec3* color) {
  P4 q;
  for (int i = 0; i < 4; i++) q.c[i] = p[i];
  noise_texture_n(dims_of(dims), q, detail, roughness, distortion, fac, color);
}
}  // namespace tex

// The loader has checked the instruction against textures_family_signature.
void exec_textures_family(const Instr& in, Machine& m) {
  const uint32_t* a = in.in;
  const uint32_t* o = in.out;
  const uint32_t* prm = in.param;
  switch (in.op) {
    case kOpTexNoise: {  // noisetex.h svm_node_tex_noise
      int n = dims_of(prm[0]);
      float scale = m.f(a[2]);
      P4 p = point_of(n, m.v(a[0]) * scale, m.f(a[1]) * scale);
      float fac;
      Vec3 color;
      noise_texture_n(n, p, m.f(a[3]), m.f(a[4]), m.f(a[5]), &fac, &color);
      m.set(o[0], fac);
      m.set(o[1], color);
      return;
    }
    case kOpTexVoronoi: {  // voronoi.h svm_node_tex_voronoi
      int n = dims_of(prm[0]);
      uint32_t feature = prm[1], metric = prm[2];
      float scale = m.f(a[2]);
      float smoothness = clamp(m.f(a[3]) / 2.0f, 0.0f, 0.5f);
      float exponent = m.f(a[4]);
      float randomness = clamp(m.f(a[5]), 0.0f, 1.0f);
      P4 p = point_of(n, m.v(a[0]) * scale, m.f(a[1]) * scale);
      VoronoiOut r;
      switch (feature) {
        case kVoronoiF1:
          voronoi_f1(n, p, exponent, randomness, metric, &r);
          break;
        case kVoronoiSmoothF1:
          voronoi_smooth_f1(n, p, smoothness, exponent, randomness, metric, &r);
          break;
        case kVoronoiF2:
          voronoi_f2(n, p, exponent, randomness, metric, &r);
          break;
        case kVoronoiDistanceToEdge:
          r.distance = voronoi_distance_to_edge(n, p, randomness);
          break;
        case kVoronoiNSphereRadius:
          r.radius = voronoi_n_sphere_radius(n, p, randomness);
          break;
        default:
          break;
      }
      // Positions back in unscaled space; which components are outputs depends on the dimension.
      P4 pos;
      for (int i = 0; i < 4; i++) pos.c[i] = scale != 0.0f ? r.position.c[i] / scale : 0.0f;
      Vec3 position{0, 0, 0};
      float w_out = 0.0f;
      if (n == 1) {
        w_out = pos.c[0];
      } else {
        position = {pos.c[0], pos.c[1], n >= 3 ? pos.c[2] : 0.0f};
        if (n == 4) w_out = pos.c[3];
      }
      m.set(o[0], r.distance);
      m.set(o[1], r.color);
      m.set(o[2], position);
      m.set(o[3], w_out);
      m.set(o[4], r.radius);
      return;
    }
    case kOpTexMusgrave: {  // musgrave.h svm_node_tex_musgrave
      int n = dims_of(prm[0]);
      float scale = m.f(a[2]);
      float detail = clamp(m.f(a[3]), 0.0f, 15.0f);
      float dimension = std::max(m.f(a[4]), 1e-5f);
      float lacunarity = std::max(m.f(a[5]), 1e-5f);
      float offset = m.f(a[6]), gain = m.f(a[7]);
      // Cycles scales after assembling the point (1D: w * scale).
      P4 p = times(n, point_of(n, m.v(a[0]), m.f(a[1])), scale);
      float fac;
      switch (prm[1]) {
        case kMusgraveMultifractal:
          fac = musgrave_multi_fractal(n, p, dimension, lacunarity, detail);
          break;
        case kMusgraveFbm:
          fac = musgrave_fbm(n, p, dimension, lacunarity, detail);
          break;
        case kMusgraveHybridMultifractal:
          fac = musgrave_hybrid_multi_fractal(n, p, dimension, lacunarity, detail, offset, gain);
          break;
        case kMusgraveRidgedMultifractal:
          fac = musgrave_ridged_multi_fractal(n, p, dimension, lacunarity, detail, offset, gain);
          break;
        case kMusgraveHeteroTerrain:
          fac = musgrave_hetero_terrain(n, p, dimension, lacunarity, detail, offset);
          break;
        default:
          fac = 0.0f;
      }
      m.set(o[0], fac);
      return;
    }
    case kOpTexWave: {  // wave.h svm_node_tex_wave
      float f = wave(prm[0], prm[1], prm[2], prm[3], m.v(a[0]) * m.f(a[1]), m.f(a[2]), m.f(a[3]), m.f(a[4]), m.f(a[5]),
                     m.f(a[6]));
      m.set(o[0], Vec3{f, f, f});
      m.set(o[1], f);
      return;
    }
    case kOpTexMagic: {  // magic.h svm_node_tex_magic
      Vec3 c = magic(m.v(a[0]), m.f(a[1]), (int)prm[0], m.f(a[2]));
      m.set(o[0], c);
      m.set(o[1], (c.x + c.y + c.z) * (1.0f / 3.0f));
      return;
    }
    case kOpTexChecker: {  // checker.h svm_node_tex_checker
      float f = checker(m.v(a[0]) * m.f(a[3]));
      m.set(o[0], f == 1.0f ? m.v(a[1]) : m.v(a[2]));
      m.set(o[1], f);
      return;
    }
    case kOpTexBrick: {  // brick.h svm_node_tex_brick
      Vec3 color1 = m.v(a[1]), color2 = m.v(a[2]), mortar = m.v(a[3]);
      float tint, f;
      brick(m.v(a[0]) * m.f(a[4]), m.f(a[5]), m.f(a[6]), m.f(a[7]), m.f(a[8]), m.f(a[9]), bits_float(prm[2]),
            (int)prm[0], bits_float(prm[3]), (int)prm[1], &tint, &f);
      if (f != 1.0f) color1 = (1.0f - tint) * color1 + tint * color2;
      m.set(o[0], color1 * (1.0f - f) + mortar * f);
      m.set(o[1], f);
      return;
    }
    case kOpTexGradient: {  // gradient.h svm_node_tex_gradient
      float f = saturate(gradient(m.v(a[0]), prm[0]));
      m.set(o[0], Vec3{f, f, f});
      m.set(o[1], f);
      return;
    }
    case kOpTexWhiteNoise: {  // white_noise.h svm_node_tex_white_noise
      int n = dims_of(prm[0]);
      P4 p = point_of(n, m.v(a[0]), m.f(a[1]));
      m.set(o[0], hash_n(n, p));
      m.set(o[1], hash_n_to_3(n, p));
      return;
    }
    case kOpTexSky: {  // sky.h svm_node_tex_sky
      m.set(o[0], sky::radiance(prm[0], m.k + prm[1 + sky::kSettings] + 1, m.v(a[0])));
      return;
    }
    default:
      return;
  }
}

void prepare_textures_family(uint32_t op, uint32_t* prm, std::vector<float>* pool) {
  if (op != kOpTexSky) return;
  float settings[sky::kSettings];
  std::memcpy(settings, prm + 1, sizeof settings);
  // The table is the core's, whatever the program said: the op reads it blindly.
  const std::vector<float> table = sky::make_table(prm[0], settings);
  prm[1 + sky::kSettings] = uint32_t(pool->size());
  pool->push_back(float(table.size()));
  pool->insert(pool->end(), table.begin(), table.end());
}

}  // namespace lt
