// Lights with Cycles 3.4's units and shapes, and the sampler that picks one for next-event
// estimation. Emissive triangles and the world are lights too. Every conversion factor from
// Blender's numbers to radiance lives in lights.cpp.
#pragma once

#include <memory>
#include <vector>

#include "core/distribution.h"
#include "core/math.h"
#include "geometry/geometry.h"
#include "scene/image.h"

namespace lt {

enum class LightType { Point, Spot, Area, Sun, Triangle, World };
enum class AreaShape { Rectangle, Ellipse };

struct Light {
  LightType type = LightType::Point;
  Spectrum power{0.0f};  // Blender's colour x energy (W; W/m^2 for the sun)
  Vec3 position, direction;  // direction: the way light travels (spot axis, sun, area normal side)
  // Point / spot: disk radius (Cycles 3.4 samples a disk facing the shaded point).
  float radius = 0;
  // Spot: cos of the half angle and the smoothstep width.
  float cos_half_angle = 0, smooth = 0;
  // Area: the two half axes (with scale) and the shape.
  Vec3 axis_u, axis_v;
  AreaShape shape = AreaShape::Rectangle;
  float area = 0;
  // Sun: tan of the half angle (0: a delta direction).
  float tan_half_angle = 0, cos_half_angle_sun = 1;
  // Triangle emitters: the instance and primitive.
  int instance = -1, primitive = -1;
  unsigned visibility = 31;
  bool delta() const {
    return ((type == LightType::Point || type == LightType::Spot) && radius == 0) ||
           (type == LightType::Sun && tan_half_angle == 0);
  }
  bool infinite() const { return type == LightType::Sun || type == LightType::World; }
  // Cycles 3.4 draws a point or spot light with a radius as a disk facing whatever it lights: its
  // emission depends on the receiver, so no light subpath can start on it (BDPT reaches it only by
  // the strategies s = 0 and s = 1, which see it from the receiver).
  bool faces_receiver() const { return (type == LightType::Point || type == LightType::Spot) && radius > 0; }
};

// World background: colour x strength, optionally times an equirectangular image.
struct World {
  Spectrum color{0.0f};
  const Image* image = nullptr;
  float rotation_z = 0;
  bool camera_visible = true;
  Distribution2D distribution;  // over the image's (u, v), weighted by sin(theta)
  float image_mean = 1;         // solid-angle mean of the image's luminance (for light picking)
  Spectrum radiance(const Vec3& dir) const;
  bool black() const { return is_black(color); }
};

struct LightSample {
  Vec3 wi;             // from the shaded point towards the light
  float distance = 0;  // INFINITY for sun and world
  Vec3 p, n;           // the point on the light and, on a surface (area lamp, emissive triangle), its normal
  Spectrum radiance;   // emitted radiance arriving along -wi (spot falloff included)
  float pdf = 0;       // solid angle pdf of this light's sampling (not including selection)
  bool delta = false;
};

// A light sampled as the start of a light subpath (BDPT): a point and a direction of emission.
struct EmissionSample {
  Ray ray;
  Vec3 n;                // normal at the origin (zero for points); for infinite lights: -ray.d
  Spectrum radiance;     // Le(origin, ray.d); intensity for point lights, irradiance for delta suns
  float pdf_pos = 0;     // area density of the origin (1 for delta positions)
  float pdf_dir = 0;     // solid-angle density of the direction (1 for delta directions)
  bool delta_pos = false, delta_dir = false;
};

class Scene;

// The shadow ray from `origin` (already offset off its surface) to a sampled light: to infinity for
// sun and world, else to the light point, moved off an emissive surface towards the origin.
inline Ray shadow_ray(const Vec3& origin, const LightSample& ls) {
  if (std::isinf(ls.distance)) {
    Ray r;
    r.o = origin;
    r.d = ls.wi;
    return r;
  }
  const bool surface = ls.n.x != 0 || ls.n.y != 0 || ls.n.z != 0;
  return spawn_ray_to(origin, surface ? offset_ray_origin(ls.p, dot(ls.n, origin - ls.p) >= 0 ? ls.n : -ls.n) : ls.p);
}

class LightSet {
 public:
  // bounds: everything light can scatter from (geometry and Volume objects); infinite lights emit
  // from a disk over its bounding sphere.
  void build(std::vector<Light> lights, const World* world, const Bounds& bounds);
  size_t size() const { return lights_.size(); }
  const Light& light(int i) const { return lights_[i]; }
  bool empty() const { return lights_.empty(); }

  // Picks a light with probability proportional to its estimated power.
  int pick(float u, float* pmf, float* u_remapped) const;
  float pmf(int light) const { return distribution_.discrete_pmf(light); }
  // Index of the light of an emissive triangle, or -1.
  int triangle_light(int instance, int primitive) const;
  int world_light() const { return world_light_; }

  bool sample(const Scene& scene, int light, const Vec3& p, Vec2 u, LightSample* out) const;
  // Solid-angle pdf that sample() picks direction wi from p for this light (selection excluded);
  // for area-like lights the point at distance t along wi.
  float pdf(const Scene& scene, int light, const Vec3& p, const Vec3& wi, float t) const;

  // Emission sampling for light subpaths, and its densities for a given origin and direction.
  // Infinite lights (sun, world) emit from a disk perpendicular to the direction over the scene's
  // bounding sphere (pbrt 3, section 12.6), so pdf_pos is 1 / (pi r^2).
  bool sample_emission(const Scene& scene, int light, Vec2 u_pos, Vec2 u_dir, EmissionSample* out) const;
  void pdf_emission(const Scene& scene, int light, const Vec3& origin, const Vec3& n, const Vec3& dir,
                    float* pdf_pos, float* pdf_dir) const;
  // Radiance a light emits from `origin` towards `dir` (spot falloff, one-sidedness).
  Spectrum emitted(const Scene& scene, int light, const Vec3& origin, const Vec3& n, const Vec3& dir) const;
  float scene_radius() const { return scene_radius_; }
  Vec3 scene_center() const { return scene_center_; }

  // Lights that rays can hit (area lights, point and spot lights with a radius): the closest hit
  // at distance < tmax is reported with its radiance towards the ray origin. Lamps do not occlude.
  struct LampHit {
    int light = -1;
    float t = INFINITY;
    Spectrum radiance;
  };
  // Calls visit(hit) for each hittable lamp visible to this ray kind crossed before tmax (lamps
  // are not occluders).
  template <class F>
  void intersect_lamps(const Ray& ray, unsigned visibility, F visit) const {
    for (int i : hittable_) {
      LampHit h;
      if ((lights_[i].visibility & visibility) && intersect_lamp(i, ray, &h)) visit(h);
    }
  }
  // Sun lights with an angle: radiance arriving along the escaped direction d.
  template <class F>
  void escaped_suns(const Vec3& d, unsigned visibility, F visit) const {
    for (int i : suns_) {
      const Light& l = lights_[i];
      if ((l.visibility & visibility) && dot(d, -l.direction) > l.cos_half_angle_sun) visit(i, sun_radiance(l));
    }
  }
  bool has_hittable() const { return !hittable_.empty() || !suns_.empty(); }
  Spectrum sun_radiance(const Light& l) const;

 private:
  bool intersect_lamp(int i, const Ray& ray, LampHit* hit) const;
  std::vector<Light> lights_;
  std::vector<int> hittable_, suns_;
  std::vector<std::pair<uint64_t, int>> triangle_index_;  // sorted (instance<<32 | prim) -> light
  Distribution1D distribution_;
  int world_light_ = -1;
  float scene_radius_ = 1;
  Vec3 scene_center_;
};

}  // namespace lt
