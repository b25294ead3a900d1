#include "scene/camera.h"

namespace lt {

Camera::Camera(const CameraDesc& desc, int width, int height) : d_(desc), width_(width), height_(height) {
  // Blender's view plane (BKE_camera_params_compute_viewplane) at unit distance.
  float xasp = 1.0f, yasp = desc.pixel_aspect > 0 ? desc.pixel_aspect : 1.0f;
  float winx = float(width), winy = float(height);
  int fit = desc.sensor_fit;
  float sensor = desc.sensor_width;
  if (fit == 0)
    fit = (xasp * winx >= yasp * winy) ? 1 : 2;
  else if (fit == 2)
    sensor = desc.sensor_height;
  float ycor = yasp / xasp;
  float pixsize = desc.orthographic ? desc.ortho_scale : sensor / std::max(1e-6f, desc.focal_length);
  float viewfac = fit == 1 ? winx : ycor * winy;
  pixsize /= viewfac;
  float dx = desc.shift_x * viewfac, dy = desc.shift_y * viewfac;
  x0_ = (-0.5f * winx + dx) * pixsize;
  x1_ = (0.5f * winx + dx) * pixsize;
  y0_ = (-0.5f * ycor * winy + dy) * pixsize;
  y1_ = (0.5f * ycor * winy + dy) * pixsize;
  pixel_area_ = ((x1_ - x0_) / winx) * ((y1_ - y0_) / winy);
  origin_ = desc.xf.point(Vec3(0.0f));
  right_ = normalize(desc.xf.vector(Vec3(1, 0, 0)));
  up_ = normalize(desc.xf.vector(Vec3(0, 1, 0)));
  forward_neg_ = normalize(desc.xf.vector(Vec3(0, 0, 1)));
}

bool Camera::project(const Vec3& p, float margin, Vec2* film, Vec3* dir, float* distance) const {
  if (d_.orthographic) return false;  // a delta direction: no point connects to it
  Vec3 v = p - origin_;
  float z = -dot(v, forward_neg_);
  if (!(z > 0)) return false;
  float dist = length(v);
  // Clipping planes are perpendicular to the axis.
  if (z < d_.clip_start || z > d_.clip_end) return false;
  float px = dot(v, right_) / z, py = dot(v, up_) / z;
  film->x = (px - x0_) / (x1_ - x0_) * width_;
  film->y = (py - y0_) / (y1_ - y0_) * height_;
  if (film->x < -margin || film->x > width_ + margin || film->y < -margin || film->y > height_ + margin) return false;
  *dir = v / dist;
  *distance = dist;
  return true;
}

void Camera::differentials(float x, float y, float* dP, float* dD) const {
  const float sx = (x1_ - x0_) / width_, sy = (y1_ - y0_) / height_;  // a pixel on the view plane
  if (d_.orthographic) {
    *dP = 0.5f * (length(right_ * sx) + length(up_ * sy));
    *dD = 0;
    return;
  }
  const float px = x0_ + (x1_ - x0_) * (x / width_), py = y0_ + (y1_ - y0_) * (y / height_);
  const Vec3 d = right_ * px + up_ * py - forward_neg_, n = normalize(d);
  *dP = 0;
  *dD = 0.5f * (length(normalize(d + right_ * sx) - n) + length(normalize(d + up_ * sy) - n));
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
