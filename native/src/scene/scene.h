// The scene the core renders: geometry, materials, images, lights, world and camera. Built
// through the C ABI, then committed once (BVH, light sampler) and read-only while rendering.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "geometry/geometry.h"
#include "media/medium.h"
#include "scene/camera.h"
#include "scene/lights/light_set.h"
#include "shading/image.h"
#include "shading/material.h"

namespace lt {

class Scene {
 public:
  Scene();
  Geometry geometry;
  std::vector<std::unique_ptr<Image>> images;
  std::vector<Material> materials;
  Material default_material = Material::default_surface();
  std::vector<Light> lamp_lights;  // from Blender light objects
  World world;
  bool world_set = false;
  CameraDesc camera;
  bool camera_set = false;
  LightSet lights;
  std::vector<std::string> warnings;

  // Participating media (docs/volumes.md). material_medium[m]: the medium inside closed meshes of
  // material m (-1: none); material_null[m]: m has no surface, its boundary is invisible.
  // global_media: media active along every ray: Volume objects (bounded by their own grid) and
  // World volumes (homogeneous, unbounded: escaping rays cross an infinite distance).
  std::vector<Medium> media;
  std::vector<int> material_medium, global_media;
  std::vector<uint8_t> material_null;
  // medium_groups[m]: the light group of global medium m's emission (a Volume object's; -1 none).
  std::vector<int> medium_groups;
  int medium_lightgroup(int m) const { return m >= 0 && m < int(medium_groups.size()) ? medium_groups[m] : -1; }
  int medium_of(int material) const {
    return material >= 0 && material < int(material_medium.size()) ? material_medium[material] : -1;
  }
  bool null_surface(int material) const {
    return material >= 0 && material < int(material_null.size()) && material_null[material];
  }
  // Set by commit(): the scene has media at all, and mesh boundaries of media.
  bool has_media() const { return has_media_; }
  bool has_boundaries() const { return has_boundaries_; }
  // Whether p may lie inside an object with a medium (within the world bounds of one that does not
  // move, or anywhere when one moves or is not a mesh): elsewhere a ray starting at p starts in no
  // such medium, and init_volume_stack traces nothing (Cycles 3.4 likewise initialises the stack
  // only when the camera may be inside a volume object's bounds: Camera::device_update_volume).
  bool may_be_inside_boundary(const Vec3& p) const;
  // A medium emits (a material's, a Volume object's or a World volume; integrators add the emission
  // along segments in media).
  bool has_emissive_media() const { return has_emissive_media_; }
  // A World volume: escaping rays cross it to infinity, so no light arrives from the world or suns.
  bool has_world_volume() const { return has_world_volume_; }
  // Some material may be transparent to shadow rays (Material::may_be_transparent): shadow rays then
  // find surfaces one by one instead of asking Embree for any hit.
  bool has_transparent_shadows() const { return has_transparent_shadows_; }

  // First call: builds the BVHs and the light sampler. After edits that are allowed on a committed
  // scene (mark_edited: instance transforms, materials, lamps, world, camera), a later call
  // rebuilds the top-level BVH only if an instance moved, then the light sampler; never a mesh BVH.
  void commit();
  bool committed() const { return committed_; }
  void mark_edited() { edited_ = true; }
  bool edited() const { return edited_; }
  uint64_t light_builds() const { return light_builds_; }
  // Mesh lights found by the last commit.
  uint64_t emissive_triangles() const { return emissive_triangles_; }
  uint64_t emissive_instances() const { return emissive_instances_; }
  // The ray kinds that see light li: an emissive triangle's object's, a lamp's own.
  unsigned light_visibility(int li) const {
    const Light& l = lights.light(li);
    return l.type == LightType::Triangle ? geometry.instance_visibility(l.instance) : l.visibility;
  }
  const Material& material(int id) const {
    return id >= 0 && id < int(materials.size()) ? materials[id] : default_material;
  }
  void require_editable() const;

 private:
  bool committed_ = false, edited_ = false;
  uint64_t light_builds_ = 0;
  uint64_t emissive_triangles_ = 0, emissive_instances_ = 0;
  bool has_media_ = false, has_boundaries_ = false, has_world_volume_ = false, has_emissive_media_ = false;
  bool has_transparent_shadows_ = false;
  std::vector<Bounds> boundary_bounds_;
  bool boundaries_anywhere_ = false;
};

}  // namespace lt
