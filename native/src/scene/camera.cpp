#include "scene/camera.h"

#include <algorithm>

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
    // Cycles' panorama view plane is [0, 1]^2 shifted by the camera's shift (blender/camera.cpp);
    // a viewport looking through the camera sees the part of it its region covers
    // (pano_viewplane: the region relative to the camera's frame).
    const float* vp = desc.panorama_viewplane;
    const bool region = vp[1] != vp[0] && vp[3] != vp[2];
    x0_ = (region ? vp[0] : 0) + desc.shift_x, x1_ = (region ? vp[1] : 1) + desc.shift_x;
    y0_ = (region ? vp[2] : 0) + desc.shift_y, y1_ = (region ? vp[3] : 1) + desc.shift_y;
    // The equisolid and polynomial fisheyes' sensor, fitted to the frame as Cycles does: note its
    // automatic fit is horizontal only for a strictly wider frame.
    const bool frame = desc.panorama_frame_aspect > 0;
    const float xr = frame ? desc.panorama_frame_aspect : winx, yr = frame ? 1.0f : winy * yasp;
    const bool horizontal = desc.sensor_fit == 1 || (desc.sensor_fit == 0 && xr > yr);
    const float size = desc.sensor_fit == 2 ? desc.sensor_height : desc.sensor_width;
    fisheye_w_ = horizontal ? size : size * xr / yr;
    fisheye_h_ = horizontal ? size * yr / xr : size;
    if (radial()) radial_ends_ = radial_pieces();
  }
  const float* k = desc.polynomial;
  const bool degenerate =
      desc.panorama &&
      ((desc.panorama_type == PanoramaType::Equirectangular &&
        (desc.latitude_max == desc.latitude_min || desc.longitude_max == desc.longitude_min)) ||
       (desc.panorama_type == PanoramaType::FisheyeLensPolynomial && k[1] == 0 && k[2] == 0 && k[3] == 0 && k[4] == 0));
  connectable_ = !(desc.panorama && desc.aperture_radius > 0) && !degenerate;
  zooms_ = !desc.panorama && !desc.orthographic && (desc.zoom_pre != 1 || desc.zoom_post != 1);
  centre_ = basis_of(desc.xf);
  if (desc.motion.size() >= 2) motion_ = decompose_motion(desc.motion);
  rigid_motion_ = true;
  for (const DecomposedTransform& d : motion_)
    for (int i = 0; i < 3; ++i)
      rigid_motion_ = rigid_motion_ && d.scale[i] > 0 && std::abs(d.skew[i]) <= 1e-6f * d.scale[0];
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
    last.basis = interpolated_basis(time);
    last.generation = generation_;
    last.time = time;
  }
  return last.basis;
}

// Without skew (to rounding) and with positive scales, the normalised columns of R S (basis_of)
// are R's: read from the quaternion, without the matrix product and the normalisations (motion
// blur's cost per camera sample).
Camera::Basis Camera::interpolated_basis(float time) const {
  const DecomposedTransform d = interpolate_decomposed(motion_, time);
  if (!rigid_motion_) return basis_of(recompose(d));
  const float x = d.q[0], y = d.q[1], z = d.q[2], w = d.q[3];
  return {d.translation,
          {1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)},
          {2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)},
          {2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)}};
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

bool Camera::radial() const {
  return d_.panorama_type == PanoramaType::FisheyeEquidistant || d_.panorama_type == PanoramaType::FisheyeEquisolid ||
         d_.panorama_type == PanoramaType::FisheyeLensPolynomial;
}

Vec2 Camera::fisheye_scale() const {
  return d_.panorama_type == PanoramaType::FisheyeEquidistant ? Vec2{2, 2} : Vec2{fisheye_w_, fisheye_h_};
}

// Cycles' fisheye_to_direction (equidistant: r fov / 2 over the inscribed circle),
// fisheye_equisolid_to_direction (2 asin(r / 2 lens)) and fisheye_lens_polynomial_to_direction.
double Camera::radial_theta(double rho) const {
  switch (d_.panorama_type) {
    case PanoramaType::FisheyeEquidistant:
      return rho * d_.fisheye_fov * 0.5;
    case PanoramaType::FisheyeEquisolid:
      return 2 * std::asin(std::min(1.0, rho / (2.0 * d_.fisheye_lens)));
    default: {
      const float* k = d_.polynomial;
      return -(k[0] + rho * (k[1] + rho * (k[2] + rho * (k[3] + rho * double(k[4])))));
    }
  }
}

