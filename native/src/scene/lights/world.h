// The world background as a light: colour x strength, optionally times an equirectangular image
// (Blender's Environment Texture), importance sampled by the image's luminance x sin(theta).
#pragma once

#include "core/distribution.h"
#include "scene/lights/light.h"
#include "shading/image.h"

namespace lt {

struct World {
  Spectrum color{0.0f};
  const Image* image = nullptr;
  float rotation_z = 0;
  bool camera_visible = true;
  Distribution2D distribution;  // over the image's (u, v), weighted by sin(theta)
  float image_mean = 1;         // solid-angle mean of the image's luminance (for light picking)
  Spectrum radiance(const Vec3& dir) const;
  bool black() const { return is_black(color); }
  // Builds distribution and image_mean from the image (at commit).
  void build_distribution();
};

bool world_sample(const World& w, Vec2 u, LightSample* s);
// Solid-angle density of world_sample for direction wi.
float world_pdf(const World& w, const Vec3& wi);
// The direction as world_sample picks it, the origin on the scene's disk (emit_from_scene_disk).
bool world_sample_emission(const World& w, const Vec3& center, float radius, Vec2 up, Vec2 ud, EmissionSample* e);

}  // namespace lt
