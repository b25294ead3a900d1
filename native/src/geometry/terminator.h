// Cycles 3.4's shadow terminator settings (Object > Shading: Geometry Offset and Shading Offset).
// Geometry: a shadow ray of next-event estimation from a smooth-shaded triangle starts on the curved
// surface its vertex normals imply rather than on the flat triangle (Hanika 2021, "Hacking the
// Shadow Terminator", Ray Tracing Gems II ch. 4; Cycles' kernel/light/sample.h, shadow_ray_offset
// and shadow_ray_smooth_surface_offset). Shading: a cosine remap of the BSDF towards the light
// (Cycles' kernel/closure/bsdf.h, shift_cos_in, from appleseed).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/math.h"

namespace lt {

// How much of the offset a shadow ray takes: 1 at and below the cutoff's grazing angles, fading
// to 0 above (Cycles' offset_amount). cutoff: Geometry Offset (> 0); nl = |dot(N, L)| with N the
// shading normal; ngl = dot(Ng, L) with Ng the geometric normal on N's side of L.
inline float terminator_offset_amount(float cutoff, float nl, float ngl) {
  const float a = nl < cutoff ? 2 - (ngl + nl) / cutoff : 1 - ngl / cutoff;
  return std::clamp(a, 0.0f, 1.0f);
}

// The offset from the point of barycentrics (b1, b2) on the triangle of corners v and unit corner
// normals n towards the surface those normals imply (a parabola, bounded by each corner's tangent
// plane), all in one space. ng: the geometric normal on the side the shadow ray leaves from; when
// it faces against the normals the offset goes the other way (Cycles' "flipped normals" case).
// The result is the interpolated (unnormalised) normal times the height, as Cycles'.
inline Vec3 smooth_surface_offset(const Vec3 v[3], const Vec3 n[3], float b1, float b2, const Vec3& ng) {
  const float u = 1 - b1 - b2, w1 = b1, w2 = b2;  // Cycles' (u, v, w): the corners' weights
  const Vec3 p = v[0] * u + v[1] * w1 + v[2] * w2;
  const Vec3 nn = n[0] * u + n[1] * w1 + n[2] * w2;
  const float a = dot(n[2] - n[0], v[0] - v[2]);
  const float b = dot(n[2] - n[1], v[1] - v[2]);
  const float c = dot(n[1] - n[0], v[1] - v[0]);
  float h = a * u * (u - 1) + (a + b + c) * u * w1 + b * w1 * (w1 - 1);
  // The linear envelope: at each corner, how far the other corners rise above its tangent plane.
  float e[3];
  const float s = dot(nn, ng) > 0 ? 1.0f : -1.0f;
  for (int i = 0; i < 3; ++i) {
    const Vec3& o1 = v[(i + 1) % 3];
    const Vec3& o2 = v[(i + 2) % 3];
    const float rise = std::max(std::max(s * dot(o1 - v[i], n[i]), s * dot(o2 - v[i], n[i])), 0.0f);
    e[i] = std::max(s * dot(v[i] - p, n[i]) + rise, 0.0f);
  }
  const float env = std::min(std::min(e[0], e[1]), e[2]);
  h = s > 0 ? std::max(env, h * 0.5f) : std::min(-env, h * 0.5f);
  return nn * h;
}

}  // namespace lt
