// Transform motion: an object's transforms at equally spaced times over the shutter (time 0 to 1),
// interpolated as Cycles does (util/transform.h: transform_motion_decompose and
// transform_motion_array_interpolate): translation and scale linearly, rotation by quaternion slerp
// along the shorter arc. Embree's quaternion instance motion (RTCQuaternionDecomposition) does the
// same for the BVH, so traversal and shading agree.
#pragma once

#include <vector>

#include "core/math.h"

namespace lt {

// An object's transform at one time and its normal matrix.
struct Pose {
  Transform xf;
  bool flipped = false;  // negative determinant: winding flips the geometric normal
  Vec3 normal_rows[3];   // inverse transpose of the linear part (up to scale), for normals
  static Pose of(const Transform& xf);
  Vec3 normal_to_world(const Vec3& n) const {
    return {dot(normal_rows[0], n), dot(normal_rows[1], n), dot(normal_rows[2], n)};
  }
  // The inverse of normal_to_world up to scale: the linear part's transpose.
  Vec3 normal_to_object(const Vec3& n) const {
    const float* m = xf.m;
    return {m[0] * n.x + m[4] * n.y + m[8] * n.z, m[1] * n.x + m[5] * n.y + m[9] * n.z,
            m[2] * n.x + m[6] * n.y + m[10] * n.z};
  }
};

// M = T * R * S: S upper triangular (scale on the diagonal, skew above), R the rotation of unit
// quaternion q (x, y, z imaginary, w real), T a translation. Cycles takes R from the polar
// decomposition; for transforms without shear (Blender's location, rotation and scale, any
// parent chain of uniform scales) the polar and this QR factor are the same rotation.
struct DecomposedTransform {
  float q[4] = {0, 0, 0, 1};
  Vec3 translation{0.0f};
  float scale[3] = {1, 1, 1};
  float skew[3] = {0, 0, 0};  // xy, xz, yz
  // Towards the next step (decompose_motion): the angle between the quaternions and the unit
  // quaternion perpendicular to q in their plane, so that slerp needs one sine and cosine
  // (Cycles' quat_interpolate, with the precomputation its comment suggests).
  float theta = 0;
  float q_perp[4] = {0, 0, 0, 0};
};

// Whether a transform's linear part is zero (an object scaled to nothing at a motion step).
inline bool scaled_to_nothing(const Transform& m) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (m.m[4 * r + c] != 0) return false;
  return true;
}
DecomposedTransform decompose(const Transform& m);
Transform recompose(const DecomposedTransform& d);
// The steps decomposed, each quaternion on the side of its predecessor (shortest arcs).
std::vector<DecomposedTransform> decompose_motion(const std::vector<Transform>& steps);
// The transform at time (0 .. 1, clamped) between equally spaced steps (at least 2).
Transform interpolate_motion(const std::vector<DecomposedTransform>& steps, float time);
// Motion steps that add nothing (motion blur's cost): the stride, a power of two, at which the n
// steps can be taken instead, while every step at an odd multiple of it is, by midpoint(a, k, b),
// half way between its neighbours a and b as the interpolation goes (a constant velocity).
template <class Midpoint>
int redundant_stride(int n, Midpoint midpoint) {
  int stride = 1;
  while (n >= 3 && (n - 1) % (2 * stride) == 0) {
    for (int k = stride; k < n - 1; k += 2 * stride)
      if (!midpoint(k - stride, k, k + stride)) return stride;
    stride *= 2;
  }
  return stride;
}
// The same before recomposing: the interpolated quaternion, translation, scale and skew.
DecomposedTransform interpolate_decomposed(const std::vector<DecomposedTransform>& steps, float time);
// A process-wide unique number (never 0), for per-thread caches keyed by an object's contents:
// an object's address may be reused by a later one, its number never is.
uint64_t next_motion_generation();

// The step below time and the weight of the one above it, for n equally spaced steps.
inline void motion_step(int n, float time, int* step, float* t) {
  const int max_step = n - 1;
  const float x = clamp(time, 0.0f, 1.0f) * float(max_step);
  *step = std::min(int(x), max_step - 1);
  *t = x - float(*step);
}

}  // namespace lt
