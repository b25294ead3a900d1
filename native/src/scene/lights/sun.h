// Sun (distant) lamps, Cycles 3.4: irradiance P (Blender's colour x strength, W/m^2) from one
// direction; with an angle, a disk of radius tan(angle / 2) at unit distance sampled by area, whose
// radiance in direction w is P / (pi tan^2(angle / 2) cos^3) with cos = w . (-direction): Cycles'
// distant light sets eval_fac to the sampling pdf, so every sample carries P (a constant radiance
// would give 0.6 % less light at a 10 degree sun).
#pragma once

#include "scene/lights/light.h"

namespace lt {

inline Light sun_lamp(const Spectrum& power, const Transform& xf, float angle) {
  Light l = blender_lamp(LightType::Sun, power, xf);
  float half = 0.5f * std::min(angle, 3.0f);  // Blender caps the angle at 180 degrees
  l.tan_half_angle = half > 1e-6f ? std::tan(half) : 0.0f;
  l.cos_half_angle_sun = std::cos(half);
  return l;
}

// Radiance towards -wi within the disk (the irradiance for a delta sun).
inline Spectrum sun_radiance(const Light& l, const Vec3& wi) {
  if (l.tan_half_angle == 0) return l.power;
  const float c = dot(wi, -l.direction);
  return l.power * (1.0f / (kPi * l.tan_half_angle * l.tan_half_angle * c * c * c));
}

inline bool sun_sample(const Light& l, Vec2 u, LightSample* s) {
  s->distance = INFINITY;
  s->n = Vec3(0.0f);
  s->on_surface = false;
  if (l.tan_half_angle == 0) {
    s->wi = -l.direction;
    s->pdf = 1;
    s->radiance = l.power;
    s->delta = true;
    return true;
  }
  Frame f(-l.direction);
  Vec2 d = sample_disk_concentric(u);
  s->wi = normalize(f.to_world(Vec3(d.x * l.tan_half_angle, d.y * l.tan_half_angle, 1)));
  float c = dot(s->wi, -l.direction);
  s->pdf = 1 / (kPi * l.tan_half_angle * l.tan_half_angle * c * c * c);
  s->radiance = sun_radiance(l, s->wi);
  s->delta = false;
  return true;
}

// Solid-angle density of sun_sample for direction wi (0 for a delta sun).
inline float sun_pdf(const Light& l, const Vec3& wi) {
  if (l.tan_half_angle == 0) return 0;
  float c = dot(wi, -l.direction);
  if (c <= l.cos_half_angle_sun) return 0;
  return 1 / (kPi * l.tan_half_angle * l.tan_half_angle * c * c * c);
}

// The direction as sun_sample picks it, the origin on the scene's disk (emit_from_scene_disk).
inline bool sun_sample_emission(const Light& l, const Vec3& center, float radius, Vec2 up, Vec2 ud, EmissionSample* e) {
  Vec3 dir;  // direction light travels
  if (l.tan_half_angle == 0) {
    dir = l.direction;
    e->pdf_dir = 1;
    e->delta_dir = true;
    e->radiance = l.power;
  } else {
    LightSample ls;
    sun_sample(l, ud, &ls);
    dir = -ls.wi;
    e->pdf_dir = ls.pdf;
    e->radiance = ls.radiance;
  }
  emit_from_scene_disk(dir, center, radius, up, e);
  return e->pdf_dir > 0 && !is_black(e->radiance);
}

// An escaped ray along d sees the sun's disk.
inline bool sun_intersect(const Light& l, const Vec3& d) { return dot(d, -l.direction) > l.cos_half_angle_sun; }

}  // namespace lt
