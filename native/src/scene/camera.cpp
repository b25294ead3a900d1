#include "scene/camera.h"

namespace lt {

namespace {
bool is_zero(const Vec3& v) { return v.x == 0 && v.y == 0 && v.z == 0; }
}  // namespace

float aperture_radius_from_fstop(bool orthographic, float focal_length_mm, float fstop) {
  fstop = std::max(fstop, 1e-5f);
  return orthographic ? 1 / (2 * fstop) : focal_length_mm * 1e-3f / (2 * fstop);
}

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
  if (desc.panorama) {
    // Cycles' panorama view plane is [0, 1]^2 shifted by the camera's shift (blender/camera.cpp).
    x0_ = desc.shift_x, x1_ = 1 + desc.shift_x, y0_ = desc.shift_y, y1_ = 1 + desc.shift_y;
    // The equisolid fisheye's sensor, fitted to the frame as Cycles does: note its automatic fit
    // is horizontal only for a strictly wider frame.
    const float xr = winx, yr = winy * yasp;
    const bool horizontal = desc.sensor_fit == 1 || (desc.sensor_fit == 0 && xr > yr);
    const float size = desc.sensor_fit == 2 ? desc.sensor_height : desc.sensor_width;
    fisheye_w_ = horizontal ? size : size * xr / yr;
    fisheye_h_ = horizontal ? size * yr / xr : size;
  }
  centre_ = basis_of(desc.xf);
  if (desc.motion.size() >= 2) motion_ = decompose_motion(desc.motion);
  generation_ = next_motion_generation();
  d_.motion.clear();  // the decomposed steps are kept
}

// BDPT asks for the camera at its sample's time for every connection and MIS weight: the last
// basis is kept per thread (a pure function of its key, so renders stay deterministic).
Camera::Basis Camera::moving_basis(float time) const {
  thread_local struct {
    uint64_t generation = 0;
    float time = -1;
    Basis basis;
  } last;
  if (last.generation != generation_ || last.time != time) {
    last.basis = basis_of(interpolate_motion(motion_, time));
    last.generation = generation_;
    last.time = time;
  }
  return last.basis;
}

Camera::Basis Camera::basis_of(const Transform& xf) {
  return {xf.point(Vec3(0.0f)), normalize(xf.vector(Vec3(1, 0, 0))), normalize(xf.vector(Vec3(0, 1, 0))),
          normalize(xf.vector(Vec3(0, 0, 1)))};
}

// Uniform over the aperture: the disk by Shirley and Chiu's concentric map, or a regular polygon
// of `blades` corners (circumradius 1, corners at rotation + (2k + 1) pi / blades, as Cycles'
// regular_polygon_sample) as one of its triangles (centre and two corners) picked uniformly,
// then uniform in it; x divided by the anamorphic ratio.
Vec2 Camera::aperture_offset(Vec2 u) const {
  Vec2 p;
  if (d_.aperture_blades >= 3) {
    const float n = float(d_.aperture_blades);
    const float k = std::min(std::floor(u.x * n), n - 1);
    const float ux = u.x * n - k;  // reused: uniform in [0, 1) again
    // Barycentrics of the two corners in the triangle (centre, c0, c1) (Turk's square root map).
    const float s = std::sqrt(ux), b0 = 1 - s, b1 = u.y * s;
    const float a = kPi / n, mid = d_.aperture_rotation + 2 * a * k;
    // Corners at mid - a and mid + a.
    const float lx = (b0 + b1) * std::cos(a), ly = (b1 - b0) * std::sin(a);
    const float c = std::cos(mid), sn = std::sin(mid);
    p = {c * lx - sn * ly, sn * lx + c * ly};
  } else {
    p = sample_disk_concentric(u);
  }
  const float r = d_.aperture_radius;
  return {p.x * r / d_.aperture_ratio, p.y * r};
}

float Camera::lens_area() const {
  if (!has_lens()) return 0;
  const float r = d_.aperture_radius;
  const float shape =
      d_.aperture_blades >= 3 ? 0.5f * float(d_.aperture_blades) * std::sin(2 * kPi / d_.aperture_blades) : kPi;
  return shape * r * r / d_.aperture_ratio;
}

