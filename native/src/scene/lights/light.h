// A light of any type, with Cycles 3.4's units and shapes, and what sampling one returns. Each type
// keeps its Blender conversion, radiance factor, sampling, densities, emission and intersection in
// one header, as Cycles' kernel/light/ does: point.h (point and spot lamps), area.h, sun.h,
// triangle.h (emissive triangles), world.h; light_set.h picks among them.
#pragma once

#include <cmath>

#include "core/math.h"
#include "core/sampling.h"
#include "geometry/hit.h"

namespace lt {

enum class LightType { Point, Spot, Area, Sun, Triangle, World };
enum class AreaShape { Rectangle, Ellipse };

struct Light {
  LightType type = LightType::Point;
  Spectrum power{0.0f};      // Blender's colour x energy (W; W/m^2 for the sun)
  Vec3 position, direction;  // direction: the way light travels (spot axis, sun, area normal side)
  // Point / spot: disk radius (Cycles 3.4 samples a disk facing the shaded point).
  float radius = 0;
  // Spot: cos of the half angle and the smoothstep width.
  float cos_half_angle = 0, smooth = 0;
  // Area: the two half axes (with scale) and the shape.
  Vec3 axis_u, axis_v;
  AreaShape shape = AreaShape::Rectangle;
  float area = 0;
  // Area: Cycles 3.4's spread (a soft box's slats): emission times max(0, (1 - tan_spread tan a)
  // normalize_spread) at angle a off the normal; tan_spread 0: none (area.h).
  float tan_spread = 0, normalize_spread = 1;
  // Sun: tan of the half angle (0: a delta direction).
  float tan_half_angle = 0, cos_half_angle_sun = 1;
  // Triangle emitters: the instance and primitive, and the material's radiance when constant.
  int instance = -1, primitive = -1;
  bool constant_emission = false;
  Spectrum emitted{0.0f};
  unsigned visibility = 31;
  int lightgroup = -1;  // the view layer's light group it belongs to (-1: none)
  // Cycles 3.4 draws a point or spot light with a radius as a disk facing whatever it lights: its
  // emission depends on the receiver, so no light subpath can start on it (BDPT reaches it only by
  // the strategies s = 0 and s = 1, which see it from the receiver).
  bool faces_receiver() const { return point_like() && radius > 0; }
  bool delta() const { return (point_like() && !faces_receiver()) || (type == LightType::Sun && tan_half_angle == 0); }
  bool infinite() const { return type == LightType::Sun || type == LightType::World; }
  // Rays can cross it (area lamps, point and spot lamps with a radius); lamps never occlude.
  bool hittable() const { return type == LightType::Area || faces_receiver(); }

 private:
  bool point_like() const { return type == LightType::Point || type == LightType::Spot; }
};

// A Blender lamp's fields common to every type: colour x energy, its origin and its -Z axis.
inline Light blender_lamp(LightType type, const Spectrum& power, const Transform& xf) {
  Light l;
  l.type = type;
  l.power = power;
  l.position = xf.point(Vec3(0.0f));
  l.direction = normalize(xf.vector(Vec3(0, 0, -1)));
  return l;
}

struct LightSample {
  Vec3 wi;             // from the shaded point towards the light
  float distance = 0;  // INFINITY for sun and world
  // The point on the light and its normal: a surface's (area lamp, emissive triangle), -wi on the
  // disk of a lamp with a radius (it faces the receiver; Cycles' Ng = -D), zero for points and
  // infinite lights.
  Vec3 p, n;
  bool on_surface = false;  // p lies on a surface with a side (area lamp, triangle): shadow rays stop off it
  Spectrum radiance;        // emitted radiance arriving along -wi (spot falloff included)
  float pdf = 0;            // solid angle pdf of this light's sampling (not including selection)
  bool delta = false;
};

// Aims a sample from the shaded point p at the light point q: wi, distance, p; d2 the squared
// distance. False where the two coincide.
inline bool aim_at(const Vec3& p, const Vec3& q, LightSample* s, float* d2) {
  Vec3 to = q - p;
  *d2 = length_squared(to);
  if (!(*d2 > 0)) return false;
  s->distance = std::sqrt(*d2);
  s->wi = to / s->distance;
  s->p = q;
  return true;
}

// A light sampled as the start of a light subpath (BDPT): a point and a direction of emission.
struct EmissionSample {
  Ray ray;
  Vec3 n;             // normal at the origin (zero for points); for infinite lights: ray.d
  Spectrum radiance;  // Le(origin, ray.d); intensity for point lights, irradiance for delta suns
  float pdf_pos = 0;  // area density of the origin (1 for delta positions)
  float pdf_dir = 0;  // solid-angle density of the direction (1 for delta directions)
  bool delta_pos = false, delta_dir = false;
};

// A hittable lamp crossed by a ray: distance, normal at the crossing (the area lamp's; -ray.d on
// a disk facing the path's last scattering) and radiance towards the ray origin.
struct LampHit {
  int light = -1;
  float t = INFINITY;
  Vec3 n;
  Spectrum radiance;
};

// The shadow ray from `origin` (already offset off its surface) to a sampled light: to infinity for
// sun and world, else to the light point (at the sample's time), moved off an emissive surface towards the origin.
inline Ray shadow_ray(const Vec3& origin, const LightSample& ls, float time) {
  if (std::isinf(ls.distance)) {
    Ray r;
    r.o = origin;
    r.d = ls.wi;
    r.time = time;
    return r;
  }
  return spawn_ray_to(
      origin, ls.on_surface ? offset_ray_origin(ls.p, dot(ls.n, origin - ls.p) >= 0 ? ls.n : -ls.n) : ls.p, time);
}

// Infinite lights (sun, world) emit from a disk perpendicular to the direction over the scene's
// bounding sphere (pbrt 3, section 12.6): its area density.
inline float scene_disk_pdf(float radius) { return 1 / (kPi * radius * radius); }
inline void emit_from_scene_disk(const Vec3& dir, const Vec3& center, float radius, Vec2 u, EmissionSample* e) {
  Frame f(dir);
  Vec2 d = sample_disk_concentric(u);
  e->ray.o = center + (f.to_world(Vec3(d.x, d.y, 0)) - dir) * radius;
  e->ray.d = dir;
  e->n = dir;
  e->pdf_pos = scene_disk_pdf(radius);
}

}  // namespace lt
