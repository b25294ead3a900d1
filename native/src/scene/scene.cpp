#include "scene/scene.h"

#include "core/error.h"
#include "scene/lights/triangle.h"
#include "shading/displacement.h"

namespace lt {

Scene::Scene() = default;

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
  has_media_ = has_boundaries_ || !global_media.empty();
  committed_ = true;
  edited_ = false;
}

}  // namespace lt