double Camera::radial_dtheta(double rho) const {
  switch (d_.panorama_type) {
    case PanoramaType::FisheyeEquidistant:
      return d_.fisheye_fov * 0.5;
    case PanoramaType::FisheyeEquisolid: {
      const double f2 = 4.0 * d_.fisheye_lens * d_.fisheye_lens - rho * rho;
      return f2 > 0 ? 2 / std::sqrt(f2) : INFINITY;
    }
    default: {
      const float* k = d_.polynomial;
      return -(k[1] + rho * (2 * k[2] + rho * (3 * k[3] + rho * 4.0 * k[4])));
    }
  }
}

// What each projection sees: equidistant its inscribed circle, equisolid the circle of its field
// of view on the sensor, the polynomial where its angle is within half the field of view.
bool Camera::radial_visible(double rho, double theta) const {
  switch (d_.panorama_type) {
    case PanoramaType::FisheyeEquidistant:
      return rho <= 1;
    case PanoramaType::FisheyeEquisolid:
      return rho <= 2.0 * d_.fisheye_lens * std::sin(0.25 * d_.fisheye_fov);
    default:
      return std::abs(theta) <= 0.5 * d_.fisheye_fov;
  }
}

// The rho range that the film within a frame's size of margin covers, cut at theta's turning
// points: the roots of theta' (a cubic for the polynomial), each alone in a piece between the
// roots of theta'' (a quadratic), found by bisection.
std::vector<double> Camera::radial_pieces() const {
  const Vec2 scale = fisheye_scale();
  const double m = std::max(width_, height_);  // the margin, in uv below
  const double mu = m / width_ * std::abs(x1_ - x0_), mv = m / height_ * std::abs(y1_ - y0_);
  const double ux = std::max(std::abs(std::min(x0_, x1_) - mu - 0.5), std::abs(std::max(x0_, x1_) + mu - 0.5));
  const double uy = std::max(std::abs(std::min(y0_, y1_) - mv - 0.5), std::abs(std::max(y0_, y1_) + mv - 0.5));
  double r_max = std::sqrt(ux * ux * scale.x * scale.x + uy * uy * scale.y * scale.y);
  if (d_.panorama_type == PanoramaType::FisheyeEquidistant) r_max = std::min(r_max, 1.0);
  if (d_.panorama_type == PanoramaType::FisheyeEquisolid) r_max = std::min(r_max, 2.0 * d_.fisheye_lens);
  std::vector<double> ends{0.0};
  if (d_.panorama_type == PanoramaType::FisheyeLensPolynomial) {
    // theta'' = -(2 k2 + 6 k3 rho + 12 k4 rho^2).
    const double a = 12.0 * d_.polynomial[4], b = 6.0 * d_.polynomial[3], c = 2.0 * d_.polynomial[2];
    std::vector<double> cuts{0.0};
    if (a != 0) {
      const double disc = b * b - 4 * a * c;
      if (disc >= 0) {
        const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
        for (double root : {q / a, q != 0 ? c / q : -1.0})
          if (root > 0 && root < r_max) cuts.push_back(root);
      }
    } else if (b != 0 && -c / b > 0 && -c / b < r_max) {
      cuts.push_back(-c / b);
    }
    cuts.push_back(r_max);
    std::sort(cuts.begin(), cuts.end());
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
      double lo = cuts[i], hi = cuts[i + 1];
      const double dlo = radial_dtheta(lo), dhi = radial_dtheta(hi);
      if ((dlo < 0) != (dhi < 0) && dlo != 0 && dhi != 0) {
        for (int it = 0; it < 80; ++it) {
          const double mid = 0.5 * (lo + hi);
          ((radial_dtheta(mid) < 0) == (dlo < 0) ? lo : hi) = mid;
        }
        ends.push_back(0.5 * (lo + hi));
      }
    }
  }
  ends.push_back(r_max);
  return ends;
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
  if (d_.panorama_type == PanoramaType::EquiangularCubemapFace) {
    // Cycles' equiangular_cubemap_face_to_direction: a 90-degree face whose film steps in equal
    // angles, tan(pi/2 u - pi/4) to the right and upwards on the plane at unit distance (Cycles'
    // (1, tan(pi/4 - pi/2 u), tan(pi/2 v - pi/4)) in Blender's camera axes). Periodic: the film
    // beyond u or v of 1.5 (or -0.5) sees the face again; exactly there nothing.
    const float x = std::tan(uv.x * (0.5f * kPi) - 0.25f * kPi), y = std::tan(uv.y * (0.5f * kPi) - 0.25f * kPi);
    const Vec3 d(x, y, -1.0f);
    const float len2 = length_squared(d);
    return std::isfinite(len2) ? d / std::sqrt(len2) : Vec3(0.0f);
  }
  if (d_.panorama_type == PanoramaType::MirrorBall) {
    // Cycles' mirrorball_to_direction: the film's inscribed circle is a mirror sphere seen from
    // infinitely far behind the camera, the view reflected off it (the centre sees forward, the
    // rim backward); outside the circle nothing.
    const float nx = 2 * uv.x - 1, ny = 2 * uv.y - 1, r2 = nx * nx + ny * ny;
    if (r2 > 1) return Vec3(0.0f);
    const float h = std::sqrt(std::max(0.0f, 1 - r2));
    return {2 * h * nx, 2 * h * ny, 1 - 2 * h * h};
  }
  // Fisheyes: the angle from the axis grows with the film radius (radial_theta). Cycles takes the
  // azimuth as acos(a / r), the upward one at the centre (which only the polynomial's k0 tilts).
  const Vec2 scale = fisheye_scale();
  const float a = (uv.x - 0.5f) * scale.x, b = (uv.y - 0.5f) * scale.y;
  const float r = std::sqrt(a * a + b * b);
  const double theta = radial_theta(r);
  if (!radial_visible(r, theta) || !std::isfinite(theta)) return Vec3(0.0f);
  const float s = float(std::sin(theta)), c = float(std::cos(theta));
  if (!(r > 0)) return {0, s, -c};
  return {a / r * s, b / r * s, -c};
}

