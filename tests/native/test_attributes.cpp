// Mesh attributes and the attribute opcodes of the inputs family (shading/inputs.*): corner
// interpolation, what the Attribute node gives for each component count and for a missing
// attribute (Cycles' svm_node_attr), Normal Map and Object Info at hand-computed points, and the
// ABI's refusals of bad attribute ids, lengths and values.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "geometry/geometry.h"
#include "geometry_builders.h"
#include "lantern/lantern.h"
#include "scene_builders.h"
#include "shading/bsdf.h"
#include "shading/inputs.h"
#include "shading/material.h"

namespace lt {
namespace {

Mesh one_triangle() {
  Mesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  m.indices = {0, 1, 2};
  return m;
}

MeshAttribute attr(int id, int n, std::vector<float> v) {
  MeshAttribute a;
  a.id = id;
  a.components = n;
  a.values = std::move(v);
  return a;
}

struct Bench {
  std::vector<float> regs = std::vector<float>(64, -999.0f);
  std::vector<float> pool;
  ShadingContext ctx;
  // Runs one instruction of the inputs family with outputs at registers 0.., inputs after them.
  std::vector<float> exec(uint32_t op, const std::vector<std::vector<float>>& inputs,
                          const std::vector<uint32_t>& params) {
    const OpSignature* sig = inputs_family_signature(op);
    EXPECT_NE(sig, nullptr);
    std::vector<uint32_t> out, in;
    uint32_t next = 0;
    for (const char* s = sig->out; *s; ++s) {
      const uint32_t n = *s == 'v' ? 3 : 1;
      out.push_back(n << 24 | next);
      next += n;
    }
    const uint32_t total = next;
    for (const auto& v : inputs) {
      in.push_back(uint32_t(v.size()) << 24 | next);
      for (float x : v) regs[next++] = x;
    }
    EXPECT_EQ(std::string(sig->params).size(), params.size());
    Instr ins{op, int(in.size()), int(out.size()), int(params.size()), in.data(), out.data(), params.data()};
    Machine m{};
    m.r = regs.data();
    m.k = pool.data();
    m.ctx = &ctx;
    exec_inputs_family(ins, m);
    return std::vector<float>(regs.begin(), regs.begin() + total);
  }
};

TEST(Attributes, InterpolatesCornerValues) {
  Mesh m = one_triangle();
  m.attributes.push_back(attr(3, 2, {0, 0, 1, 0, 0, 1}));
  float v[4];
  int n = -1;
  ASSERT_TRUE(m.interpolate(3, 0, 0.25f, 0.5f, v, &n));
  EXPECT_EQ(n, 2);
  EXPECT_FLOAT_EQ(v[0], 0.25f);
  EXPECT_FLOAT_EQ(v[1], 0.5f);
  EXPECT_FLOAT_EQ(v[2], 0.0f);
  EXPECT_FLOAT_EQ(v[3], 1.0f);
  EXPECT_FALSE(m.interpolate(4, 0, 0.25f, 0.5f, v, &n));
  EXPECT_EQ(n, 0);
}

TEST(Attributes, DroppedTrianglesTakeTheirCornersAlong) {
  Mesh m = one_triangle();
  m.positions.push_back(Vec3(2, 0, 0));
  m.indices = {0, 1, 1, 0, 1, 2};  // the first triangle has no area
  m.attributes.push_back(attr(0, 1, {9, 9, 9, 1, 2, 3}));
  Geometry g;
  std::vector<std::string> warnings;
  const int id = g.add_mesh(std::move(m), warnings);
  const Mesh& kept = g.mesh(id);
  ASSERT_EQ(kept.triangle_count(), 1u);
  ASSERT_EQ(kept.attributes[0].values, (std::vector<float>{1, 2, 3}));
}

TEST(Attributes, AttributeNodeOutputsByComponentCount) {
  Mesh m = one_triangle();
  m.attributes.push_back(attr(1, 1, {1, 2, 3}));
  m.attributes.push_back(attr(2, 2, {0.5f, 0.25f, 0.5f, 0.25f, 0.5f, 0.25f}));
  m.attributes.push_back(attr(3, 3, {0.1f, 0.2f, 0.6f, 0.1f, 0.2f, 0.6f, 0.1f, 0.2f, 0.6f}));
  m.attributes.push_back(attr(4, 4, {0.3f, 0.6f, 0.9f, 0.5f, 0.3f, 0.6f, 0.9f, 0.5f, 0.3f, 0.6f, 0.9f, 0.5f}));
  Instance inst;
  Bench r;
  r.ctx.mesh = &m;
  r.ctx.instance = &inst;
  r.ctx.primitive = 0;
  r.ctx.bary = {0.5f, 0.25f};  // corner weights 0.25, 0.5, 0.25
  auto o = r.exec(kOpAttribute, {}, {1, 0, 0});
  EXPECT_FLOAT_EQ(o[0], 2.0f);
  EXPECT_FLOAT_EQ(o[2], 2.0f);
  EXPECT_FLOAT_EQ(o[3], 2.0f);
  EXPECT_FLOAT_EQ(o[4], 1.0f);
  o = r.exec(kOpAttribute, {}, {2, 0, 0});
  EXPECT_FLOAT_EQ(o[1], 0.25f);
  EXPECT_FLOAT_EQ(o[2], 0.0f);
  EXPECT_FLOAT_EQ(o[3], 0.5f);  // Fac of a UV map: u
  o = r.exec(kOpAttribute, {}, {3, 0, 0});
  EXPECT_NEAR(o[3], 0.3f, 1e-6f);  // average
  EXPECT_FLOAT_EQ(o[4], 1.0f);
  o = r.exec(kOpAttribute, {}, {4, 2, 0});
  EXPECT_NEAR(o[3], 0.6f, 1e-6f);
  EXPECT_FLOAT_EQ(o[4], 0.5f);  // alpha
  // Missing: 0, alpha 1 for the Attribute node, 0 for Color Attribute (svm_node_vertex_color).
  o = r.exec(kOpAttribute, {}, {7, 0, 0});
  EXPECT_EQ(o, (std::vector<float>{0, 0, 0, 0, 1}));
  o = r.exec(kOpAttribute, {}, {7, 2, 0});
  EXPECT_EQ(o, (std::vector<float>{0, 0, 0, 0, 0}));
  // Object values.
  inst.attributes.push_back({5, {0.2f, 0.4f, 0.6f, 0.8f}});
  o = r.exec(kOpAttribute, {}, {5, 1, 0});
  EXPECT_FLOAT_EQ(o[1], 0.4f);
  EXPECT_FLOAT_EQ(o[4], 0.8f);
}

// A 2 x 2 x 2 box at the origin (flat: face normals), as one instance.
struct BevelBox {
  Geometry g;
  BevelBox() { lt_test::add_lone_instance(g, lt_test::box_mesh(Vec3(-1.0f), Vec3(1.0f))); }
  // The shading point a ray straight down meets at (x, y) on the top face.
  ShadingContext top(float x, float y) const {
    Ray r;
    r.o = Vec3(x, y, 3);
    r.d = Vec3(0, 0, -1);
    r.tmin = 0;
    r.tmax = 10;
    Hit hit;
    EXPECT_TRUE(g.intersect(r, 31u, &hit));
    ShadingContext c = shading_context(g, g.surface(hit), r.d, hit.t);
    c.geometry = &g;
    c.trace_seed = 12345;
    return c;
  }
};

TEST(Bevel, NormalOfTheSurfaceWithinTheRadius) {
  BevelBox box;
  Bench r;
  r.ctx = box.top(0, 0);
  const std::vector<float> unlinked = {0, 0, 0};
  // Far from the edges every hit is the top face's: its normal exactly.
  EXPECT_EQ(r.exec(kOpBevel, {{0.3f}, unlinked}, {64}), (std::vector<float>{0, 0, 1}));
  // On the edge at x = 1 the faces x and z weigh alike (Cycles' estimator, by symmetry): 45
  // degrees, up to the noise of 1024 samples.
  r.ctx = box.top(0.999f, 0.0f);
  std::vector<float> n = r.exec(kOpBevel, {{0.3f}, unlinked}, {1024});
  EXPECT_NEAR(n[0], std::sqrt(0.5f), 0.03f);
  EXPECT_NEAR(n[1], 0.0f, 0.03f);
  EXPECT_NEAR(n[2], std::sqrt(0.5f), 0.03f);
  EXPECT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0f, 1e-5f);
  // Inside the radius the side face pulls less the further from it.
  r.ctx = box.top(0.85f, 0.0f);
  const std::vector<float> near = r.exec(kOpBevel, {{0.3f}, unlinked}, {1024});
  EXPECT_GT(near[0], 0.05f);
  EXPECT_LT(near[0], n[0] - 0.1f);
  // A linked Normal keeps the bevel's change: ref + (bevel - N), normalised.
  r.ctx = box.top(0.999f, 0.0f);
  const std::vector<float> ref = {0.0f, 0.6f, 0.8f};
  std::vector<float> kept = r.exec(kOpBevel, {{0.3f}, ref}, {1024});
  const Vec3 expected = normalize(Vec3(ref[0], ref[1], ref[2]) + Vec3(n[0], n[1], n[2]) - Vec3(0, 0, 1));
  EXPECT_NEAR(kept[0], expected.x, 1e-5f);
  EXPECT_NEAR(kept[1], expected.y, 1e-5f);
  EXPECT_NEAR(kept[2], expected.z, 1e-5f);
}

TEST(Bevel, TracesNothingWhereCyclesDoesNot) {
  BevelBox box;
  Bench r;
  const std::vector<float> unlinked = {0, 0, 0}, ref = {0.0f, 0.6f, 0.8f};
  r.ctx = box.top(0.999f, 0.0f);
  r.ctx.min_ray_pdf = 7.9f;  // a blurry bounce before: the shading normal, a linked Normal kept
  EXPECT_EQ(r.exec(kOpBevel, {{0.3f}, unlinked}, {64}), (std::vector<float>{0, 0, 1}));
  EXPECT_EQ(r.exec(kOpBevel, {{0.3f}, ref}, {64}), ref);
  r.ctx.min_ray_pdf = INFINITY;
  EXPECT_EQ(r.exec(kOpBevel, {{0.0f}, unlinked}, {64}), (std::vector<float>{0, 0, 1}));  // no radius
  r.ctx.geometry = nullptr;  // light samples and shadow rays: the shading normal, unblended
  EXPECT_EQ(r.exec(kOpBevel, {{0.3f}, ref}, {64}), (std::vector<float>{0, 0, 1}));
}

TEST(Attributes, NormalMapInTangentSpace) {
  Mesh m = one_triangle();
  // Tangent +X, sign +1 at every corner; flat: the normal is +Z.
  m.attributes.push_back(attr(0, 4, {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1}));
  Instance inst;
  inst.xf = Transform();
  inst.normal_rows[0] = Vec3(1, 0, 0);
  inst.normal_rows[1] = Vec3(0, 1, 0);
  inst.normal_rows[2] = Vec3(0, 0, 1);
  Bench r;
  r.ctx.mesh = &m;
  r.ctx.instance = &inst;
  r.ctx.primitive = 0;
  r.ctx.pose = Pose::of(inst.xf);  // the normal map reads the instance's pose at the ray's time
  r.ctx.N = r.ctx.Ng = Vec3(0, 0, 1);
  // (1, 0.5, 0.5) -> (1, 0, 0) in tangent space: the tangent.
  auto o = r.exec(kOpNormalMap, {{1.0f}, {1.0f, 0.5f, 0.5f}}, {0, 0});
  EXPECT_NEAR(o[0], 1.0f, 1e-6f);
  EXPECT_NEAR(o[2], 0.0f, 1e-6f);
  // (0.5, 1, 0.5): the bitangent, sign x N x T = +Y.
  o = r.exec(kOpNormalMap, {{1.0f}, {0.5f, 1.0f, 0.5f}}, {0, 0});
  EXPECT_NEAR(o[1], 1.0f, 1e-6f);
  // Strength 0: the shading normal.
  o = r.exec(kOpNormalMap, {{0.0f}, {1.0f, 0.5f, 0.5f}}, {0, 0});
  EXPECT_NEAR(o[2], 1.0f, 1e-6f);
  // Seen from behind: the map's normal flipped, as Cycles.
  r.ctx.backfacing = true;
  r.ctx.N = r.ctx.Ng = Vec3(0, 0, -1);
  o = r.exec(kOpNormalMap, {{1.0f}, {0.5f, 0.5f, 1.0f}}, {0, 0});
  EXPECT_NEAR(o[2], -1.0f, 1e-6f);
  // No tangents: the unperturbed normal.
  r.ctx.backfacing = false;
  r.ctx.N = Vec3(0, 0, 1);
  o = r.exec(kOpNormalMap, {{1.0f}, {1.0f, 0.5f, 0.5f}}, {0, 9});
  EXPECT_NEAR(o[2], 1.0f, 1e-6f);
  // Blender world space flips Y and Z.
  o = r.exec(kOpNormalMap, {{1.0f}, {0.5f, 0.5f, 0.0f}}, {4, 0});
  EXPECT_NEAR(o[2], 1.0f, 1e-6f);
}

TEST(Attributes, TangentNode) {
  Mesh m = one_triangle();
  m.attributes.push_back(attr(2, 4, {1, 0, 0.5f, 1, 1, 0, 0.5f, 1, 1, 0, 0.5f, 1}));
  Instance inst;
  inst.normal_rows[0] = Vec3(1, 0, 0);
  inst.normal_rows[1] = Vec3(0, 1, 0);
  inst.normal_rows[2] = Vec3(0, 0, 1);
  Bench r;
  r.ctx.mesh = &m;
  r.ctx.instance = &inst;
  r.ctx.primitive = 0;
  r.ctx.pose = Pose::of(inst.xf);
  r.ctx.N = Vec3(0, 0, 1);
  // UV map: the stored tangent made normal to N.
  auto o = r.exec(kOpTangent, {}, {1, 2, 2});
  EXPECT_NEAR(o[0], 1.0f, 1e-6f);
  EXPECT_NEAR(o[2], 0.0f, 1e-6f);
  EXPECT_EQ(r.exec(kOpTangent, {}, {1, 2, 5}), (std::vector<float>{0, 0, 0}));  // no such map
  // Radial around Z at Generated (1, 0.5, 0.5): (-(y - 0.5), x - 0.5, 0) = +Y.
  r.ctx.generated = Vec3(1.0f, 0.5f, 0.5f);
  o = r.exec(kOpTangent, {}, {0, 2, 0});
  EXPECT_NEAR(o[1], 1.0f, 1e-6f);
  // Radial around X at Generated (0.5, 0.5, 1): (0, -(z - 0.5), y - 0.5) = -Y.
  r.ctx.generated = Vec3(0.5f, 0.5f, 1.0f);
  o = r.exec(kOpTangent, {}, {0, 0, 0});
  EXPECT_NEAR(o[1], -1.0f, 1e-6f);
}

// Cycles' bump_shadowing_term on diffuse lobes of a bumped normal: light grazing the smooth
// surface is darkened, glossy lobes and unbumped points are untouched.
TEST(Attributes, BumpShadowingTerm) {
  Bsdf b;
  Lobe d;
  d.type = LobeType::Diffuse;
  b.add(d);
  const Vec3 wo(0, 0, 1), wi = normalize(Vec3(-0.6f, 0, 0.8f));
  const float lambert = b.eval(wo, wi, nullptr).x;
  EXPECT_NEAR(lambert, 1 / kPi, 1e-6f);
  const Vec3 smooth(0.5f, 0, std::sqrt(0.75f));
  b.set_bump(smooth, false);
  const double g = dot(smooth, wi) / (wi.z * smooth.z);
  EXPECT_NEAR(b.eval(wo, wi, nullptr).x, lambert * (-g * g * g + g * g + g), 1e-6);
  // Light on the smooth side: full brightness; light transport reads the light along wo.
  EXPECT_NEAR(b.eval(wo, Vec3(0.6f, 0, 0.8f), nullptr).x, lambert, 1e-6f);
  b.set_bump(smooth, true);
  EXPECT_NEAR(b.eval(wi, wo, nullptr).x, lambert * (-g * g * g + g * g + g), 1e-6);
  b.clear();
  b.add(d);
  EXPECT_NEAR(b.eval(wo, wi, nullptr).x, lambert, 1e-6f);
}

TEST(Attributes, ObjectInfo) {
  Instance inst;
  inst.xf.m[3] = 1;
  inst.xf.m[7] = 2;
  inst.xf.m[11] = 3;
  inst.color[0] = 0.5f;
  inst.color[3] = 0.25f;
  inst.pass_index = 7;
  inst.random = 0.125f;
  Bench r;
  r.ctx.instance = &inst;
  auto o = r.exec(kOpObjectInfo, {}, {});
  EXPECT_EQ(o, (std::vector<float>{1, 2, 3, 0.5f, 1, 1, 0.25f, 7, 0.125f}));
}

}  // namespace
}  // namespace lt

