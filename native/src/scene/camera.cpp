#include "scene/camera.h"

namespace lt {

Camera::Camera(const CameraDesc& desc, int width, int height) : d_(desc), width_(width), height_(height) {
  // Blender's view plane (BKE_camera_params_compute_viewplane) at unit distance.
  float xasp = 1.0f, yasp = desc.pixel_aspect > 0 ? desc.pixel_aspect : 1.0f;
  float winx = float(width), winy = float(height);
  int fit = desc.sensor_fit;
  float sensor = desc.sensor_width;
  if (fit == 0) fit = (xasp * winx >= yasp * winy) ? 1 : 2;
  else if (fit == 2) sensor = desc.sensor_height;
  float ycor = yasp / xasp;
  float pixsize = desc.orthographic ? desc.ortho_scale : sensor / std::max(1e-6f, desc.focal_length);
  float viewfac = fit == 1 ? winx : ycor * winy;
  pixsize /= viewfac;
  float dx = desc.shift_x * viewfac, dy = desc.shift_y * viewfac;
  x0_ = (-0.5f * winx + dx) * pixsize;
  x1_ = (0.5f * winx + dx) * pixsize;
  y0_ = (-0.5f * ycor * winy + dy) * pixsize;
  y1_ = (0.5f * ycor * winy + dy) * pixsize;
  origin_ = desc.xf.point(Vec3(0.0f));
  right_ = normalize(desc.xf.vector(Vec3(1, 0, 0)));
  up_ = normalize(desc.xf.vector(Vec3(0, 1, 0)));
  forward_neg_ = normalize(desc.xf.vector(Vec3(0, 0, 1)));
}

Ray Camera::generate(float x, float y) const {
  float px = x0_ + (x1_ - x0_) * (x / width_);
  float py = y0_ + (y1_ - y0_) * (y / height_);
  Ray r;
  if (d_.orthographic) {
    r.o = origin_ + right_ * px + up_ * py;
    r.d = -forward_neg_;
    r.tmin = d_.clip_start;
    r.tmax = d_.clip_end;
  } else {
    Vec3 local(px, py, -1.0f);
    float inv_len = 1.0f / length(local);
    r.o = origin_;
    r.d = (right_ * px + up_ * py - forward_neg_) * inv_len;
    // Clipping planes are perpendicular to the axis, as in Cycles.
    r.tmin = d_.clip_start * length(local);
    r.tmax = d_.clip_end * length(local);
  }
  return r;
}

}  // namespace lt