void Camera::panorama_preimages(const Vec3& w, float margin, Projection* out) const {
  const float W = float(width_), H = float(height_);
  const float du = x1_ - x0_, dv = y1_ - y0_;
  // The film's pixels per unit of uv area.
  const double uv_to_pixels = double(W) * H / std::abs(double(du) * dv);
  auto add = [&](float u, float v, double importance) {
    const Vec2 film{(u - x0_) / du * W, (v - y0_) / dv * H};
    if (!(film.x >= -margin && film.x <= W + margin && film.y >= -margin && film.y <= H + margin)) return;
    if (!(importance > 0) || !std::isfinite(importance) || out->count == kMaxPreimages) return;
    out->at[out->count++] = {film, float(importance)};
  };
  // The film's uv range within the margin.
  const float u_lo = std::min(x0_, x1_) - margin / W * std::abs(du),
              u_hi = std::max(x0_, x1_) + margin / W * std::abs(du);
  const float v_lo = std::min(y0_, y1_) - margin / H * std::abs(dv),
              v_hi = std::max(y0_, y1_) + margin / H * std::abs(dv);
  if (d_.panorama_type == PanoramaType::Equirectangular) {
    // d omega = cos(lat) dlat dlon; the film's pixels cover the ranges linearly. Longitudes repeat
    // every turn, and a latitude past a pole is the one before it half a turn round.
    const double dlon = double(d_.longitude_max) - d_.longitude_min, dlat = double(d_.latitude_max) - d_.latitude_min;
    if (dlon == 0 || dlat == 0) return;
    const double lon = std::atan2(double(w.x), -double(w.z)), lat = std::asin(std::clamp(double(w.y), -1.0, 1.0));
    const double pi = 3.14159265358979323846;
    const double lats[3] = {lat, pi - lat, -pi - lat}, turns[3] = {0, pi, pi};
    for (int i = 0; i < 3; ++i) {
      const double v = (lats[i] - d_.latitude_min) / dlat;
      if (v < v_lo || v > v_hi) continue;
      const double importance = uv_to_pixels / (std::abs(std::cos(lats[i]) * dlon * dlat));
      // Longitudes lon + turn + 2 pi k whose u is within [u_lo, u_hi].
      const double l0 = lon + turns[i] - d_.longitude_min;
      const double ka = (std::min(u_lo * dlon, u_hi * dlon) - l0) / (2 * pi),
                   kb = (std::max(u_lo * dlon, u_hi * dlon) - l0) / (2 * pi);
      for (double k = std::ceil(ka); k <= std::floor(kb) && k - std::ceil(ka) < 8; ++k)
        add(float((l0 + 2 * pi * k) / dlon), float(v), importance);
    }
    return;
  }
  if (d_.panorama_type == PanoramaType::EquiangularCubemapFace) {
    // x = tan a, y = tan b on the plane at unit distance, a and b linear in u and v (pi/2 per
    // unit): d omega = dx dy / (1 + x^2 + y^2)^(3/2) and dx = (1 + x^2) da. A forward direction
    // is seen at u = 2 a / pi + 1/2 (and v), and again every 2 units of u or v.
    if (!(w.z < 0)) return;
    const double x = double(w.x) / -w.z, y = double(w.y) / -w.z, s = 1 + x * x + y * y;
    const double quarter = 0.5 * 3.14159265358979323846;
    const double importance = uv_to_pixels * s * std::sqrt(s) / (quarter * quarter * (1 + x * x) * (1 + y * y));
    const double u0 = std::atan(x) / quarter + 0.5, v0 = std::atan(y) / quarter + 0.5;
    for (double u = u0 + 2 * std::ceil((u_lo - u0) / 2); u <= u_hi; u += 2)
      for (double v = v0 + 2 * std::ceil((v_lo - v0) / 2); v <= v_hi; v += 2) add(float(u), float(v), importance);
    return;
  }
  if (d_.panorama_type == PanoramaType::MirrorBall) {
    // The sphere's normal halves the angle between the view's -Z and the direction: equal-area,
    // d omega = 4 dA on the unit disk (the angle from the axis is twice the normal's), and the
    // disk is 2 x 2 in uv, 16 uv areas per steradian. The rim (straight behind) is a null set.
    const Vec3 m = w - Vec3(0, 0, 1);
    const float len = length(m);
    if (!(len > 1e-7f)) return;
    add(0.5f * (m.x / len + 1), 0.5f * (m.y / len + 1), uv_to_pixels / 16);
    return;
  }
  // Radial fisheyes: a direction at angle alpha from the axis and azimuth psi on the film is seen
  // where theta(rho) = alpha + 2 pi k (azimuth psi) or -alpha + 2 pi k (the opposite azimuth).
  // dA = rho drho dphi, d omega = |sin theta theta'| drho dphi, and the film's pixels cover uv
  // linearly, the radial units by fisheye_scale().
  const double pi = 3.14159265358979323846;
  // (atan2: accurate near the axis and straight behind, where acos of -z is not)
  const double alpha = std::atan2(std::hypot(double(w.x), double(w.y)), -double(w.z));
  const double psi = std::atan2(double(w.y), double(w.x));
  const Vec2 scale = fisheye_scale();
  const double to_pixels = uv_to_pixels / (double(scale.x) * scale.y);
  const double half_fov = 0.5 * d_.fisheye_fov;
  double found[kMaxPreimages];
  int n_found = 0;
  for (size_t i = 0; i + 1 < radial_ends_.size(); ++i) {
    const double ra = radial_ends_[i], rb = radial_ends_[i + 1];
    const double ta = radial_theta(ra), tb = radial_theta(rb);
    const double lo = std::max(std::min(ta, tb), -half_fov), hi = std::min(std::max(ta, tb), half_fov);
    if (!(lo <= hi)) continue;
    for (int side = 0; side < 2; ++side) {
      const double base = side == 0 ? alpha : -alpha;
      for (double k = std::ceil((lo - base) / (2 * pi)); base + 2 * pi * k <= hi; ++k) {
        const double target = base + 2 * pi * k;
        // theta is monotonic on [ra, rb]: bisection.
        double a = ra, b = rb;
        const bool rising = tb >= ta;
        for (int it = 0; it < 60; ++it) {
          const double mid = 0.5 * (a + b);
          ((radial_theta(mid) < target) == rising ? a : b) = mid;
        }
        const double rho = 0.5 * (a + b);
        // A root on the end two pieces share is found by both.
        bool seen = false;
        for (int j = 0; j < n_found; ++j)
          seen = seen || std::abs(found[j] - (side == 0 ? rho : -rho)) < 1e-9 * (1 + rb);
        if (seen || n_found == kMaxPreimages) continue;
        found[n_found++] = side == 0 ? rho : -rho;
        const double theta = radial_theta(rho);
        if (!radial_visible(rho, theta)) continue;
        const double phi = side == 0 ? psi : psi + pi;
        const double st = std::abs(std::sin(theta)), dt = std::abs(radial_dtheta(rho));
        // rho / sin(theta) tends to 1 / theta'(0) on the axis when theta(0) = 0.
        const double jac = st > 1e-9 ? rho / (st * dt) : (std::abs(theta) < 1e-6 ? 1 / (dt * dt) : 0.0);
        add(float(rho * std::cos(phi) / scale.x + 0.5), float(rho * std::sin(phi) / scale.y + 0.5), jac * to_pixels);
      }
    }
  }
}

