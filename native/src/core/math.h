// Small vector maths shared by the whole core. Float everywhere; film accumulation uses double.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace lt {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kInv4Pi = 0.07957747154594766788f;
constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

struct Vec3 {
  float x = 0, y = 0, z = 0;
  Vec3() = default;
  constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  explicit constexpr Vec3(float s) : x(s), y(s), z(s) {}
  float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  Vec3 operator-() const { return {-x, -y, -z}; }
  Vec3& operator+=(const Vec3& b) {
    x += b.x;
    y += b.y;
    z += b.z;
    return *this;
  }
  Vec3& operator-=(const Vec3& b) {
    x -= b.x;
    y -= b.y;
    z -= b.z;
    return *this;
  }
  Vec3& operator*=(const Vec3& b) {
    x *= b.x;
    y *= b.y;
    z *= b.z;
    return *this;
  }
  Vec3& operator*=(float s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
  Vec3& operator/=(float s) {
    float r = 1.0f / s;
    x *= r;
    y *= r;
    z *= r;
    return *this;
  }
};

inline Vec3 operator+(Vec3 a, const Vec3& b) { return a += b; }
inline Vec3 operator-(Vec3 a, const Vec3& b) { return a -= b; }
inline Vec3 operator*(Vec3 a, const Vec3& b) { return a *= b; }
inline Vec3 operator*(Vec3 a, float s) { return a *= s; }
inline Vec3 operator*(float s, Vec3 a) { return a *= s; }
inline Vec3 operator/(Vec3 a, float s) { return a /= s; }
inline Vec3 operator/(const Vec3& a, const Vec3& b) { return {a.x / b.x, a.y / b.y, a.z / b.z}; }
inline float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length_squared(const Vec3& a) { return dot(a, a); }
inline float length(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(const Vec3& a) { return a / length(a); }
inline Vec3 vmin(const Vec3& a, const Vec3& b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3 vmax(const Vec3& a, const Vec3& b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
inline Vec3 abs(const Vec3& a) { return {std::abs(a.x), std::abs(a.y), std::abs(a.z)}; }
inline float max_component(const Vec3& a) { return std::max(a.x, std::max(a.y, a.z)); }
// Largest magnitude: negative lights (Blender allows negative energy) carry negative radiance.
inline float max_abs_component(const Vec3& a) {
  return std::max(std::abs(a.x), std::max(std::abs(a.y), std::abs(a.z)));
}
inline float average(const Vec3& a) { return (a.x + a.y + a.z) * (1.0f / 3.0f); }
inline bool is_black(const Vec3& a) { return a.x == 0 && a.y == 0 && a.z == 0; }
inline bool same_vector(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
inline bool is_finite(const Vec3& a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }
inline Vec3 lerp(float t, const Vec3& a, const Vec3& b) { return a * (1 - t) + b * t; }
// Rec. 709 luminance, the weights Blender's default (linear Rec. 709) working space uses.
inline float luminance(const Vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

using Spectrum = Vec3;  // linear RGB

template <class T>
inline T clamp(T v, T lo, T hi) {
  return v < lo ? lo : (v > hi ? hi : v);
}
inline float sqr(float x) { return x * x; }
inline float safe_sqrt(float x) { return std::sqrt(std::max(0.0f, x)); }

// Orthonormal basis around n (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
// Cycles' make_orthonormals (util/math_float3.h): a fixed pair of unit vectors normal to n and each
// other (the footprint's differentials lie along them).
inline void orthonormals(const Vec3& n, Vec3* a, Vec3* b) {
  *a = n.x != n.y || n.x != n.z ? Vec3(n.z - n.y, n.x - n.z, n.y - n.x) : Vec3(n.z - n.y, n.x + n.z, -n.y - n.x);
  *a = normalize(*a);
  *b = cross(n, *a);
}

struct Frame {
  Vec3 s, t, n;
  Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
  explicit Frame(const Vec3& normal) : n(normal) {
    float sign = std::copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    s = Vec3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    t = Vec3(b, sign + n.y * n.y * a, -n.y);
  }
  // +X along the tangent's part normal to the normal (Cycles' make_orthonormals_tangent); without
  // one (a tangent along the normal) the frame above.
  Frame(const Vec3& normal, const Vec3& tangent) : Frame(normal) {
    Vec3 b = cross(normal, tangent);
    const float len = length(b);
    if (!(len > 1e-7f) || !std::isfinite(len)) return;
    t = b / len;
    s = cross(t, n);
  }
  Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

// Row-major 3x4 affine transform (Blender's matrix_world without the last row).
struct Transform {
  float m[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  Vec3 point(const Vec3& p) const {
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
  }
  Vec3 vector(const Vec3& v) const {
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
            m[8] * v.x + m[9] * v.y + m[10] * v.z};
  }
  Vec3 column(int c) const { return {m[c], m[4 + c], m[8 + c]}; }
  float determinant() const {
    return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
           m[2] * (m[4] * m[9] - m[5] * m[8]);
  }
  // Transforms a normal by the inverse transpose of the linear part (cofactor matrix; the
  // determinant's scale does not matter for a direction that is normalised afterwards).
  Vec3 normal(const Vec3& n) const {
    Vec3 c0 = cross(column(1), column(2)), c1 = cross(column(2), column(0)), c2 = cross(column(0), column(1));
    Vec3 r = c0 * n.x + c1 * n.y + c2 * n.z;
    return determinant() < 0 ? -r : r;
  }
  // Whether every entry is the identity's within tol.
  bool is_identity(float tol = 1e-6f) const {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        if (!(std::abs(m[r * 4 + c] - (r == c ? 1.0f : 0.0f)) <= tol)) return false;
    return true;
  }
  // The bounds of the box [lo, hi] mapped by this transform (its 8 corners').
  void map_box(const Vec3& lo, const Vec3& hi, Vec3* out_lo, Vec3* out_hi) const {
    *out_lo = Vec3(INFINITY);
    *out_hi = Vec3(-INFINITY);
    for (int c = 0; c < 8; ++c) {
      const Vec3 p = point(Vec3((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z));
      *out_lo = vmin(*out_lo, p);
      *out_hi = vmax(*out_hi, p);
    }
  }
};

// a after b (b is applied first).
Transform compose(const Transform& a, const Transform& b);
// Inverse of an affine transform; throws InvalidArgument if its linear part is singular.
Transform affine_inverse(const Transform& t);

struct Ray {
  Vec3 o, d;
  float tmin = 0, tmax = INFINITY;
  // Motion blur: the time in the shutter (0 to 1) of the camera sample the ray belongs to; the
  // shutter's centre in a scene without motion.
  float time = 0.5f;
  // The triangle the ray leaves (instance and primitive; -1: none), which it must not meet again,
  // and the distance within which its instance's triangles crossed from behind are not met
  // either (geometry/hit.h, leave).
  int self_instance = -1, self_primitive = -1;
  float self_tmax = 0;
};

}  // namespace lt
