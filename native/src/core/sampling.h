// Warps from the unit square to directions and shapes, their pdfs, MIS heuristics and the
// counter-based random numbers that make renders independent of thread count and tile order.
#pragma once

#include "core/math.h"

namespace lt {

struct Vec2 {
  float x = 0, y = 0;
};

// Shirley & Chiu's concentric map of the square to the unit disk.
inline Vec2 sample_disk_concentric(Vec2 u) {
  float a = 2 * u.x - 1, b = 2 * u.y - 1;
  if (a == 0 && b == 0) return {0, 0};
  float r, phi;
  if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = (kPi / 4) * (b / a);
  } else {
    r = b;
    phi = (kPi / 2) - (kPi / 4) * (a / b);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

inline Vec3 sample_cosine_hemisphere(Vec2 u) {
  Vec2 d = sample_disk_concentric(u);
  return {d.x, d.y, safe_sqrt(1 - d.x * d.x - d.y * d.y)};
}
inline float cosine_hemisphere_pdf(float cos_theta) { return cos_theta > 0 ? cos_theta * kInvPi : 0; }

inline Vec3 sample_uniform_sphere(Vec2 u) {
  float z = 1 - 2 * u.x;
  float r = safe_sqrt(1 - z * z);
  float phi = 2 * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}
inline float uniform_sphere_pdf() { return kInv4Pi; }

// Blender's equirectangular projection (Cycles' direction_to_equirectangular, kernel/camera/
// projection.h): +X at the image centre, +Z at the top; a zero direction maps to (0, 0).
inline Vec2 direction_to_equirectangular(const Vec3& d) {
  const float l = length(d);
  if (!(l > 0)) return {0, 0};
  return {(std::atan2(d.y, d.x) - kPi) / (-2 * kPi), 1 - std::acos(clamp(d.z / l, -1.0f, 1.0f)) * kInvPi};
}
inline Vec3 equirectangular_to_direction(Vec2 uv) {
  const float phi = kPi - 2 * kPi * uv.x, theta = kPi * (1 - uv.y);
  const float s = std::sin(theta);
  return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}
// Cycles' direction_to_mirrorball: a mirror ball seen from -Y (the image of a unit direction).
inline Vec2 direction_to_mirrorball(Vec3 d) {
  d.y -= 1;
  const float div = 2 * std::sqrt(std::max(-0.5f * d.y, 0.0f));
  if (div > 0) d = d / div;
  return {0.5f * (d.x + 1), 0.5f * (d.z + 1)};
}

// Uniform direction in the cone around +Z with the given cos of the half angle.
inline Vec3 sample_uniform_cone(Vec2 u, float cos_max) {
  float cos_theta = 1 - u.x * (1 - cos_max);
  float sin_theta = safe_sqrt(1 - cos_theta * cos_theta);
  float phi = 2 * kPi * u.y;
  return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}
inline float uniform_cone_pdf(float cos_max) { return 1 / (2 * kPi * (1 - cos_max)); }

// Barycentrics (b1, b2) uniform over a triangle (Heitz 2019, "A Low-Distortion Map Between
// Triangle and Square").
inline Vec2 sample_triangle(Vec2 u) {
  float b0, b1;
  if (u.x < u.y) {
    b0 = u.x / 2;
    b1 = u.y - b0;
  } else {
    b1 = u.y / 2;
    b0 = u.x - b1;
  }
  return {b1, 1 - b0 - b1};
}

inline float power_heuristic(float pdf_a, float pdf_b) {
  if (std::isinf(pdf_a)) return 1;
  float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  return a > 0 ? a / (a + b) : 0;
}

// ---- random numbers ----------------------------------------------------------------------

inline uint32_t hash_u32(uint32_t x) {  // lowbias32 (Chris Wellons' hash prospector)
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

inline uint64_t mix_u64(uint64_t z) {  // splitmix64 finaliser
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// PCG32 (O'Neill 2014): the independent stream.
class Pcg32 {
 public:
  Pcg32() = default;
  Pcg32(uint64_t key, uint64_t stream) {
    state_ = 0;
    inc_ = (stream << 1u) | 1u;
    next_u32();
    state_ += key;
    next_u32();
  }
  uint32_t next_u32() {
    uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
  }

 private:
  uint64_t state_ = 0, inc_ = 1;
};

inline uint32_t reverse_bits(uint32_t x) {
  x = (x << 16) | (x >> 16);
  x = ((x & 0x00ff00ffu) << 8) | ((x & 0xff00ff00u) >> 8);
  x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);
  x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);
  return ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);
}

// Vegdahl's improved Laine-Karras permutation: each bit is flipped by a function of the bits
// below it, so reverse(LK(reverse(y))) is an Owen scrambling of the fixed-point value y (Burley
// 2020, "Practical Hash-based Owen Scrambling"): the scrambled points keep every elementary interval.
inline uint32_t laine_karras_permutation(uint32_t x, uint32_t seed) {
  x ^= x * 0x3d20adeaU;
  x += seed;
  x *= (seed >> 16) | 1U;
  x ^= x * 0x05526c56U;
  x ^= x * 0x53a22864U;
  return x;
}

// The second dimension of Sobol's sequence (the Pascal matrix mod 2: direction numbers
// v_0 = 2^31, v_{k+1} = v_k ^ (v_k >> 1)), taken from and returned in bit-reversed form:
// reverse(sobol_1(reverse(r))), by byte tables (the first dimension is a bit reversal).
struct Sobol1Tables {
  uint32_t t[4][256];  // t[b][k]: XOR over the bits j of k of reverse(v[31 - (8b + j)])
  constexpr Sobol1Tables() : t() {
    uint32_t v[32] = {};
    v[0] = 1u << 31;
    for (int k = 1; k < 32; ++k) v[k] = v[k - 1] ^ (v[k - 1] >> 1);
    for (int b = 0; b < 4; ++b)
      for (int k = 0; k < 256; ++k)
        for (int j = 0; j < 8; ++j)
          if (k >> j & 1) {
            uint32_t x = v[31 - (8 * b + j)], r = 0;
            for (int q = 0; q < 32; ++q) r |= ((x >> q) & 1u) << (31 - q);
            t[b][k] ^= r;
          }
  }
};
inline constexpr Sobol1Tables kSobol1{};
inline uint32_t sobol_1_reversed(uint32_t r) {
  return kSobol1.t[0][r & 255] ^ kSobol1.t[1][(r >> 8) & 255] ^ kSobol1.t[2][(r >> 16) & 255] ^ kSobol1.t[3][r >> 24];
}

inline float u32_to_unit(uint32_t x) { return std::min(kOneMinusEpsilon, float(x) * 0x1p-32f); }

// Point i of a 2D Sobol' sequence, Owen-scrambled and shuffled (Burley 2020) by the hash h, from
// i's bit reversal: the first two dimensions of Sampler's points.
inline Vec2 sobol_owen_2d(uint32_t reversed_index, uint64_t h) {
  const uint32_t r = laine_karras_permutation(reversed_index, uint32_t(h));
  const uint32_t s3 = hash_u32(uint32_t(h >> 32) ^ 0x68e31da4u);
  return {u32_to_unit(reverse_bits(laine_karras_permutation(reverse_bits(r), uint32_t(h >> 32)))),
          u32_to_unit(reverse_bits(laine_karras_permutation(sobol_1_reversed(r), s3)))};
}

// Where a sample's numbers come from (lt_sample_pattern).
enum class SamplePattern : uint8_t { SobolOwen = 0, Independent = 1 };

// A sample's random numbers. They depend only on (seed, pixel, sample index) and the order of the
// calls, so they never depend on threads, tiles or on which samples ran before.
// SobolOwen (Burley 2020, as pbrt-v4's padded Sobol sampler): each call is its own dimension; a
// call's 1D or 2D point is the Owen-scrambled Sobol point of the sample index, shuffled by a
// nested uniform scramble of the index, with scrambles hashed from (seed, pixel, call): stratified
// in every call's own dimensions over any power-of-two run of samples, padded (independent)
// across calls. Even and odd sample indices are two independently scrambled sequences, so the
// film's two halves (a pixel's even- and odd-numbered samples, core/film.h) stay independent and
// the error estimate honest. Calls past kQmcCalls draw from a PCG32 stream. Independent: one
// PCG32 stream per sample.
class Sampler {
 public:
  Sampler(uint32_t seed, uint32_t pixel, uint32_t sample_index, SamplePattern pattern = SamplePattern::Independent)
      : pattern_(pattern) {
    const uint64_t key = mix_u64((uint64_t(seed) << 32) ^ pixel);
    if (pattern == SamplePattern::Independent) {
      pcg_ = Pcg32(key, mix_u64(key ^ (uint64_t(sample_index) * 0x9e3779b97f4a7c15ULL)));
    } else {
      key_ = mix_u64(key ^ (sample_index & 1u));
      pcg_ = Pcg32(key, mix_u64(key ^ (uint64_t(sample_index) * 0x9e3779b97f4a7c15ULL) ^ 0x5851f42d4c957f2dULL));
      reversed_index_ = reverse_bits(sample_index >> 1);
    }
  }
  // With i the sample's index within its half and r = LK(reverse(i), s1), Burley's shuffled
  // index is reverse(r); its first Sobol dimension is r itself, scrambled as
  // reverse(LK(reverse(r), s2)); its second is scrambled from its bit-reversed form.
  float next_1d() {
    if (pattern_ == SamplePattern::Independent || dim_ >= kQmcCalls) return u32_to_unit(pcg_.next_u32());
    const uint64_t h = next_hash();
    const uint32_t r = laine_karras_permutation(reversed_index_, uint32_t(h));
    return u32_to_unit(reverse_bits(laine_karras_permutation(reverse_bits(r), uint32_t(h >> 32))));
  }
  Vec2 next_2d() {
    if (pattern_ == SamplePattern::Independent || dim_ >= kQmcCalls) {
      float a = next_1d();
      return {a, next_1d()};
    }
    return sobol_owen_2d(reversed_index_, next_hash());
  }
  SamplePattern pattern() const { return pattern_; }

 private:
  uint64_t next_hash() { return mix_u64(key_ ^ (uint64_t(++dim_) * 0x9e3779b97f4a7c15ULL)); }

  // Calls past this many take independent numbers: deep in a path (long walks through media,
  // many bounces) the calls of different samples no longer mean the same thing, so their
  // stratification buys nothing, and PCG32 costs a tenth of a scrambled point.
  static constexpr uint32_t kQmcCalls = 64;
  SamplePattern pattern_;
  Pcg32 pcg_;
  uint64_t key_ = 0;
  uint32_t reversed_index_ = 0, dim_ = 0;
};

}  // namespace lt