bool Camera::generate(float x, float y, Vec2 u_lens, Ray* r, float time) const {
  const Vec2 pp = plane_point(x, y);
  const Basis b = motion_.empty() ? centre_ : interpolated_basis(time);
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
    r->tmin = d_.clip_start;
    r->tmax = d_.clip_end;
    if (has_lens()) {
      // Cycles' orthographic depth of field (camera_sample_orthographic): rays start on the near
      // clip plane, moved by the lens offset, and aim at the focus distance measured from there,
      // so the plane in focus is at Clip Start + focus distance.
      const Vec2 l = aperture_offset(u_lens);
      r->o = ortho_lens_plane(b) + b.right * (pp.x + l.x) + b.up * (pp.y + l.y);
      r->d = normalize(b.to_world(Vec3(-l.x, -l.y, -d_.focus_distance)));
      r->tmin = 0;
      r->tmax = d_.clip_end - d_.clip_start;
    }
    return true;
  }
  const float s = plane_scale(time);
  Vec3 local(pp.x * s, pp.y * s, -1.0f);
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
    r->d = (b.right * local.x + b.up * local.y - b.forward_neg) * (1.0f / len);
  }
  // Clipping planes are perpendicular to the axis, as in Cycles (with a lens, Cycles keeps the
  // pinhole ray's range along the lens ray: 1 / cos of the pinhole ray).
  r->tmin = d_.clip_start * len;
  r->tmax = d_.clip_end * len;
  return true;
}

