#include "scene/scene.h"

#include <algorithm>

#include "core/error.h"
#include "scene/lights/triangle.h"
#include "shading/displacement.h"

namespace lt {

Scene::Scene() = default;

bool Scene::may_be_inside_boundary(const Vec3& p) const {
  if (boundaries_anywhere_) return true;
  for (const Bounds& b : boundary_bounds_)
    if (p.x >= b.lo.x && p.y >= b.lo.y && p.z >= b.lo.z && p.x <= b.hi.x && p.y <= b.hi.y && p.z <= b.hi.z) return true;
  return !is_finite(p);  // (a ray that cannot be placed: traced as before)
}

void Scene::require_editable() const {
  if (committed_) throw StateError("the scene is committed and can no longer be edited");
}

void Scene::commit() {
  if (committed_ && !edited_) return;
  if (!committed_) displace_meshes(geometry, materials, images);  // before the meshes' BVHs
  geometry.commit();
  has_transparent_shadows_ = false;
  for (size_t m = 0; m < materials.size(); ++m)
    has_transparent_shadows_ |= !null_surface(int(m)) && materials[m].may_be_transparent();
  std::vector<Light> all = lamp_lights;
  emissive_triangles_ = emissive_instances_ = 0;
  // Every triangle of an emissive material becomes a light (Cycles' mesh lights).
  for (size_t i = 0; i < geometry.instance_count(); ++i) {
    const size_t before = all.size();
    const Instance& inst = geometry.instance(int(i));
    const Mesh& m = geometry.mesh(inst.mesh);
    if (!m.rtc) continue;
    if (!std::isfinite(inst.xf.determinant())) continue;  // left out of the geometry
    for (size_t t = 0; t < m.triangle_count(); ++t) {
      const Material& mat = material(inst.material_for(m.slots.empty() ? 0 : m.slots[t]));
      if (!mat.emissive()) continue;
      Light l;
      if (triangle_light(geometry, int(i), int(t), mat, &l)) all.push_back(l);
    }
    emissive_triangles_ += all.size() - before;
    emissive_instances_ += all.size() > before;
  }
  if (world_set) world.build(images);
  if (world_set && !world.black()) {
    Light w;
    w.type = LightType::World;
    w.lightgroup = world.lightgroup;
    all.push_back(w);
  }
  // Bounded global media are Volume objects, unbounded ones World volumes.
  Bounds bounds = geometry.bounds();
  has_world_volume_ = false;
  for (int m : global_media) {
    Vec3 lo, hi;
    if (media[m].bounds(&lo, &hi)) {
      bounds.extend(lo);
      bounds.extend(hi);
    } else {
      // A World volume that only emits (sigma_t = 0) hides nothing.
      has_world_volume_ = has_world_volume_ || !media[m].empty();
    }
  }
  // Rays from beyond Embree's range miss (geometry.h): say so instead of rendering less silently.
  bool beyond = !bounds.empty() && !(within_traceable_range(bounds.lo) && within_traceable_range(bounds.hi));
  for (const Light& l : lamp_lights)
    beyond = beyond || (l.type != LightType::Sun && !within_traceable_range(l.position));
  if (beyond)
    warnings.push_back(
        "the scene reaches beyond 1.8e18 from the origin, the range within which rays can be traced "
        "(Embree's); rays from beyond it miss");
  lights.build(std::move(all), world_set ? &world : nullptr, bounds, &geometry);
  ++light_builds_;
  material_medium.resize(materials.size(), -1);
  material_null.resize(materials.size(), 0);
  has_boundaries_ = false;
  has_emissive_media_ = false;
  for (int m : material_medium) {
    has_boundaries_ = has_boundaries_ || m >= 0;
    has_emissive_media_ = has_emissive_media_ || (m >= 0 && media[m].emissive());
  }
  for (int m : global_media) has_emissive_media_ = has_emissive_media_ || media[m].emissive();
  boundary_bounds_.clear();
  boundaries_anywhere_ = false;
  for (size_t i = 0; has_boundaries_ && i < geometry.instance_count(); ++i) {
    const Instance& inst = geometry.instance(int(i));
    const Mesh& m = geometry.mesh(inst.mesh);
    const bool medium =
        std::any_of(inst.materials.begin(), inst.materials.end(), [&](int mat) { return medium_of(mat) >= 0; });
    if (!medium || !m.rtc) continue;
    if (!inst.motion.empty() || m.motion_steps > 1 || !m.is_triangles()) {
      boundaries_anywhere_ = true;
      continue;
    }
    Bounds b;
    for (const Vec3& p : m.positions) b.extend(inst.xf.point(p));
    if (b.empty()) continue;
    // Grown by a margin well beyond the rounding of the transform and of the rays' offsets.
    const Vec3 pad = (b.hi - b.lo) * 1e-3f + Vec3(1e-3f * (1.0f + max_abs_component(vmax(abs(b.lo), abs(b.hi)))));
    b.lo = b.lo - pad;
    b.hi = b.hi + pad;
    boundary_bounds_.push_back(b);
  }
  has_media_ = has_boundaries_ || !global_media.empty();
  committed_ = true;
  edited_ = false;
}

}  // namespace lt
