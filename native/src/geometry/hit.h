// What an intersection tells the integrator, and where a ray leaving a surface starts.
#pragma once

#include <algorithm>
#include <cmath>
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
  bool touching = false;  // the triangle touches another object's here (Geometry::touches; leave, below)
  float time = 0.5f;      // the ray's (motion blur): the shutter time the point was found at
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

// A ray leaving a triangle where it touches another object's (SurfacePoint::touching: in its
// plane and in the box where the two overlap, Geometry::find_contacts), such as a glass block's
// bottom resting on a table or the table under it, meets that object there: it starts on the
// point's own line, drawn back along it until it lies an ulp of the point's largest coordinate
// behind the triangle's plane (at most 10 ulps back along the ray), and skips the triangle
// (Geometry's query filter; Cycles' self-intersection test, intersection_skip_self, whose rays
// start on the surface). Its own object's other triangles are skipped within 4 times that
// distance where the ray passes them in the sense it leaves its own or they lie in its plane (a
// neighbour in the same plane, crossed from behind at the shared edge, and a face doubled back to
// back are not met; a concave neighbour, which faces the ray, is). Other rays, and rays off curves
// and points, start at an origin offset forwards (spawn_origin), which would step over a touching
// surface: through a resting glass block they saw the world under the floor (4 to 6 % on the
// image mean against Cycles). The filter doubled Embree's time where every ray took it, hence
// only where something touches.
inline bool leaves_triangle(const SurfacePoint& sp) { return sp.curve < 0 && sp.primitive >= 0 && sp.instance >= 0; }
inline bool meets_contact(const SurfacePoint& sp) { return sp.touching && leaves_triangle(sp); }
// How far back along d (unit) the ray starts.
inline float draw_back(const SurfacePoint& sp, const Vec3& d) {
  const float ulp =
      std::max(std::max(std::abs(sp.p.x), std::abs(sp.p.y)), std::max(std::abs(sp.p.z), 1.0f / 1024)) * 0x1p-23f;
  return ulp / std::max(std::abs(dot(d, sp.ng)), 0.1f);
}
inline Vec3 leave_origin(const SurfacePoint& sp, const Vec3& d) {
  return meets_contact(sp) ? sp.p - d * draw_back(sp, d) : spawn_origin(sp, d);
}
// What a ray from leave_origin(sp, r->d) along r->d must skip.
inline void skip_self(const SurfacePoint& sp, Ray* r) {
  const bool t = meets_contact(sp);
  r->self_instance = t ? sp.instance : -1;
  r->self_primitive = t ? sp.primitive : -1;
  r->self_tmax = t ? 4 * draw_back(sp, r->d) : 0;
}
// A ray starting at a point off any surface (in a medium): it skips nothing.
inline void start_at(const Vec3& p, Ray* r) {
  r->o = p;
  r->self_instance = r->self_primitive = -1;
  r->self_tmax = 0;
}
// Sets the origin of a ray leaving sp along r->d and what it skips.
inline void leave(const SurfacePoint& sp, Ray* r) {
  r->o = leave_origin(sp, r->d);
  skip_self(sp, r);
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
