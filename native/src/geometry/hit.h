// What an intersection tells the integrator, and the robust offset that starts the next ray.
#pragma once

#include <cstdint>
#include <cstring>

#include "core/math.h"
#include "core/sampling.h"

namespace lt {

struct Hit {
  float t = INFINITY;
  int instance = -1;
  int primitive = -1;
  float u = 0, v = 0;  // barycentrics of vertices 1 and 2; curves: the segment's parameter u
  float time = 0.5f;   // the ray's (motion blur)
  Vec3 p{0.0f};        // world position (ray origin + t direction): curves and points shade from it
  bool valid() const { return instance >= 0; }
};

// Everything shading needs at a surface point, in world space.
struct SurfacePoint {
  Vec3 p;
  Vec3 ng;  // geometric normal (unit), as wound by the mesh
  Vec3 ns;  // shading normal (unit), on ng's side
  Vec2 uv;
  Vec2 bary;       // barycentrics of the triangle's second and third vertices
  Vec3 po;         // object-space position
  Vec3 generated;  // po in the mesh's texture space (Cycles' Generated coordinates)
  int material = -1;
  int instance = -1, primitive = -1;
  float time = 0.5f;  // the ray's (motion blur): the shutter time the point was found at
  // Curves and points (primitive: the segment or the point): the curve (point) index, and the
  // curve's tangent dP/du in world space (zero on points and triangles).
  int curve = -1;
  Vec3 dpdu{0.0f};
};

// Offsets a ray origin off a surface along the geometric normal by an amount that scales with the
// position's magnitude (Waechter & Binder, "A Fast and Robust Method for Avoiding
// Self-Intersection", Ray Tracing Gems ch. 6).
inline Vec3 offset_ray_origin(const Vec3& p, const Vec3& n) {
  constexpr float kOrigin = 1.0f / 32.0f, kFloatScale = 1.0f / 65536.0f, kIntScale = 256.0f;
  Vec3 r;
  for (int i = 0; i < 3; ++i) {
    int32_t of = int32_t(kIntScale * n[i]);
    int32_t bits;
    float pc = p[i];
    std::memcpy(&bits, &pc, 4);
    bits += p[i] < 0 ? -of : of;
    float pi;
    std::memcpy(&pi, &bits, 4);
    r[i] = std::abs(p[i]) < kOrigin ? p[i] + kFloatScale * n[i] : pi;
  }
  return r;
}

// Origin for a ray leaving the surface towards direction d (above or below it).
inline Vec3 spawn_origin(const SurfacePoint& sp, const Vec3& d) {
  return offset_ray_origin(sp.p, dot(d, sp.ng) >= 0 ? sp.ng : -sp.ng);
}

// The shadow ray from `from` to `to`, both already offset off their surfaces, aimed at `to` itself
// and ending just short of it (pbrt-v4's SpawnRayTo). Aiming from an offset origin at the unmoved
// target tilts the ray by the offset; at grazing angles it then meets the target's surface well
// before its end (an emitter 10 cm from a ceiling lit none of it).
inline Ray spawn_ray_to(const Vec3& from, const Vec3& to, float time) {
  Ray r;
  r.time = time;
  r.o = from;
  Vec3 d = to - from;
  float dist = length(d);
  r.d = dist > 0 ? d / dist : Vec3(0.0f);
  r.tmin = 0;
  r.tmax = dist * (1 - 1e-4f);
  return r;
}

}  // namespace lt