Vec3 Camera::lens_point(Vec2 u, float time) const {
  const Basis b = basis(time);
  if (!has_lens()) return b.origin;
  const Vec2 l = aperture_offset(u);
  return b.origin + b.right * l.x + b.up * l.y;
}

Vec3 Camera::panorama_direction(float x, float y) const {
  const Vec2 uv = plane_point(x, y);
  if (d_.panorama_type == PanoramaType::Equirectangular) {
    // Longitude grows to the right from the view axis, latitude upwards (Cycles'
    // equirectangular_range_to_direction, turned into Blender's camera axes).
    const float lon = d_.longitude_min + (d_.longitude_max - d_.longitude_min) * uv.x;
    const float lat = d_.latitude_min + (d_.latitude_max - d_.latitude_min) * uv.y;
    const float c = std::cos(lat);
    return {c * std::sin(lon), std::sin(lat), -c * std::cos(lon)};
  }
  // Fisheyes: the angle from the axis grows with the film radius, linearly (equidistant, over the
  // frame's inscribed circle) or as 2 asin(r / 2f) (equisolid, r on the fitted sensor in mm).
  float a, b, theta;
  if (d_.panorama_type == PanoramaType::FisheyeEquidistant) {
    a = 2 * (uv.x - 0.5f), b = 2 * (uv.y - 0.5f);
    const float r = std::sqrt(a * a + b * b);
    if (r > 1) return Vec3(0.0f);
    theta = r * d_.fisheye_fov * 0.5f;
  } else {
    a = (uv.x - 0.5f) * fisheye_w_, b = (uv.y - 0.5f) * fisheye_h_;
    const float r = std::sqrt(a * a + b * b);
    if (r > 2 * d_.fisheye_lens * std::sin(0.25f * d_.fisheye_fov)) return Vec3(0.0f);
    theta = 2 * std::asin(std::min(1.0f, r / (2 * d_.fisheye_lens)));
  }
  const float r = std::sqrt(a * a + b * b);
  const float s = std::sin(theta);
  if (!(r > 0)) return {0, 0, -1};
  return {a / r * s, b / r * s, -std::cos(theta)};
}

bool Camera::generate(float x, float y, Vec2 u_lens, Ray* r, float time) const {
  const Vec2 pp = plane_point(x, y);
  const Basis b = basis(time);
  r->time = time;
  if (d_.panorama) {
    Vec3 d = panorama_direction(x, y);
    if (is_zero(d)) return false;
    Vec3 o(0.0f);
    if (has_lens()) {
      // Cycles' camera_sample_panorama: the lens is perpendicular to the direction, its axes
      // from the view axis (any other where the direction is the axis).
      const Vec3 axis(0, 0, -1);
      Vec3 u = axis - d * dot(d, axis);
      u = length_squared(u) > 1e-12f ? normalize(u) : Vec3(1, 0, 0);
      const Vec3 v = cross(d, u);
      const Vec2 l = aperture_offset(u_lens);
      o = u * l.x + v * l.y;
      d = normalize(d * d_.focus_distance - o);
    }
    r->o = b.origin + b.to_world(o);
    r->d = normalize(b.to_world(d));
    r->tmin = d_.clip_start;
    r->tmax = d_.clip_end;
    return true;
  }
  if (d_.orthographic) {
    r->o = b.origin + b.right * pp.x + b.up * pp.y;
    r->d = -b.forward_neg;
    if (has_lens()) {
      // Cycles' orthographic depth of field: every ray aims at the focus point on the view axis
      // (camera_sample_orthographic), so only the focus plane stays sharp.
      const Vec2 l = aperture_offset(u_lens);
      r->o = r->o + b.right * l.x + b.up * l.y;
      r->d = normalize(b.to_world(Vec3(-l.x, -l.y, -d_.focus_distance)));
    }
    r->tmin = d_.clip_start;
    r->tmax = d_.clip_end;
    return true;
  }
  Vec3 local(pp.x, pp.y, -1.0f);
  const float len = length(local);
  if (has_lens()) {
    // Thin lens (Cycles' camera_sample_perspective; pbrt 3, section 6.2.3): the pinhole ray's
    // point on the plane in focus, seen from a point on the lens.
    const Vec2 l = aperture_offset(u_lens);
    const Vec3 lens(l.x, l.y, 0.0f);
    r->o = b.origin + b.to_world(lens);
    r->d = normalize(b.to_world(local * d_.focus_distance - lens));
  } else {
    r->o = b.origin;
    r->d = (b.right * pp.x + b.up * pp.y - b.forward_neg) * (1.0f / len);
  }
  // Clipping planes are perpendicular to the axis, as in Cycles (with a lens, Cycles keeps the
  // pinhole ray's range along the lens ray: 1 / cos of the pinhole ray).
  r->tmin = d_.clip_start * len;
  r->tmax = d_.clip_end * len;
  return true;
}

