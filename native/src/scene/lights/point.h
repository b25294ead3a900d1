// Point and spot lamps, Cycles 3.4: a point of intensity P / (4 pi) (P: Blender's colour x energy);
// with a radius r, a disk of radiance P / (4 pi^2 r^2) facing the shaded point, sampled by area.
// Spots keep the cone of Cycles' spot_attenuation.
#pragma once

#include "scene/lights/light.h"

namespace lt {

inline Light point_lamp(const Spectrum& power, const Transform& xf, float radius) {
  Light l = blender_lamp(LightType::Point, power, xf);
  l.radius = radius;
  return l;
}

// spot_size: Blender's full cone angle; spot_blend: the fraction of it smoothed.
inline Light spot_lamp(const Spectrum& power, const Transform& xf, float radius, float spot_size, float spot_blend) {
  Light l = blender_lamp(LightType::Spot, power, xf);
  l.radius = radius;
  float size = clamp(spot_size, 0.0f, kPi);
  l.cos_half_angle = std::cos(0.5f * size);
  l.smooth = (1 - l.cos_half_angle) * clamp(spot_blend, 0.0f, 1.0f);
  return l;
}

// Cycles' spot_attenuation: the cone edge is smoothed over (1 - cos(half)) * blend, and the
// intensity keeps an extra cos of the angle to the axis.
inline float spot_attenuation(const Light& l, const Vec3& from_light) {
  if (l.type != LightType::Spot) return 1.0f;
  float c = dot(from_light, l.direction);
  if (c <= l.cos_half_angle) return 0.0f;
  float t = c - l.cos_half_angle;
  if (l.smooth > 0 && t < l.smooth) {
    float x = t / l.smooth;
    c *= x * x * (3 - 2 * x);
  }
  return c;
}

// Cycles 3.4's factors: the disk's radiance, or a point's intensity over the squared distance d2
// (d2 = 1: the intensity itself).
inline Spectrum point_lamp_radiance(const Light& l, float atten, float d2 = 1) {
  if (l.radius > 0) return l.power * (atten / (4 * kPi * kPi * l.radius * l.radius));
  return l.power * (atten * kInv4Pi / d2);
}

inline bool point_lamp_sample(const Light& l, const Vec3& p, Vec2 u, LightSample* s) {
  Vec3 q = l.position, n;
  if (l.radius > 0) {
    n = normalize(p - l.position);
    Frame f(n);
    Vec2 d = sample_disk_concentric(u);
    q = l.position + f.to_world(Vec3(d.x * l.radius, d.y * l.radius, 0));
  }
  float d2;
  if (!aim_at(p, q, s, &d2)) return false;
  s->n = l.radius > 0 ? -s->wi : Vec3(0.0f);
  s->on_surface = false;  // the disk faces each receiver: no surface of the scene
  float atten = spot_attenuation(l, -s->wi);
  if (atten == 0) return false;
  s->radiance = point_lamp_radiance(l, atten, d2);
  if (l.radius > 0) {
    float cos_l = dot(n, -s->wi);
    if (cos_l <= 0) return false;
    s->pdf = d2 / (kPi * l.radius * l.radius * cos_l);
    s->delta = false;
  } else {
    s->pdf = 1;
    s->delta = true;
  }
  return true;
}

// Solid-angle density of point_lamp_sample for direction wi from p, the disk at distance t.
inline float point_lamp_pdf(const Light& l, const Vec3& p, const Vec3& wi, float t) {
  if (l.radius == 0) return 0;
  Vec3 n = normalize(p - l.position);
  float cos_l = dot(n, -wi);
  return cos_l > 0 ? t * t / (kPi * l.radius * l.radius * cos_l) : 0;
}

// Only points start light subpaths (Light::faces_receiver); a spot's directions stay in its cone.
inline bool point_lamp_sample_emission(const Light& l, Vec2 ud, EmissionSample* e) {
  if (l.faces_receiver()) return false;
  Vec3 dir;
  if (l.type == LightType::Spot) {
    dir = Frame(l.direction).to_world(sample_uniform_cone(ud, l.cos_half_angle));
    e->pdf_dir = uniform_cone_pdf(l.cos_half_angle);
  } else {
    dir = sample_uniform_sphere(ud);
    e->pdf_dir = uniform_sphere_pdf();
  }
  e->ray.o = l.position;
  e->ray.d = dir;
  e->n = Vec3(0.0f);
  e->pdf_pos = 1;
  e->delta_pos = true;
  e->radiance = point_lamp_radiance(l, spot_attenuation(l, dir));
  return !is_black(e->radiance);
}

inline void point_lamp_pdf_emission(const Light& l, const Vec3& dir, float* pdf_pos, float* pdf_dir) {
  *pdf_pos = l.radius > 0 ? 1 / (kPi * l.radius * l.radius) : 1;
  if (l.type == LightType::Spot)
    *pdf_dir = dot(dir, l.direction) > l.cos_half_angle ? uniform_cone_pdf(l.cos_half_angle) : 0;
  else
    *pdf_dir = uniform_sphere_pdf();
}

// A lamp with a radius: the disk facing `from`, the path's last scattering (Cycles 3.4 keeps the
// ray's origin there through transparent and volume-only surfaces, moving only its tmin), which
// the densities of point_lamp_pdf assume too; the ray may start further along the same line.
inline bool point_lamp_intersect(const Light& l, const Ray& ray, const Vec3& from, LampHit* hit) {
  Vec3 n = from - l.position;
  float dist = length(n);
  if (!(dist > 0)) return false;  // within the radius too: the disk still faces `from` (Cycles)
  n = n / dist;
  float denom = dot(ray.d, n);
  if (denom >= 0) return false;
  float t = dot(l.position - ray.o, n) / denom;
  if (!(t > ray.tmin && t < ray.tmax)) return false;
  Vec3 q = ray.o + ray.d * t - l.position;
  if (length_squared(q) > l.radius * l.radius) return false;
  float atten = spot_attenuation(l, -ray.d);
  if (atten == 0) return false;
  hit->t = t;
  hit->n = -ray.d;
  hit->radiance = point_lamp_radiance(l, atten);
  return true;
}

}  // namespace lt
