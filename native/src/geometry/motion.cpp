#include "geometry/motion.h"

#include <atomic>

namespace lt {

namespace {

// The unit quaternion of a rotation matrix given by its columns (Shoemake 1985).
void quaternion_from_columns(const Vec3& c0, const Vec3& c1, const Vec3& c2, float q[4]) {
  const float m00 = c0.x, m11 = c1.y, m22 = c2.z, trace = m00 + m11 + m22;
  if (trace > 0) {
    const float s = 0.5f / std::sqrt(trace + 1);
    q[3] = 0.25f / s;
    q[0] = (c1.z - c2.y) * s;
    q[1] = (c2.x - c0.z) * s;
    q[2] = (c0.y - c1.x) * s;
  } else if (m00 > m11 && m00 > m22) {
    const float s = 2 * std::sqrt(1 + m00 - m11 - m22);
    q[3] = (c1.z - c2.y) / s;
    q[0] = 0.25f * s;
    q[1] = (c1.x + c0.y) / s;
    q[2] = (c2.x + c0.z) / s;
  } else if (m11 > m22) {
    const float s = 2 * std::sqrt(1 + m11 - m00 - m22);
    q[3] = (c2.x - c0.z) / s;
    q[0] = (c1.x + c0.y) / s;
    q[1] = 0.25f * s;
    q[2] = (c2.y + c1.z) / s;
  } else {
    const float s = 2 * std::sqrt(1 + m22 - m00 - m11);
    q[3] = (c0.y - c1.x) / s;
    q[0] = (c2.x + c0.z) / s;
    q[1] = (c2.y + c1.z) / s;
    q[2] = 0.25f * s;
  }
  const float l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (int i = 0; i < 4; ++i) q[i] /= l;
}

// Cycles' quat_interpolate: slerp from a towards b (a.theta, a.q_perp precomputed), linear
// (normalised) when the two nearly coincide.
void slerp(const DecomposedTransform& a, const DecomposedTransform& b, float t, float out[4]) {
  if (a.theta == 0) {
    float l = 0;
    for (int i = 0; i < 4; ++i) l += sqr(out[i] = (1 - t) * a.q[i] + t * b.q[i]);
    l = std::sqrt(l);
    for (int i = 0; i < 4; ++i) out[i] /= l;
    return;
  }
  const float ct = std::cos(a.theta * t), st = std::sin(a.theta * t);
  for (int i = 0; i < 4; ++i) out[i] = a.q[i] * ct + a.q_perp[i] * st;
}

}  // namespace

uint64_t next_motion_generation() {
  static std::atomic<uint64_t> counter{0};
  return ++counter;
}

Pose Pose::of(const Transform& xf) {
  Pose p;
  p.xf = xf;
  p.flipped = xf.determinant() < 0;
  // Rows of the cofactor matrix, sign-corrected so that normals keep facing outwards.
  for (int r = 0; r < 3; ++r) {
    Vec3 e(r == 0, r == 1, r == 2);
    Vec3 row = xf.normal(e);  // column r of the normal matrix
    p.normal_rows[0][r] = row.x;
    p.normal_rows[1][r] = row.y;
    p.normal_rows[2][r] = row.z;
  }
  return p;
}

DecomposedTransform decompose(const Transform& m) {
  DecomposedTransform d;
  d.translation = Vec3(m.m[3], m.m[7], m.m[11]);
  if (scaled_to_nothing(m)) {  // no rotation of its own: decompose_motion gives it a neighbour's
    d.scale[0] = d.scale[1] = d.scale[2] = 0;
    return d;
  }
  // Gram-Schmidt on the columns: L = R S with S upper triangular.
  const Vec3 c0 = m.column(0), c1 = m.column(1), c2 = m.column(2);
  const float s00 = length(c0);
  const Vec3 r0 = c0 / s00;
  const float s01 = dot(r0, c1);
  const Vec3 u1 = c1 - r0 * s01;
  const float s11 = length(u1);
  const Vec3 r1 = u1 / s11;
  const float s02 = dot(r0, c2), s12 = dot(r1, c2);
  const Vec3 u2 = c2 - r0 * s02 - r1 * s12;
  float s22 = length(u2);
  Vec3 r2 = u2 / s22;
  // A mirroring transform: R stays a rotation, the mirror goes into S's last scale.
  if (dot(cross(r0, r1), r2) < 0) {
    r2 = -r2;
    s22 = -s22;
  }
  quaternion_from_columns(r0, r1, r2, d.q);
  d.scale[0] = s00, d.scale[1] = s11, d.scale[2] = s22;
  d.skew[0] = s01, d.skew[1] = s02, d.skew[2] = s12;
  return d;
}

Transform recompose(const DecomposedTransform& d) {
  const float x = d.q[0], y = d.q[1], z = d.q[2], w = d.q[3];
  const float r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                         {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                         {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  const float s[3][3] = {{d.scale[0], d.skew[0], d.skew[1]}, {0, d.scale[1], d.skew[2]}, {0, 0, d.scale[2]}};
  Transform m;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m.m[4 * i + j] = r[i][0] * s[0][j] + r[i][1] * s[1][j] + r[i][2] * s[2][j];
    m.m[4 * i + 3] = d.translation[i];
  }
  return m;
}

std::vector<DecomposedTransform> decompose_motion(const std::vector<Transform>& steps) {
  std::vector<DecomposedTransform> d(steps.size());
  for (size_t i = 0; i < steps.size(); ++i) d[i] = decompose(steps[i]);
  // A step scaled to nothing (an object growing from or shrinking to nothing) takes the rotation of
  // the step before it, or of the first one after it that has one, as Cycles'
  // transform_motion_decompose: its scale alone is interpolated, not a turn to an arbitrary rotation.
  for (size_t i = 0; i < steps.size(); ++i) {
    if (!scaled_to_nothing(steps[i])) continue;
    size_t from = i;
    if (i > 0) {
      from = i - 1;
    } else {
      while (from + 1 < steps.size() && scaled_to_nothing(steps[from])) ++from;
    }
    std::copy(d[from].q, d[from].q + 4, d[i].q);
  }
  for (size_t i = 0; i < steps.size(); ++i) {
    if (i > 0 &&
        d[i - 1].q[0] * d[i].q[0] + d[i - 1].q[1] * d[i].q[1] + d[i - 1].q[2] * d[i].q[2] + d[i - 1].q[3] * d[i].q[3] <
            0)
      for (float& c : d[i].q) c = -c;
  }
  // In double, and the angle by atan2 of its sine and cosine: acos of a cosine near 1 (a step's
  // small turn) and the perpendicular from nearly equal quaternions lose most of float's digits.
  for (size_t i = 0; i + 1 < d.size(); ++i) {
    const float* a = d[i].q;
    const float* b = d[i + 1].q;
    double c = 0;
    for (int k = 0; k < 4; ++k) c += double(a[k]) * double(b[k]);
    if (c > 0.9995) continue;  // linear: theta stays 0
    double perp[4], l = 0;
    for (int k = 0; k < 4; ++k) {
      perp[k] = double(b[k]) - double(a[k]) * c;
      l += perp[k] * perp[k];
    }
    l = std::sqrt(l);
    for (int k = 0; k < 4; ++k) d[i].q_perp[k] = float(perp[k] / l);
    d[i].theta = float(std::atan2(l, c));
  }
  return d;
}

Transform interpolate_motion(const std::vector<DecomposedTransform>& steps, float time) {
  return recompose(interpolate_decomposed(steps, time));
}

DecomposedTransform interpolate_decomposed(const std::vector<DecomposedTransform>& steps, float time) {
  int step;
  float t;
  motion_step(int(steps.size()), time, &step, &t);
  const DecomposedTransform &a = steps[size_t(step)], &b = steps[size_t(step) + 1];
  DecomposedTransform d;
  slerp(a, b, t, d.q);
  d.translation = lerp(t, a.translation, b.translation);
  for (int i = 0; i < 3; ++i) {
    d.scale[i] = (1 - t) * a.scale[i] + t * b.scale[i];
    d.skew[i] = (1 - t) * a.skew[i] + t * b.skew[i];
  }
  return d;
}

}  // namespace lt
