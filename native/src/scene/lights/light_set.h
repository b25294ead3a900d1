// The scene's lights and the samplers that pick one: for next-event estimation from a shading point,
// the light tree (light_tree.h) over the bounded lights beside the infinite ones (sun, world), which
// keep their share of the power; for light subpaths (no shading point), by power. Each call on a
// light goes to its type (point.h, area.h, sun.h, triangle.h, world.h).
#pragma once

#include <vector>

#include "core/distribution.h"
#include "geometry/geometry.h"
#include "scene/lights/light.h"
#include "scene/lights/light_tree.h"
#include "scene/lights/sun.h"
#include "scene/lights/world.h"

namespace lt {

class Scene;

// How next-event estimation picks a light. Power: as light subpaths do (the selection before the
// tree, kept for tests and benchmarks: LightSet::set_selection, or LANTERN_LIGHT_SELECTION=power
// in the environment when the scene is committed).
enum class LightSelection { Tree, Power };

class LightSet {
 public:
  // bounds: everything light can scatter from (geometry and Volume objects); infinite lights emit
  // from a disk over its bounding sphere. geometry: the emissive triangles' corners.
  void build(std::vector<Light> lights, const World* world, const Bounds& bounds, const Geometry* geometry);
  // For the next build.
  void set_selection(LightSelection s) { selection_ = s; }
  LightSelection selection() const { return tree_used_ ? LightSelection::Tree : LightSelection::Power; }
  const LightTree& tree() const { return tree_; }
  size_t size() const { return lights_.size(); }
  const Light& light(int i) const { return lights_[i]; }
  bool empty() const { return lights_.empty(); }
  // Whether pick and pick_nee can return a light: false without lights, or with only lights of no
  // power (a constant World alone). Integrators then skip next-event estimation and light
  // subpaths, which could not find a light, and draw no numbers for them.
  bool pickable() const { return distribution_.integral() > 0; }

  // Picks a light with probability proportional to its estimated power (light subpaths); -1 if
  // none has any (a constant World is never picked: LightSet::build).
  int pick(float u, float* pmf, float* u_remapped) const;
  float pmf(int light) const { return distribution_.integral() > 0 ? distribution_.discrete_pmf(light) : 0.0f; }
  // Picks a light for next-event estimation at p (n: the geometric normal at a surface, either
  // side, or zero in a medium): -1 if none can reach p. pmf_nee is exactly the probability it
  // picks `light` there (for MIS against the BSDF or phase function, and BDPT's weights).
  int pick_nee(const Vec3& p, const Vec3& n, float u, float* pmf) const;
  float pmf_nee(const Vec3& p, const Vec3& n, int light) const;
  // Index of the light of an emissive triangle, or -1.
  int triangle_light(int instance, int primitive) const;
  int world_light() const { return world_light_; }
  int lightgroup(int light) const { return light >= 0 ? lights_[light].lightgroup : -1; }

  // time: the sample's shutter time (motion blur: emissive triangles move; lamps do not, as in
  // Cycles 3.4).
  bool sample(const Scene& scene, int light, const Vec3& p, Vec2 u, LightSample* out, float time = 0.5f) const;
  // Solid-angle pdf that sample() picks direction wi from p for this light (selection excluded);
  // for area-like lights the point at distance t along wi.
  float pdf(const Scene& scene, int light, const Vec3& p, const Vec3& wi, float t, float time = 0.5f) const;
  // Next-event estimation's area density for the point q of a finite light seen from p, over the
  // light subpaths' (uniform by area): 1 but for rectangles and triangles, which it may sample by
  // solid angle (BDPT's MIS weighs strategy s = 1 with it).
  float nee_position_ratio(const Scene& scene, int light, const Vec3& p, const Vec3& q, float time = 0.5f) const;

  // Emission sampling for light subpaths, and its densities for a given origin (normal n) and
  // direction. Infinite lights emit from the scene's disk (emit_from_scene_disk).
  bool sample_emission(const Scene& scene, int light, Vec2 u_pos, Vec2 u_dir, EmissionSample* out,
                       float time = 0.5f) const;
  void pdf_emission(const Scene& scene, int light, const Vec3& origin, const Vec3& n, const Vec3& dir, float* pdf_pos,
                    float* pdf_dir, float time = 0.5f) const;
  float scene_radius() const { return scene_radius_; }
  Vec3 scene_center() const { return scene_center_; }

  using LampHit = lt::LampHit;
  // Calls visit(hit) for each hittable lamp (Light::hittable) visible to this ray kind crossed
  // before tmax: lamps are not occluders. from: the path's last scattering, which a point lamp's
  // disk faces (the ray may start further along the same line, past invisible boundaries).
  template <class F>
  void intersect_lamps(const Ray& ray, const Vec3& from, unsigned visibility, F visit) const {
    for (int i : hittable_) {
      LampHit h;
      if ((lights_[i].visibility & visibility) && intersect_lamp(i, ray, from, &h)) visit(h);
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
  bool intersect_lamp(int i, const Ray& ray, const Vec3& from, LampHit* hit) const;
  std::vector<Light> lights_;
  std::vector<int> hittable_, suns_;
  std::vector<std::pair<uint64_t, int>> triangle_index_;  // sorted (instance<<32 | prim) -> light
  Distribution1D distribution_;
  LightSelection selection_ = LightSelection::Tree;
  bool tree_used_ = false;
  LightTree tree_;           // over the bounded lights of non-zero power
  float tree_share_ = 0;     // the power share of the tree's lights: its probability
  Distribution1D infinite_;  // the infinite lights by power, for the rest
  std::vector<int> infinite_lights_;
  std::vector<int> infinite_slot_;  // light -> its bin of infinite_, or -1
  int world_light_ = -1;
  float scene_radius_ = 1;
  Vec3 scene_center_;
};

}  // namespace lt
