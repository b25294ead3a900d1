// Emissive triangles (Cycles' mesh lights): every triangle of an emissive material, two-sided,
// its radiance the material's emission at the point; next-event estimation samples it by solid
// angle or by area (triangle_light_solid_angle), light subpaths uniformly by area.
#pragma once

#include <algorithm>
#include <cmath>

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
  l->constant_emission = material.constant_emission(&l->emitted);
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

// The triangle (p0, p1, p2) as seen from p on the unit sphere, for sampling it uniformly in solid
// angle (Arvo 1995, "Stratified Sampling of Spherical Triangles", as Cycles 3.4's
// triangle_light_sample), in double: the solid angle is a difference of angles near pi.
struct SphericalTriangle {
  struct D3 {
    double x = 0, y = 0, z = 0;
  };
  D3 a, b, c;  // unit directions to the corners
  double alpha = 0, cos_alpha = 1, sin_alpha = 0, cos_ab = 1, solid_angle = 0;

  static D3 d3(const Vec3& v) { return {v.x, v.y, v.z}; }
  static double dot(const D3& u, const D3& v) { return u.x * v.x + u.y * v.y + u.z * v.z; }
  static D3 axpy(double s, const D3& u, const D3& v) { return {s * u.x + v.x, s * u.y + v.y, s * u.z + v.z}; }
  static D3 mul(double s, const D3& u) { return {s * u.x, s * u.y, s * u.z}; }
  static D3 cross(const D3& u, const D3& v) {
    return {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
  }
  static D3 unit(const D3& u) {
    const double l = std::sqrt(dot(u, u));
    return l > 0 ? D3{u.x / l, u.y / l, u.z / l} : D3{};
  }
  SphericalTriangle() = default;
  SphericalTriangle(const Vec3& p, const Vec3& p0, const Vec3& p1, const Vec3& p2) {
    const D3 o = d3(p);
    a = unit(axpy(-1, o, d3(p0)));
    b = unit(axpy(-1, o, d3(p1)));
    c = unit(axpy(-1, o, d3(p2)));
    // The angle at each corner is the one between the planes through it and its two neighbours.
    const D3 nab = unit(cross(a, b)), nac = unit(cross(a, c)), nbc = unit(cross(b, c));
    auto angle = [](double x) { return std::acos(std::clamp(x, -1.0, 1.0)); };
    cos_alpha = std::clamp(dot(nac, nab), -1.0, 1.0);
    alpha = angle(cos_alpha);
    sin_alpha = std::sin(alpha);
    cos_ab = dot(a, b);
    solid_angle = std::max(0.0, alpha + angle(-dot(nab, nbc)) + angle(dot(nac, nbc)) - kPi);
  }
  // The direction for u in [0, 1)^2: u.x picks the sub-triangle of area u.x * solid_angle, u.y
  // the point along its edge from b.
  Vec3 direction(Vec2 u) const {
    const double phi = u.x * solid_angle - alpha, s = std::sin(phi), t = std::cos(phi);
    const double uu = t - cos_alpha, vv = s + sin_alpha * cos_ab;
    const double det = (vv * s + uu * t) * sin_alpha;
    const double q = det != 0 ? std::clamp(((vv * t - uu * s) * cos_alpha - vv) / det, -1.0, 1.0) : 1.0;
    const D3 c1 = axpy(q, a, mul(std::sqrt(1 - q * q), unit(axpy(-dot(c, a), a, c))));
    const double z = 1 - u.y * (1 - dot(c1, b));
    const D3 d = axpy(z, b, mul(std::sqrt(std::max(0.0, 1 - z * z)), unit(axpy(-dot(c1, b), b, c1))));
    return Vec3(float(d.x), float(d.y), float(d.z));
  }
};

// Below this solid angle (sr) a triangle is sampled by area (the angles lose their precision).
constexpr double kMinTriangleSolidAngle = 1e-7;

// Cycles 3.4 samples a triangle by solid angle from points closer to its plane than its longest
// edge (the intent of its test, which divides the distance by twice the area), else by area. The
// solid angle when the first (and the spherical triangle in *st), else 0.
inline double triangle_light_solid_angle(const Vec3& p, const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& ng,
                                         SphericalTriangle* st = nullptr) {
  const float edge2 = std::max({length_squared(p1 - p0), length_squared(p2 - p0), length_squared(p2 - p1)});
  const float plane = dot(ng, p0 - p);
  if (!(edge2 > plane * plane)) return 0;
  const SphericalTriangle t(p, p0, p1, p2);
  if (st) *st = t;
  return t.solid_angle >= kMinTriangleSolidAngle ? t.solid_angle : 0;
}

inline bool triangle_light_sample(const Scene& scene, const Light& l, const Vec3& p, Vec2 u, float time,
                                  LightSample* s) {
  Vec3 p0, p1, p2;
  float area;
  Vec3 ng = triangle_light_corners(scene, l, time, &p0, &p1, &p2, &area);
  SphericalTriangle st;
  const double solid_angle = triangle_light_solid_angle(p, p0, p1, p2, ng, &st);
  Vec2 b;
  if (solid_angle > 0) {
    // The sampled direction's point on the triangle's plane, and its barycentrics.
    const Vec3 d = st.direction(u);
    const float t = dot(ng, p0 - p) / dot(ng, d);
    if (!(t > 0) || !std::isfinite(t)) return false;
    const Vec3 e1 = p1 - p0, e2 = p2 - p0, r = p + d * t - p0;
    const Vec3 c = cross(e1, e2);
    const float inv = 1 / dot(c, c);
    b = Vec2{std::clamp(dot(cross(r, e2), c) * inv, 0.0f, 1.0f), std::clamp(dot(cross(e1, r), c) * inv, 0.0f, 1.0f)};
    if (b.x + b.y > 1) b = Vec2{b.x / (b.x + b.y), b.y / (b.x + b.y)};
  } else {
    b = sample_triangle(u);
  }
  Vec3 q = p0 * (1 - b.x - b.y) + p1 * b.x + p2 * b.y;
  float d2;
  if (!aim_at(p, q, s, &d2)) return false;
  float cos_l = std::abs(dot(ng, s->wi));
  if (!(cos_l > 0)) return false;
  s->pdf = solid_angle > 0 ? float(1 / solid_angle) : d2 / (area * cos_l);
  s->n = ng;
  s->on_surface = true;
  s->radiance = l.constant_emission ? l.emitted
                                    : triangle_light_radiance(scene, triangle_light_surface(scene, l, b, time), -s->wi);
  s->delta = false;
  return !is_black(s->radiance);
}

// Solid-angle density of triangle_light_sample at p for direction wi, the triangle at distance t.
inline float triangle_light_pdf(const Scene& scene, const Light& l, const Vec3& p, const Vec3& wi, float t,
                                float time) {
  Vec3 p0, p1, p2;
  float area;
  Vec3 ng = triangle_light_corners(scene, l, time, &p0, &p1, &p2, &area);
  float cos_l = std::abs(dot(ng, wi));
  if (!(cos_l > 0)) return 0;
  const double solid_angle = triangle_light_solid_angle(p, p0, p1, p2, ng);
  return solid_angle > 0 ? float(1 / solid_angle) : t * t / (area * cos_l);
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
