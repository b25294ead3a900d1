#include "shading/material.h"

#include "shading/shaders.h"

namespace lt {

Material::Material(Program program) : program_(std::move(program)) {
  emissive_ = program_.emission_estimate(&emission_estimate_);
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
  c.object_N = normalize(inst.normal_to_object(c.N));
  // Cycles' primitive_tangent: a tangent around the generated Z axis, made normal to N.
  const Vec3 around = inst.normal_to_world(Vec3(-(c.generated.y - 0.5f), c.generated.x - 0.5f, 0.0f));
  const Vec3 tangent = cross(c.N, normalize(cross(around, c.N)));
  c.tangent = is_finite(tangent) ? tangent : Vec3(0.0f);
  c.ray_length = t;
  c.mesh = &geometry.mesh(inst.mesh);
  c.instance = &inst;
  c.primitive = sp.primitive;
  return c;
}

}  // namespace lt
