// Blender's camera model: sensor fit, focal length, shift, orthographic scale and clipping planes
// (BKE_camera_params_compute_viewplane), looking down local -Z with +Y up.
#pragma once

#include "core/math.h"
#include "core/sampling.h"

namespace lt {

struct CameraDesc {
  bool orthographic = false;
  Transform xf;
  float focal_length = 50, sensor_width = 36, sensor_height = 24;
  int sensor_fit = 0;  // 0 auto, 1 horizontal, 2 vertical
  float ortho_scale = 7.3f;
  float shift_x = 0, shift_y = 0;
  float clip_start = 0.1f, clip_end = 1000;
  float pixel_aspect = 1;
};

class Camera {
 public:
  Camera() = default;
  Camera(const CameraDesc& desc, int width, int height);
  // Ray through the film position (x, y) in pixels of the full frame, y up from the bottom.
  Ray generate(float x, float y) const;
  // Distance along the camera's viewing axis (Blender's Z depth) of a world point.
  float depth(const Vec3& p) const { return -dot(p - origin_, forward_neg_); }
  Vec3 position() const { return origin_; }

 private:
  CameraDesc d_;
  int width_ = 1, height_ = 1;
  float x0_ = 0, x1_ = 0, y0_ = 0, y1_ = 0;  // view plane at unit distance (or ortho plane)
  Vec3 origin_, right_, up_, forward_neg_;  // forward_neg_: local +Z (the camera looks down -Z)
};

}  // namespace lt
