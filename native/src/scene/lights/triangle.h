// Emissive triangles (Cycles' mesh lights): every triangle of an emissive material, two-sided,
// its radiance the material's emission at the point; sampled uniformly by area.
#pragma once

#include "scene/lights/light.h"
#include "scene/scene.h"

namespace lt {

// The light of triangle `primitive` of `instance`, picked by power estimate x area x pi; false for
// a degenerate triangle.
inline bool triangle_light(const Geometry& geometry, int instance, int primitive, const Material& material, Light* l) {
  *l = Light();
  l->type = LightType::Triangle;
  l->instance = instance;
  l->primitive = primitive;
  l->lightgroup = geometry.instance(instance).lightgroup;
  Vec3 p0, p1, p2;
  geometry.triangle(instance, primitive, &p0, &p1, &p2);
  l->area = 0.5f * length(cross(p1 - p0, p2 - p0));
  if (!(l->area > 0) || !std::isfinite(l->area)) return false;
  l->power = Spectrum(material.emission_power_estimate() * l->area * kPi);
  return true;
}

// The triangle's corners, its geometric normal and its area at time (motion blur: a moving or
// deforming emitter is sampled where it is at the ray's time, as Cycles' triangle_light_sample).
inline Vec3 triangle_light_corners(const Scene& scene, const Light& l, float time, Vec3* p0, Vec3* p1, Vec3* p2,
                                   float* area) {
  scene.geometry.triangle(l.instance, l.primitive, p0, p1, p2, time);
  const Vec3 c = cross(*p1 - *p0, *p2 - *p0);
  *area = scene.geometry.has_motion() ? 0.5f * length(c) : l.area;
  return normalize(c);
}

// The surface at barycentrics b and time, and the radiance it emits.
inline SurfacePoint triangle_light_surface(const Scene& scene, const Light& l, Vec2 b, float time) {
  Hit h;
  h.instance = l.instance;
  h.primitive = l.primitive;
  h.u = b.x;
  h.v = b.y;
  h.time = time;
  return scene.geometry.surface(h);
}
// dir: the direction the light leaves in (toward the receiver).
// A light sample has no ray footprint (Cycles' shader_setup_from_sample: zero dP).
inline Spectrum triangle_light_radiance(const Scene& scene, const SurfacePoint& sp, const Vec3& dir) {
  const Material& material = scene.material(sp.material);
  ShadingContext ctx = shading_context(scene.geometry, sp, -dir, 0.0f);
  if (material.needs_differentials()) add_differentials(scene.geometry, sp, 0.0f, &ctx);
  return material.emission(ctx, scene.images);
}

inline bool triangle_light_sample(const Scene& scene, const Light& l, const Vec3& p, Vec2 u, float time,
                                  LightSample* s) {
  Vec3 p0, p1, p2;
  float area;
  Vec3 ng = triangle_light_corners(scene, l, time, &p0, &p1, &p2, &area);
  Vec2 b = sample_triangle(u);
  Vec3 q = p0 * (1 - b.x - b.y) + p1 * b.x + p2 * b.y;
  float d2;
  if (!aim_at(p, q, s, &d2)) return false;
  float cos_l = std::abs(dot(ng, s->wi));
  if (!(cos_l > 0)) return false;
  s->pdf = d2 / (area * cos_l);
  s->n = ng;
  s->on_surface = true;
  s->radiance = triangle_light_radiance(scene, triangle_light_surface(scene, l, b, time), -s->wi);
  s->delta = false;
  return !is_black(s->radiance);
}

// Solid-angle density of triangle_light_sample for direction wi, the triangle at distance t.
inline float triangle_light_pdf(const Scene& scene, const Light& l, const Vec3& wi, float t, float time) {
  Vec3 p0, p1, p2;
  float area;
  Vec3 ng = triangle_light_corners(scene, l, time, &p0, &p1, &p2, &area);
  float cos_l = std::abs(dot(ng, wi));
  return cos_l > 0 ? t * t / (area * cos_l) : 0;
}

// Both sides emit: the first half of ud.x picks the side, cosine-weighted directions on it.
inline bool triangle_light_sample_emission(const Scene& scene, const Light& l, Vec2 up, Vec2 ud, float time,
                                           EmissionSample* e) {
  Vec3 p0, p1, p2;
  float area;
  Vec3 ng = triangle_light_corners(scene, l, time, &p0, &p1, &p2, &area);
  Vec2 b = sample_triangle(up);
  float ux = ud.x < 0.5f ? 2 * ud.x : 2 * ud.x - 1;
  Vec3 n = ud.x < 0.5f ? ng : -ng;
  Vec3 local = sample_cosine_hemisphere({std::min(ux, kOneMinusEpsilon), ud.y});
  SurfacePoint sp = triangle_light_surface(scene, l, b, time);
  e->ray.o = sp.p;
  e->ray.d = Frame(n).to_world(local);
  e->n = n;
  e->pdf_pos = 1 / area;
  e->pdf_dir = 0.5f * cosine_hemisphere_pdf(local.z);
  e->radiance = triangle_light_radiance(scene, sp, e->ray.d);
  return e->pdf_dir > 0 && !is_black(e->radiance);
}

// n: the normal of the side the direction leaves from.
inline void triangle_light_pdf_emission(const Scene& scene, const Light& l, const Vec3& n, const Vec3& dir, float time,
                                        float* pdf_pos, float* pdf_dir) {
  Vec3 p0, p1, p2;
  float area = l.area;
  if (scene.geometry.has_motion()) triangle_light_corners(scene, l, time, &p0, &p1, &p2, &area);
  *pdf_pos = 1 / area;
  *pdf_dir = 0.5f * std::abs(dot(dir, n)) * kInvPi;
}

}  // namespace lt