bool Camera::project(const Vec3& o, const Vec3& p, float margin, Vec2* film, Vec3* dir, float* distance,
                     float time) const {
  if (!connectable()) return false;
  const Basis b = basis(time);
  Vec3 v = p - o;
  float z = -dot(v, b.forward_neg);
  if (!(z > 0)) return false;
  float dist = length(v);
  float px = dot(v, b.right) / z, py = dot(v, b.up) / z;
  if (has_lens()) {
    // The ray from o through p meets the plane in focus at the pinhole ray of film position
    // (px, py) (Camera::generate); its clipping range along the ray is the pinhole ray's.
    const Vec3 l = o - b.origin;
    px += dot(l, b.right) / d_.focus_distance;
    py += dot(l, b.up) / d_.focus_distance;
    const float len = std::sqrt(px * px + py * py + 1);
    if (dist < d_.clip_start * len || dist > d_.clip_end * len) return false;
  } else if (z < d_.clip_start || z > d_.clip_end) {
    return false;  // clipping planes are perpendicular to the axis
  }
  film->x = (px - x0_) / (x1_ - x0_) * width_;
  film->y = (py - y0_) / (y1_ - y0_) * height_;
  if (film->x < -margin || film->x > width_ + margin || film->y < -margin || film->y > height_ + margin) return false;
  *dir = v / dist;
  *distance = dist;
  return true;
}

bool Camera::raster(const Vec3& p, float time, Vec2* film) const {
  if (d_.panorama) return false;
  const Basis b = basis(time);
  const Vec3 v = p - b.origin;
  float px = dot(v, b.right), py = dot(v, b.up);
  if (!d_.orthographic) {
    const float z = -dot(v, b.forward_neg);
    if (z == 0) {  // Cycles' transform_perspective: the raster origin where w = 0
      *film = Vec2{0.0f, 0.0f};
      return true;
    }
    px /= z;
    py /= z;
  }
  film->x = (px - x0_) / (x1_ - x0_) * width_;
  film->y = (py - y0_) / (y1_ - y0_) * height_;
  return true;
}

void Camera::differentials(float x, float y, float* dP, float* dD) const {
  if (d_.panorama) {
    // Cycles' camera_sample_panorama: the view-plane step of a pixel as dP, the change of
    // direction to the neighbouring pixels as dD (0 towards one that sees nothing).
    const Vec3 c = panorama_direction(x, y), dx = panorama_direction(x + 1, y), dy = panorama_direction(x, y + 1);
    auto step = [&](const Vec3& n) { return is_zero(c) || is_zero(n) ? 0.0f : length(normalize(n) - normalize(c)); };
    *dD = 0.5f * (step(dx) + step(dy));
    // Rays start at the near clip: Cycles moves the origin there and grows dP by its dD.
    *dP = 0.5f * ((x1_ - x0_) / width_ + (y1_ - y0_) / height_) + d_.clip_start * *dD;
    return;
  }
  const float sx = (x1_ - x0_) / width_, sy = (y1_ - y0_) / height_;  // a pixel on the view plane
  // The footprint's size does not depend on where the camera is: the centre's axes.
  const Vec3 &right = centre_.right, &up = centre_.up, &forward_neg = centre_.forward_neg;
  if (d_.orthographic) {
    *dP = 0.5f * (length(right * sx) + length(up * sy));
    *dD = 0;
    return;
  }
  const Vec2 pp = plane_point(x, y);
  const Vec3 d = right * pp.x + up * pp.y - forward_neg, n = normalize(d);
  *dD = 0.5f * (length(normalize(d + right * sx) - n) + length(normalize(d + up * sy) - n));
  *dP = d_.clip_start * length(d) * *dD;  // from the near clip along the ray (Cycles' nearclip / cos)
}

}  // namespace lt
