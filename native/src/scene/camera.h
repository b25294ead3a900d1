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
  // Cycles' compact ray differentials there (camera_sample_perspective / _orthographic): the
  // footprint's size at the camera (dP: a pixel for orthographic, 0 for a pinhole) and its growth
  // per unit distance (dD: the angle between neighbouring pixels' rays).
  void differentials(float x, float y, float* dP, float* dD) const;
  // Distance along the camera's viewing axis (Blender's Z depth) of a world point.
  float depth(const Vec3& p) const { return -dot(p - origin_, forward_neg_); }
  Vec3 position() const { return origin_; }
  Vec3 forward() const { return -forward_neg_; }
  bool orthographic() const { return d_.orthographic; }
  int width() const { return width_; }  // the film: the full frame in pixels
  int height() const { return height_; }

  // For connecting a point to the pinhole (BDPT's t = 1): the full-frame film position (pixels,
  // y up) where the point is seen, the unit direction from the camera to it and the distance.
  // False if it is behind the camera, outside the clipping range or off the film (filter margin
  // included).
  bool project(const Vec3& p, float margin, Vec2* film, Vec3* dir, float* distance) const;
  // Solid-angle density of camera rays through the film area around `film` per unit film pixel
  // area density: a ray through film position x has solid-angle pdf = pixel_density(x) / (a cos^3),
  // with a the view-plane area of one pixel at unit distance (pbrt 3, section 16.1.1).
  float pixel_plane_area() const { return pixel_area_; }

 private:
  CameraDesc d_;
  int width_ = 1, height_ = 1;
  float x0_ = 0, x1_ = 0, y0_ = 0, y1_ = 0;  // view plane at unit distance (or ortho plane)
  float pixel_area_ = 1;
  Vec3 origin_, right_, up_, forward_neg_;  // forward_neg_: local +Z (the camera looks down -Z)
};

}  // namespace lt
