// The scene the core renders: geometry, materials, images, lights, world and camera. Built
// through the C ABI, then committed once (BVH, light sampler) and read-only while rendering.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "geometry/geometry.h"
#include "scene/camera.h"
#include "scene/image.h"
#include "scene/lights.h"
#include "scene/material.h"

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

  void commit();
  bool committed() const { return committed_; }
  const Material& material(int id) const {
    return id >= 0 && id < int(materials.size()) ? materials[id] : default_material;
  }
  void require_editable() const;

 private:
  bool committed_ = false;
};

}  // namespace lt
