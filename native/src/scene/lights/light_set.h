// The scene's lights and the sampler that picks one for next-event estimation and light subpaths,
// by power; each call goes to the light's type (point.h, area.h, sun.h, triangle.h, world.h).
#pragma once

#include <vector>

#include "core/distribution.h"
#include "geometry/geometry.h"
#include "scene/lights/light.h"
#include "scene/lights/sun.h"
#include "scene/lights/world.h"

namespace lt {

class Scene;

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

  // Emission sampling for light subpaths, and its densities for a given origin (normal n) and
  // direction. Infinite lights emit from the scene's disk (emit_from_scene_disk).
  bool sample_emission(const Scene& scene, int light, Vec2 u_pos, Vec2 u_dir, EmissionSample* out) const;
  void pdf_emission(const Scene& scene, int light, const Vec3& origin, const Vec3& n, const Vec3& dir, float* pdf_pos,
                    float* pdf_dir) const;
  float scene_radius() const { return scene_radius_; }
  Vec3 scene_center() const { return scene_center_; }

  using LampHit = lt::LampHit;
  // Calls visit(hit) for each hittable lamp (Light::hittable) visible to this ray kind crossed
  // before tmax: lamps are not occluders.
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
      if ((l.visibility & visibility) && sun_intersect(l, d)) visit(i, sun_radiance(l, d));
    }
  }
  bool has_hittable() const { return !hittable_.empty() || !suns_.empty(); }

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
