// Area lamps, Cycles 3.4: a rectangle or ellipse, one-sided, of radiance P / (4 A) (P: Blender's
// colour x energy, A: the area), sampled uniformly by area; light subpaths leave it cosine-weighted.
#pragma once

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

inline bool area_lamp_sample(const Light& l, const Vec3& p, Vec2 u, LightSample* s) {
  Vec3 q = area_lamp_point(l, u);
  float d2;
  if (!aim_at(p, q, s, &d2)) return false;
  s->n = l.direction;
  s->on_surface = true;
  float cos_l = dot(l.direction, -s->wi);
  if (cos_l <= 0) return false;
  s->pdf = d2 / (l.area * cos_l);
  s->radiance = area_lamp_radiance(l) * area_spread_factor(l, cos_l);
  s->delta = false;
  return true;
}

// Solid-angle density of area_lamp_sample for direction wi, the lamp at distance t.
inline float area_lamp_pdf(const Light& l, const Vec3& wi, float t) {
  float cos_l = dot(l.direction, -wi);
  return cos_l > 0 ? t * t / (l.area * cos_l) : 0;
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