bool Camera::project(const Vec3& o, const Vec3& p, float margin, Projection* out, float time) const {
  out->count = 0;
  out->parallel = false;
  if (!connectable()) return false;
  const Basis b = basis(time);
  Vec3 v = p - o;
  const float dist = length(v);
  if (!(dist > 0)) return false;
  out->dir = v / dist;
  out->distance = dist;
  if (d_.panorama) {
    // Clipping is the distance from the camera (camera_sample_panorama).
    if (dist < d_.clip_start || dist > d_.clip_end) return false;
    out->near = d_.clip_start;
    const Vec3 w{dot(out->dir, b.right), dot(out->dir, b.up), dot(out->dir, b.forward_neg)};
    panorama_preimages(w, margin, out);
    return out->count > 0;
  }
  if (d_.orthographic) return project_orthographic(b, o, margin, out);
  float z = -dot(v, b.forward_neg);
  if (!(z > 0)) return false;
  float px = dot(v, b.right) / z, py = dot(v, b.up) / z;
  if (has_lens()) {
    // The ray from o through p meets the plane in focus at the pinhole ray of film position
    // (px, py) (Camera::generate); its clipping range along the ray is the pinhole ray's.
    const Vec3 l = o - b.origin;
    px += dot(l, b.right) / d_.focus_distance;
    py += dot(l, b.up) / d_.focus_distance;
    const float len = std::sqrt(px * px + py * py + 1);
    if (dist < d_.clip_start * len || dist > d_.clip_end * len) return false;
    out->near = d_.clip_start * len;
  } else if (z < d_.clip_start || z > d_.clip_end) {
    return false;  // clipping planes are perpendicular to the axis
  } else {
    out->near = d_.clip_start * dist / z;
  }
  const float s = plane_scale(time);  // a zoom: the view plane at this time is s times the centre's
  Vec2 film{(px / s - x0_) / (x1_ - x0_) * width_, (py / s - y0_) / (y1_ - y0_) * height_};
  if (film.x < -margin || film.x > width_ + margin || film.y < -margin || film.y > height_ + margin) return false;
  // A view-plane area a per pixel at unit distance: the direction at angle theta from the axis
  // covers a / cos^3 theta of it per steradian (pbrt 3, section 16.1.1; the same from a lens
  // point, pbrt-v4's PerspectiveCamera::PDF_We, since the focus plane is at cos theta times the
  // ray's length).
  const float c = z / dist;
  out->at[0] = {film, 1 / (pixel_area_ * s * s * c * c * c)};
  out->count = 1;
  return true;
}

