#include "shading/material.h"

#include "shading/shaders.h"

namespace lt {

Material::Material(Program program) : program_(std::move(program)) {
  emissive_ = program_.emission_estimate(&emission_estimate_);
  static const std::vector<std::unique_ptr<Image>> kNoImages;  // constant inputs read none
  constant_emission_ = emissive_ && program_.constant_emission(kNoImages, &constant_emitted_);
}

Material Material::default_surface() {
  auto v = [](uint32_t at) { return (3u << 24) | kConstBit | at; };
  auto f = [](uint32_t at) { return (1u << 24) | kConstBit | at; };
  // Diffuse(weight 1, default normal, colour 0.8, roughness 0).
  std::vector<float> k = {1, 1, 1, 0, 0, 0, 0.8f, 0.8f, 0.8f, 0};
  std::vector<uint32_t> code = {kOpDiffuse, 4, v(0), v(3), v(6), f(9)};
  return Material(Program(std::move(code), std::move(k), 0, 0));
}

ShadingContext shading_context(const Geometry& geometry, const SurfacePoint& sp, const Vec3& ray_d, float t) {
  ShadingContext c;
  c.backfacing = dot(ray_d, sp.ng) > 0;
  c.P = sp.p;
  c.Ng = c.backfacing ? -sp.ng : sp.ng;
  c.N = c.backfacing ? -sp.ns : sp.ns;
  c.I = -ray_d;
  c.uv = sp.uv;
  c.bary = sp.bary;
  c.object_P = sp.po;
  c.generated = sp.generated;
  const Instance& inst = geometry.instance(sp.instance);
  c.ray_length = t;
  c.mesh = &geometry.mesh(inst.mesh);
  c.instance = &inst;
  c.pose = geometry.pose(sp.instance, sp.time);
  set_shading_normal(&c, c.N);
  c.primitive = sp.primitive;
  c.curve = sp.curve;
  c.dpdu = sp.dpdu;
  // Cycles' primitive_tangent on curves: the curve's direction.
  if (sp.curve >= 0 && length_squared(sp.dpdu) > 0) c.set_normal_values(c.object_normal(), normalize(sp.dpdu));
  return c;
}

void set_shading_normal(ShadingContext* c, const Vec3& n) {
  c->N = n;
  c->derived_ = false;
}

void ShadingContext::derive_normal_values() const {
  object_N_ = normalize(pose.normal_to_object(N));
  // Cycles' primitive_tangent: a tangent around the generated Z axis, made normal to N.
  const Vec3 around = pose.normal_to_world(Vec3(-(generated.y - 0.5f), generated.x - 0.5f, 0.0f));
  const Vec3 tangent = cross(N, normalize(cross(around, N)));
  tangent_ = is_finite(tangent) ? tangent : Vec3(0.0f);
  derived_ = true;
}

Vec3 ShadingContext::object_normal() const {
  if (!derived_) derive_normal_values();
  return object_N_;
}

Vec3 ShadingContext::surface_tangent() const {
  if (!derived_) derive_normal_values();
  return tangent_;
}

void add_tracing(const Geometry& geometry, const SurfacePoint& sp, float min_ray_pdf, Sampler& sampler,
                 ShadingContext* ctx) {
  ctx->geometry = &geometry;
  ctx->min_ray_pdf = min_ray_pdf;
  ctx->time = sp.time;
  ctx->trace_seed = mix_u64(uint64_t(sampler.next_1d() * 0x1p32f) ^ 0x2545f4914f6cdd1dULL);
}

void add_differentials(const Geometry& geometry, const SurfacePoint& sp, float footprint, ShadingContext* ctx) {
  ctx->footprint = footprint;
  const Instance& inst = geometry.instance(sp.instance);
  const Mesh& mesh = geometry.mesh(inst.mesh);
  if (!mesh.is_triangles()) {
    // Curves and points: the footprint moves P in the tangent plane; the rest stays (no
    // parametrisation to differentiate; Cycles' curves have no dPdv either).
    Vec3 dirs[2];
    orthonormals(ctx->Ng, &dirs[0], &dirs[1]);
    for (int k = 0; k < 2; ++k)
      ctx->offset[k] = ShadingContext::Offset{dirs[k] * footprint, Vec3(0.0f), Vec3(0.0f), {0, 0}, {0, 0}};
    return;
  }
  // The triangle's edges in world space (at the point's time): a move dP in its plane changes the
  // barycentrics of vertices 1 and 2 by the solution of dP = e1 db1 + e2 db2 (least squares,
  // exact in the plane).
  Vec3 q[3];
  Vec3* w = ctx->corners;
  geometry.object_corners(mesh, sp.primitive, sp.time, &q[0], &q[1], &q[2]);
  geometry.triangle(sp.instance, sp.primitive, &w[0], &w[1], &w[2], sp.time);
  const Vec3 e1 = w[1] - w[0], e2 = w[2] - w[0];
  const float a11 = dot(e1, e1), a12 = dot(e1, e2), a22 = dot(e2, e2), det = a11 * a22 - a12 * a12;
  Vec3 dirs[2];
  orthonormals(ctx->Ng, &dirs[0], &dirs[1]);
  const Vec3 size = mesh.texspace_size * 2.0f;
  for (int k = 0; k < 2; ++k) {
    ShadingContext::Offset& o = ctx->offset[k];
    o.P = dirs[k] * footprint;
    const float r1 = dot(o.P, e1), r2 = dot(o.P, e2);
    o.bary = det != 0 ? Vec2{(a22 * r1 - a12 * r2) / det, (a11 * r2 - a12 * r1) / det} : Vec2{0, 0};
    // Object space: the same move through the inverse transform, i.e. barycentrics in object space.
    o.object_P = (q[1] - q[0]) * o.bary.x + (q[2] - q[0]) * o.bary.y;
    // Generated: the undisplaced triangle's (Mesh::undisplaced).
    o.generated = (undisplaced_point(mesh, sp.primitive, o.bary.x, o.bary.y, q[0] + o.object_P) -
                   undisplaced_point(mesh, sp.primitive, 0, 0, q[0])) /
                  size;
    if (!mesh.corner_uvs.empty()) {
      const Vec2* uv = &mesh.corner_uvs[3 * size_t(sp.primitive)];
      o.uv = {(uv[1].x - uv[0].x) * o.bary.x + (uv[2].x - uv[0].x) * o.bary.y,
              (uv[1].y - uv[0].y) * o.bary.x + (uv[2].y - uv[0].y) * o.bary.y};
    } else {
      o.uv = {0, 0};
    }
  }
}

}  // namespace lt
