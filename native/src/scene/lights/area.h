// Area lamps, Cycles 3.4: a rectangle or ellipse, one-sided, of radiance P / (4 A) (P: Blender's
// colour x energy, A: the area); next-event estimation samples a rectangle by solid angle from
// nearby (area_window_solid_angle), else and an ellipse by area; light subpaths leave it uniform by
// area, cosine-weighted.
#pragma once

#include <algorithm>
#include <cmath>

#include "scene/lights/light.h"

namespace lt {

// size_x, size_y: Blender's sizes (square and disk shapes pass size_x twice); the lamp lights its -Z side.
inline Light area_lamp(const Spectrum& power, const Transform& xf, AreaShape shape, float size_x, float size_y) {
  Light l = blender_lamp(LightType::Area, power, xf);
  l.shape = shape;
  l.axis_u = xf.vector(Vec3(1, 0, 0)) * (0.5f * std::abs(size_x));
  l.axis_v = xf.vector(Vec3(0, 1, 0)) * (0.5f * std::abs(size_y));
  float a = length(cross(l.axis_u, l.axis_v));
  l.area = shape == AreaShape::Rectangle ? 4 * a : kPi * a;
  l.direction = normalize(cross(l.axis_u, l.axis_v)) * -1.0f;
  return l;
}

// Blender's Spread (radians) as Cycles 3.4 turns it into the slat model: the cut-off angle off
// the normal is spread / 2 (min 1 degree), and the normalisation keeps the lamp's power, the
// integral of cos a sin a (1 - tan a / tan(spread / 2)) over [0, spread / 2] against 1/2:
// 1 / (1 - h cot h) for h = spread / 2 (Cycles writes it with the complement's tangent).
inline void set_area_spread(Light* l, float spread) {
  if (!(spread > 0) || spread >= kPi) return;  // none (0: a descriptor that does not say)
  const double h = 0.5 * std::max(double(spread), kPi / 180.0);
  l->tan_spread = float(1 / std::tan(h));
  l->normalize_spread = float(1 / (1 - h / std::tan(h)));  // double: 1 - h cot h ~ h^2 / 3 when small
}

// The spread's factor for light leaving at cos_a off the normal (1 without a spread).
inline float area_spread_factor(const Light& l, float cos_a) {
  if (l.tan_spread == 0) return 1.0f;
  if (!(cos_a > 0)) return 0.0f;
  const float tan_a = std::sqrt(std::max(0.0f, 1.0f - cos_a * cos_a)) / cos_a;
  return std::max(0.0f, (1.0f - l.tan_spread * tan_a) * l.normalize_spread);
}

inline Spectrum area_lamp_radiance(const Light& l) { return l.power * (0.25f / l.area); }

// A point uniform by area (rectangle: u over [-1, 1]^2 of the half axes).
inline Vec3 area_lamp_point(const Light& l, Vec2 u) {
  if (l.shape == AreaShape::Rectangle) return l.position + l.axis_u * (2 * u.x - 1) + l.axis_v * (2 * u.y - 1);
  Vec2 d = sample_disk_concentric(u);
  return l.position + l.axis_u * d.x + l.axis_v * d.y;
}

// The rectangle next-event estimation samples from p: the lamp, or with a Spread only the part
// whose light can reach p, the square around the disk of radius (distance to the plane) / tan h
// clamped to the lamp (Cycles 3.4's light_spread_clamp_area_light). False where none can.
struct AreaWindow {
  Vec3 corner, ex, ey;   // ex, ey: unit axes
  float lx = 0, ly = 0;  // side lengths
};
inline bool area_lamp_window(const Light& l, const Vec3& p, AreaWindow* w) {
  const float hx = length(l.axis_u), hy = length(l.axis_v);
  if (!(hx > 0 && hy > 0)) return false;
  w->ex = l.axis_u / hx;
  w->ey = l.axis_v / hy;
  float u0 = -hx, u1 = hx, v0 = -hy, v1 = hy;
  if (l.tan_spread > 0) {
    const Vec3 d = p - l.position;
    const float r = dot(d, l.direction) / l.tan_spread, cu = dot(d, w->ex), cv = dot(d, w->ey);
    u0 = std::max(u0, cu - r), u1 = std::min(u1, cu + r);
    v0 = std::max(v0, cv - r), v1 = std::min(v1, cv + r);
    if (!(u0 < u1 && v0 < v1)) return false;
  }
  w->corner = l.position + w->ex * u0 + w->ey * v0;
  w->lx = u1 - u0;
  w->ly = v1 - v0;
  return true;
}

// The solid angle a rectangle subtends from p and what sampling it uniformly needs (Urena, Fajardo
// and King 2013, "An Area-Preserving Parametrization for Spherical Rectangles", as Cycles 3.4's
// rect_light_sample, in single precision as there): S is a difference of angles near 2 pi, exact
// to about 1e-6 sr, which the nearby points it is used from (area_window_solid_angle) keep far
// above kMinRectSolidAngle.
struct SphericalRect {
  float x0, y0, x1, y1, z0, b0, b1, k, solid_angle = 0;
  Vec3 o, x, y, z;
};
inline SphericalRect spherical_rect(const AreaWindow& w, const Vec3& p) {
  SphericalRect r;
  r.o = p;
  r.x = w.ex;
  r.y = w.ey;
  r.z = cross(w.ex, w.ey);
  const Vec3 d = w.corner - p;
  r.z0 = dot(d, r.z);
  if (r.z0 > 0) r.z = -r.z, r.z0 = -r.z0;  // z points away from the rectangle
  r.x0 = dot(d, r.x), r.y0 = dot(d, r.y);
  r.x1 = r.x0 + w.lx, r.y1 = r.y0 + w.ly;
  if (!(r.z0 < 0)) return r;  // p in the rectangle's plane: no solid angle
  // The z components of the normals of the planes through p and each edge (the other components
  // are zero or follow), and the angles between neighbours.
  const float zz = r.z0 * r.z0;
  const float nz[4] = {-r.y0 / std::sqrt(zz + r.y0 * r.y0), r.x1 / std::sqrt(zz + r.x1 * r.x1),
                       r.y1 / std::sqrt(zz + r.y1 * r.y1), -r.x0 / std::sqrt(zz + r.x0 * r.x0)};
  auto angle = [](float c) { return std::acos(std::clamp(c, -1.0f, 1.0f)); };
  const float g0 = angle(-nz[0] * nz[1]), g1 = angle(-nz[1] * nz[2]), g2 = angle(-nz[2] * nz[3]),
              g3 = angle(-nz[3] * nz[0]);
  r.b0 = nz[0];
  r.b1 = nz[2];
  r.k = 2 * kPi - g2 - g3;
  r.solid_angle = g0 + g1 - r.k;
  return r;
}
inline Vec3 spherical_rect_point(const SphericalRect& r, Vec2 u) {
  const float au = u.x * r.solid_angle + r.k;
  const float fu = (std::cos(au) * r.b0 - r.b1) / std::sin(au);
  float cu = std::copysign(1 / std::sqrt(fu * fu + r.b0 * r.b0), fu);
  cu = std::clamp(cu, -1.0f, 1.0f);
  const float xu = std::clamp(-cu * r.z0 / std::max(std::sqrt(1 - cu * cu), 1e-6f), r.x0, r.x1);
  const float dd = std::sqrt(xu * xu + r.z0 * r.z0);
  const float h0 = r.y0 / std::sqrt(dd * dd + r.y0 * r.y0), h1 = r.y1 / std::sqrt(dd * dd + r.y1 * r.y1);
  const float hv = h0 + u.y * (h1 - h0), hv2 = hv * hv;
  const float yv = hv2 < 1 - 1e-6f ? std::clamp(hv * dd / std::sqrt(1 - hv2), r.y0, r.y1) : r.y1;
  return r.o + r.x * xu + r.y * yv + r.z * r.z0;
}

// Below this solid angle (sr) a rectangle is sampled by area: the spherical parametrisation's
// angles lose their precision there, and area sampling is as good as uniform in solid angle.
constexpr float kMinRectSolidAngle = 1e-3f;

// The solid angle of window w from p when next-event estimation samples it by solid angle, else 0:
// from points closer to the lamp's plane than the window's longer side, as for triangles (further
// away cos / d^2 hardly varies over it, and area sampling costs no inverse cosines: on cornell_area
// always by solid angle cost 14 % more CPU per sample for 6 % less variance).
inline float area_window_solid_angle(const Light& l, const AreaWindow& w, const Vec3& p, SphericalRect* r) {
  const float side = std::max(w.lx, w.ly), plane = dot(p - l.position, l.direction);
  if (!(plane < side)) return 0;
  *r = spherical_rect(w, p);
  return r->solid_angle >= kMinRectSolidAngle ? r->solid_angle : 0;
}

// Next-event estimation: a rectangle (its Spread's window) uniform in solid angle from nearby
// (area_window_solid_angle; Cycles 3.4 from everywhere), else by area, an ellipse by area.
inline bool area_lamp_sample(const Light& l, const Vec3& p, Vec2 u, LightSample* s) {
  if (!(dot(p - l.position, l.direction) > 0)) return false;  // one-sided
  Vec3 q;
  float window_area = l.area;
  float solid_angle = 0;
  if (l.shape == AreaShape::Rectangle) {
    AreaWindow w;
    if (!area_lamp_window(l, p, &w)) return false;
    SphericalRect r;
    solid_angle = area_window_solid_angle(l, w, p, &r);
    window_area = w.lx * w.ly;
    q = solid_angle > 0 ? spherical_rect_point(r, u) : w.corner + w.ex * (u.x * w.lx) + w.ey * (u.y * w.ly);
  } else {
    q = area_lamp_point(l, u);
  }
  float d2;
  if (!aim_at(p, q, s, &d2)) return false;
  s->n = l.direction;
  s->on_surface = true;
  float cos_l = dot(l.direction, -s->wi);
  if (cos_l <= 0) return false;
  s->pdf = solid_angle > 0 ? 1 / solid_angle : d2 / (window_area * cos_l);
  s->radiance = area_lamp_radiance(l) * area_spread_factor(l, cos_l);
  s->delta = false;
  return true;
}

// Solid-angle density of area_lamp_sample at p for direction wi, which meets the lamp at distance t.
inline float area_lamp_pdf(const Light& l, const Vec3& p, const Vec3& wi, float t) {
  float cos_l = dot(l.direction, -wi);
  if (!(cos_l > 0)) return 0;
  if (l.shape == AreaShape::Ellipse) return t * t / (l.area * cos_l);
  AreaWindow w;
  if (!area_lamp_window(l, p, &w)) return 0;
  if (l.tan_spread > 0) {  // outside the window: never sampled (and dark)
    const Vec3 q = p + wi * t - w.corner;
    const float a = dot(q, w.ex), b = dot(q, w.ey);
    if (!(a >= 0 && a <= w.lx && b >= 0 && b <= w.ly)) return 0;
  }
  SphericalRect r;
  const float solid_angle = area_window_solid_angle(l, w, p, &r);
  return solid_angle > 0 ? 1 / solid_angle : t * t / (w.lx * w.ly * cos_l);
}

inline bool area_lamp_sample_emission(const Light& l, Vec2 up, Vec2 ud, EmissionSample* e) {
  Vec3 q = area_lamp_point(l, up);
  Vec3 local = sample_cosine_hemisphere(ud);
  e->ray.o = q;
  e->ray.d = Frame(l.direction).to_world(local);
  e->n = l.direction;
  e->pdf_pos = 1 / l.area;
  e->pdf_dir = cosine_hemisphere_pdf(local.z);
  e->radiance = area_lamp_radiance(l) * area_spread_factor(l, local.z);
  return e->pdf_dir > 0;
}

inline void area_lamp_pdf_emission(const Light& l, const Vec3& dir, float* pdf_pos, float* pdf_dir) {
  *pdf_pos = 1 / l.area;
  *pdf_dir = cosine_hemisphere_pdf(dot(dir, l.direction));
}

inline bool area_lamp_intersect(const Light& l, const Ray& ray, LampHit* hit) {
  float denom = dot(ray.d, l.direction);
  if (denom >= 0) return false;  // one-sided: seen only from the side it lights
  float t = dot(l.position - ray.o, l.direction) / denom;
  if (!(t > ray.tmin && t < ray.tmax)) return false;
  Vec3 q = ray.o + ray.d * t - l.position;
  float a = dot(q, l.axis_u) / length_squared(l.axis_u), b = dot(q, l.axis_v) / length_squared(l.axis_v);
  bool inside = l.shape == AreaShape::Rectangle ? (std::abs(a) <= 1 && std::abs(b) <= 1) : (a * a + b * b <= 1);
  if (!inside) return false;
  hit->t = t;
  hit->n = l.direction;
  hit->radiance = area_lamp_radiance(l) * area_spread_factor(l, -denom / length(ray.d));
  return true;
}

}  // namespace lt