using namespace lt_test;  // NOLINT

// The ABI: ids, lengths and values it refuses.
TEST(AttributesAbi, RefusesBadAttributes) {
  ScenePtr scene = new_scene();
  lt_scene* s = scene.get();
  MeshData tri;
  tri.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  tri.triangles = {0, 1, 2};
  std::vector<float> values = {0, 0, 1, 0, 0, 1};
  lt_mesh_attribute a{5, 2, values.data(), 6};
  auto add = [&](lt_mesh_attribute at, int count = 1) {
    lt_mesh_desc md = tri.desc();
    md.attributes = &at;
    md.attribute_count = count;
    int id = -1;
    return lt_scene_add_mesh(s, &md, &id);
  };
  EXPECT_EQ(add(a), LT_OK);
  lt_mesh_attribute bad = a;
  bad.id = -1;
  EXPECT_EQ(add(bad), LT_ERROR_INVALID_ARGUMENT);
  bad.id = 1 << 16;
  EXPECT_EQ(add(bad), LT_ERROR_INVALID_ARGUMENT);
  bad = a;
  bad.value_count = 5;
  EXPECT_EQ(add(bad), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(lt_last_error()).find("expected 6"), std::string::npos) << lt_last_error();
  bad = a;
  bad.components = 5;
  EXPECT_EQ(add(bad), LT_ERROR_INVALID_ARGUMENT);
  bad = a;
  bad.components = 0;
  bad.value_count = 0;
  EXPECT_EQ(add(bad), LT_ERROR_INVALID_ARGUMENT);
  bad = a;
  bad.values = nullptr;
  EXPECT_EQ(add(bad), LT_ERROR_INVALID_ARGUMENT);
  values[3] = NAN;
  EXPECT_EQ(add(a), LT_ERROR_INVALID_ARGUMENT);
  values[3] = INFINITY;
  EXPECT_EQ(add(a), LT_ERROR_INVALID_ARGUMENT);
  values[3] = 0;
  EXPECT_EQ(add(a, -1), LT_ERROR_INVALID_ARGUMENT);
  lt_mesh_attribute two[2] = {a, a};  // one id twice
  lt_mesh_desc md = tri.desc();
  md.attributes = two;
  md.attribute_count = 2;
  int id = -1;
  EXPECT_EQ(lt_scene_add_mesh(s, &md, &id), LT_ERROR_INVALID_ARGUMENT);
  md.attributes = nullptr;
  md.attribute_count = 1;
  EXPECT_EQ(lt_scene_add_mesh(s, &md, &id), LT_ERROR_INVALID_ARGUMENT);

  const int mesh = add_mesh(s, tri);
  lt_instance_desc inst{};
  inst.mesh = mesh;
  Xform xf = identity();
  std::copy(xf.begin(), xf.end(), inst.transform);
  inst.visibility = LT_VISIBLE_ALL;
  EXPECT_EQ(lt_scene_add_instance(s, &inst, &id), LT_OK);
  inst.color[1] = NAN;
  EXPECT_EQ(lt_scene_add_instance(s, &inst, &id), LT_ERROR_INVALID_ARGUMENT);
  inst.color[1] = 1;
  int ids[1] = {-3};
  float vals[4] = {1, 2, 3, 4};
  inst.attribute_ids = ids;
  inst.attribute_values = vals;
  inst.attribute_count = 1;
  EXPECT_EQ(lt_scene_add_instance(s, &inst, &id), LT_ERROR_INVALID_ARGUMENT);
  ids[0] = 3;
  vals[2] = INFINITY;
  EXPECT_EQ(lt_scene_add_instance(s, &inst, &id), LT_ERROR_INVALID_ARGUMENT);
  vals[2] = 3;
  EXPECT_EQ(lt_scene_add_instance(s, &inst, &id), LT_OK);
  inst.attribute_values = nullptr;
  EXPECT_EQ(lt_scene_add_instance(s, &inst, &id), LT_ERROR_INVALID_ARGUMENT);
}