// The lens offset l (camera x, y) makes the direction (-l, -focus) (generate()), the same for every
// film position: the connection point is p moved back along it to the camera's plane.
Vec3 Camera::connection_point(const Vec3& p, Vec2 u, float time) const {
  if (!d_.orthographic) return has_lens() ? lens_point(u, time) : position(time);
  const Basis b = basis(time);
  const Vec3 origin = has_lens() ? ortho_lens_plane(b) : b.origin;
  const Vec3 v = p - origin;
  const float depth = -dot(v, b.forward_neg);
  Vec2 along{0, 0};  // the plane's offset per unit of depth
  if (has_lens()) {
    const Vec2 l = aperture_offset(u);
    along = {-l.x / d_.focus_distance, -l.y / d_.focus_distance};
  }
  return origin + b.right * (dot(v, b.right) - along.x * depth) + b.up * (dot(v, b.up) - along.y * depth);
}

// The camera's rays from one lens offset l are parallel, direction d = (-l, -focus) normalised:
// the film's pixels cover its plane linearly (pixel_area_ each), and an area across the rays is
// cos(d, axis) times the plane's. The film position is o's on the plane less l, which the
// direction (out->dir, from o) gives: l = focus * d_xy / d_z.
bool Camera::project_orthographic(const Basis& b, const Vec3& o, float margin, Projection* out) const {
  const Vec3 local{dot(out->dir, b.right), dot(out->dir, b.up), -dot(out->dir, b.forward_neg)};  // z forward
  if (!(local.z > 0)) return false;
  if (has_lens()) {  // o on the near clip plane (generate()'s rays start there)
    if (out->distance > d_.clip_end - d_.clip_start) return false;
    out->near = 0;
  } else {
    const float along_ray = out->distance * local.z;
    if (along_ray < d_.clip_start || along_ray > d_.clip_end) return false;
    out->near = d_.clip_start;  // along the ray, as generate()'s
  }
  const Vec3 on_plane = o - (has_lens() ? ortho_lens_plane(b) : b.origin);
  float px = dot(on_plane, b.right), py = dot(on_plane, b.up);
  if (has_lens()) {
    px += d_.focus_distance * local.x / local.z;  // minus l
    py += d_.focus_distance * local.y / local.z;
  }
  const Vec2 film{(px - x0_) / (x1_ - x0_) * width_, (py - y0_) / (y1_ - y0_) * height_};
  if (film.x < -margin || film.x > width_ + margin || film.y < -margin || film.y > height_ + margin) return false;
  out->parallel = true;
  out->at[0] = {film, 1 / (pixel_area_ * (has_lens() ? local.z : 1.0f))};
  out->count = 1;
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
    const float s = plane_scale(time);
    px /= z * s;
    py /= z * s;
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
