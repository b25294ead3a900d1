// Light shapes: chi-square tests of LightSet::sample against LightSet::pdf through the generic
// tester (chi2.h), one adapter for all lights. The pdf adapter finds the distance to the light
// along a direction the way the integrator does (lamp intersection, scene intersection for
// emissive triangles, none for sun and world) and returns 0 where the direction misses it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "chi2.h"
#include "program_builder.h"
#include "scene/lights/area.h"
#include "scene/lights/triangle.h"
#include "scene/scene.h"

namespace lt {
namespace {

using test::Chi2Options;
using test::Chi2Result;
using test::DirectionSample;

struct LightCase {
  std::string name;
  std::unique_ptr<Scene> scene;
  int light = 0;
  Vec3 p;              // the shaded point
  Vec3 pole{0, 0, 1};  // bins concentrate around this axis (towards small lights)
  double power = 1;
};

Light area_light(Vec3 position, Vec3 normal_dir, Vec3 u, Vec3 v, AreaShape shape) {
  Light l;
  l.type = LightType::Area;
  l.power = Spectrum(100.0f);
  l.position = position;
  l.direction = normalize(normal_dir);
  l.axis_u = u;
  l.axis_v = v;
  l.shape = shape;
  float uv = length(cross(u, v));
  l.area = shape == AreaShape::Rectangle ? 4 * uv : kPi * uv;
  return l;
}

std::unique_ptr<Scene> lamp_scene(const Light& l) {
  auto s = std::make_unique<Scene>();
  s->lamp_lights.push_back(l);
  s->commit();
  return s;
}

LightCase lamp_case(std::string name, const Light& l, Vec3 p, double power) {
  LightCase c;
  c.name = std::move(name);
  c.scene = lamp_scene(l);
  c.p = p;
  c.pole = normalize(l.position - p);
  c.power = power;
  return c;
}

std::vector<LightCase> make_cases() {
  std::vector<LightCase> cs;
  // Area lights: rectangle and ellipse, facing the point and tilted, near and far.
  cs.push_back(lamp_case(
      "area_rect_facing",
      area_light(Vec3(0.3f, -0.2f, 2), Vec3(0, 0, -1), Vec3(0.5f, 0, 0), Vec3(0, 0.8f, 0), AreaShape::Rectangle),
      Vec3(0, 0, 0), 1.5));
  {
    Vec3 n = normalize(Vec3(0.3f, 0.2f, -1));
    Frame f(n);
    cs.push_back(lamp_case("area_rect_tilted_near",
                           area_light(Vec3(-0.2f, 0.1f, 0.6f), n, f.s * 0.7f, f.t * 0.4f, AreaShape::Rectangle),
                           Vec3(0.1f, 0, 0), 1));
    Vec3 n2 = normalize(Vec3(-0.6f, -0.3f, -1));
    Frame f2(n2);
    cs.push_back(lamp_case("area_ellipse_tilted",
                           area_light(Vec3(1, 0.5f, 1.5f), n2, f2.s * 0.3f, f2.t * 0.6f, AreaShape::Ellipse),
                           Vec3(0, 0, 0), 2));
  }
  // Rectangles sampled by solid angle: a large one seen almost edge-on from close to its plane;
  // one with a Spread of 60 degrees, sampled only where its light reaches the point; one so small
  // and far (4e-8 sr) that it is sampled by area.
  cs.push_back(
      lamp_case("area_rect_grazing",
                area_light(Vec3(0, 0, 0.05f), Vec3(0, 0, -1), Vec3(1, 0, 0), Vec3(0, 1.2f, 0), AreaShape::Rectangle),
                Vec3(1.5f, 0.3f, 0), 1));
  {
    Light l = area_light(Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, 0, 0), Vec3(0, 0.8f, 0), AreaShape::Rectangle);
    set_area_spread(&l, 60 * kPi / 180);
    cs.push_back(lamp_case("area_rect_spread", l, Vec3(0.6f, 0.3f, 0), 1.5));
    cs.back().pole = Vec3(0, 0, 1);
  }
  cs.push_back(lamp_case(
      "area_rect_far",
      area_light(Vec3(3, -2, 100), Vec3(0, 0, -1), Vec3(0.01f, 0, 0), Vec3(0, 0.01f, 0), AreaShape::Rectangle),
      Vec3(0, 0, 0), 4));
  // Point and spot lights with a radius: a disk facing the point.
  {
    Light l;
    l.type = LightType::Point;
    l.power = Spectrum(1000.0f);
    l.position = Vec3(0.2f, 0.1f, 1.5f);
    l.radius = 0.3f;
    cs.push_back(lamp_case("point_radius", l, Vec3(0, 0, 0), 2));
    l.position = Vec3(0, 0, 0.35f);
    cs.push_back(lamp_case("point_radius_close", l, Vec3(0, 0, 0), 1));
    l.type = LightType::Spot;
    l.position = Vec3(1, 0.5f, 1);
    l.direction = normalize(Vec3(-1, -0.5f, -1));
    l.cos_half_angle = std::cos(0.5f);
    l.smooth = 0.1f;
    l.radius = 0.2f;
    cs.push_back(lamp_case("spot_radius", l, Vec3(0, 0, 0), 2));
  }
  // Sun with an angular diameter of 10 degrees.
  {
    Light l;
    l.type = LightType::Sun;
    l.power = Spectrum(3.0f);
    l.direction = normalize(Vec3(0.2f, 0.1f, -1));
    float half = 5 * kPi / 180;
    l.tan_half_angle = std::tan(half);
    l.cos_half_angle_sun = std::cos(half);
    LightCase c;
    c.name = "sun_10deg";
    c.scene = lamp_scene(l);
    c.pole = -l.direction;
    c.power = 3;
    cs.push_back(std::move(c));
  }
  // World: uniform colour, and an environment image with a hot spot, rotated.
  {
    LightCase c;
    c.name = "world_uniform";
    c.scene = std::make_unique<Scene>();
    c.scene->world.set_color(Spectrum(0.5f));
    c.scene->world_set = true;
    c.scene->commit();
    c.light = c.scene->lights.world_light();
    cs.push_back(std::move(c));
  }
  {
    LightCase c;
    c.name = "world_image";
    c.scene = std::make_unique<Scene>();
    const int w = 16, h = 8;
    std::vector<float> px(size_t(w) * h * 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int k = 0; k < 3; ++k)
          px[(size_t(y) * w + x) * 3 + k] = 0.05f + 0.1f * ((x + y) % 3) + (x == 5 && y == 6 ? 20.0f : 0.0f);
    c.scene->images.push_back(
        std::make_unique<Image>(w, h, 3, px.data(), false, Interpolation::Linear, Extension::Repeat));
    // Background(Environment Texture(the direction rotated 0.3 about Z)).
    ShaderCode p;
    const float cr = std::cos(0.3f), sr = std::sin(0.3f);
    const uint32_t object = p.tex_coord({cr, -sr, 0, 0, sr, cr, 0, 0, 0, 0, 1, 0})[3];
    p.emit_color(p.one(), p.environment(object, 0));
    c.scene->world.set_program(std::make_shared<const Program>(p.code, p.k, p.registers, 1), 0);
    c.scene->world_set = true;
    c.scene->commit();
    c.light = c.scene->lights.world_light();
    // Bins around a tilted pole: the map's cell edges (equirectangular) then cross them, which the
    // adaptive quadrature of the expected counts handles, rather than lying exactly on bin edges.
    c.pole = normalize(Vec3(0.1f, 0.2f, 1));
    cs.push_back(std::move(c));
  }
  {
    // A procedural world: its map (32 x 16) decides the pdf, the program the radiance.
    LightCase c;
    c.name = "world_procedural";
    c.scene = std::make_unique<Scene>();
    const ShaderCode p = noise_world();
    c.scene->world.set_program(std::make_shared<const Program>(p.code, p.k, p.registers, 0), 32);
    c.scene->world_set = true;
    c.scene->commit();
    c.light = c.scene->lights.world_light();
    c.pole = normalize(Vec3(0.1f, 0.2f, 1));
    cs.push_back(std::move(c));
  }
  // Emissive triangles (mesh lights): seen from closer to its plane than its longest edge, sampled
  // by solid angle (facing, and almost edge-on), else by area (far).
  auto triangle_case = [&](std::string name, Vec3 a, Vec3 b, Vec3 c, Vec3 p, double power) {
    LightCase lc;
    lc.name = std::move(name);
    lc.scene = std::make_unique<Scene>();
    ShaderCode e;
    e.emission(e.one(), {1, 1, 1}, 5);
    lc.scene->materials.push_back(Material(Program(e.code, e.k, e.registers, 0)));
    Mesh m;
    m.positions = {a, b, c};
    m.indices = {0, 1, 2};
    int mesh = lc.scene->geometry.add_mesh(std::move(m), lc.scene->warnings);
    Instance inst;
    inst.mesh = mesh;
    inst.materials = {0};
    lc.scene->geometry.add_instance(inst, lc.scene->warnings);
    lc.scene->commit();
    lc.light = lc.scene->lights.triangle_light(0, 0);
    lc.p = p;
    lc.pole = normalize((a + b + c) * (1.0f / 3) - p);
    lc.power = power;
    cs.push_back(std::move(lc));
  };
  triangle_case("triangle", Vec3(-0.5f, -0.3f, 1.2f), Vec3(0.8f, 0.1f, 1.0f), Vec3(0.1f, 0.9f, 1.6f), Vec3(0.0f), 1.5);
  triangle_case("triangle_grazing", Vec3(-1, -1, 0.04f), Vec3(2, -0.5f, 0.05f), Vec3(0.5f, 2, 0.06f),
                Vec3(0.3f, 0.2f, 0), 1);
  triangle_case("triangle_far", Vec3(-0.5f, -0.3f, 4.2f), Vec3(0.8f, 0.1f, 4.0f), Vec3(0.1f, 0.9f, 4.6f), Vec3(0.0f),
                3);
  return cs;
}

const std::vector<LightCase>& cases() {
  static const std::vector<LightCase> cs = make_cases();
  return cs;
}

// Distance along wi from p to the light, or -1 if the direction misses it.
float distance_to_light(const Scene& s, int i, const Vec3& p, const Vec3& wi) {
  const Light& l = s.lights.light(i);
  if (l.infinite()) return INFINITY;
  Ray r;
  r.o = p;
  r.d = wi;
  if (l.type == LightType::Triangle) {
    Hit h;
    if (!s.geometry.intersect(r, 31u, &h) || h.instance != l.instance || h.primitive != l.primitive) return -1;
    return h.t;
  }
  float t = -1;
  s.lights.intersect_lamps(r, p, 31u, [&](const LightSet::LampHit& h) {
    if (h.light == i) t = h.t;
  });
  return t;
}

class LightChi2 : public ::testing::TestWithParam<int> {};

TEST_P(LightChi2, SamplesFollowPdf) {
  const LightCase& c = cases()[GetParam()];
  ASSERT_GE(c.light, 0);
  const Scene& s = *c.scene;
  const Light& light = s.lights.light(c.light);
  ASSERT_FALSE(light.delta());
  auto sampler = [&](Sampler& rng, DirectionSample* out) {
    LightSample ls;
    if (!s.lights.sample(s, c.light, c.p, rng.next_2d(), &ls)) return false;
    out->dir = ls.wi;
    out->pdf = ls.pdf;
    return !ls.delta;
  };
  auto pdf = [&](const Vec3& wi) {
    float t = distance_to_light(s, c.light, c.p, wi);
    return t > 0 ? double(s.lights.pdf(s, c.light, c.p, wi, t)) : 0.0;
  };
  Chi2Options o;
  o.name = c.name;
  o.pole = c.pole;
  o.theta_power = c.power;
  o.seed = 5000u + uint32_t(GetParam());
  o.expected_integral = 1;  // every light shape's sampling covers exactly its solid angle
  // The pdf adapter recomputes the distance by intersection, the sampler from the sampled point.
  o.pdf_rel_tolerance = 2e-3;
  Chi2Result r = test::chi2_test(sampler, pdf, o);
  EXPECT_TRUE(r.chi2_ok) << r.summary;
  EXPECT_TRUE(r.integral_ok) << r.summary;
  EXPECT_TRUE(r.pdf_ok) << r.summary;
  RecordProperty("summary", r.summary);
}

INSTANTIATE_TEST_SUITE_P(AllLights, LightChi2, ::testing::Range(0, int(cases().size())),
                         [](const ::testing::TestParamInfo<int>& param_info) {
                           return cases()[param_info.param].name;
                         });

// Delta lights: the exact direction, pdf 1, and no density for MIS.
TEST(DeltaLights, PointAndSun) {
  Light pt;
  pt.type = LightType::Point;
  pt.power = Spectrum(1000.0f);
  pt.position = Vec3(0, 0, 1);
  auto s = lamp_scene(pt);
  LightSample ls;
  ASSERT_TRUE(s->lights.sample(*s, 0, Vec3(0, 0, 0), Vec2{0.3f, 0.7f}, &ls));
  EXPECT_TRUE(ls.delta);
  EXPECT_EQ(ls.pdf, 1.0f);
  EXPECT_NEAR(length(ls.wi - Vec3(0, 0, 1)), 0, 1e-6f);
  EXPECT_NEAR(ls.distance, 1, 1e-6f);
  EXPECT_NEAR(ls.radiance.x, 1000 / (4 * kPi), 1e-2f);  // intensity P / (4 pi) at 1 m
  EXPECT_EQ(s->lights.pdf(*s, 0, Vec3(0, 0, 0), ls.wi, 1), 0.0f);

  Light sun;
  sun.type = LightType::Sun;
  sun.power = Spectrum(3.0f);
  sun.direction = normalize(Vec3(1, 0, -1));
  auto s2 = lamp_scene(sun);
  ASSERT_TRUE(s2->lights.sample(*s2, 0, Vec3(0, 0, 0), Vec2{0.3f, 0.7f}, &ls));
  EXPECT_TRUE(ls.delta);
  EXPECT_NEAR(length(ls.wi + sun.direction), 0, 1e-6f);
  EXPECT_EQ(s2->lights.pdf(*s2, 0, Vec3(0, 0, 0), ls.wi, INFINITY), 0.0f);
}

}  // namespace
}  // namespace lt

namespace lt {
namespace {

// An area lamp's Spread (Cycles 3.4's slat model) keeps its power: the spread factor weighted by
// cos a over the hemisphere integrates to pi (the lamp without a spread), by the midpoint rule;
// it is 1 without a spread and 0 beyond the cut-off angle spread / 2.
TEST(AreaSpread, KeepsThePowerAndCutsOffAtHalfTheSpread) {
  for (float degrees : {0.5f, 10.0f, 40.0f, 90.0f, 150.0f, 179.0f}) {
    Light l;
    set_area_spread(&l, degrees * kPi / 180.0f);
    const int n = 400000;
    double integral = 0;
    for (int i = 0; i < n; ++i) {
      const double a = (i + 0.5) * (0.5 * kPi / n);
      integral += area_spread_factor(l, float(std::cos(a))) * std::cos(a) * std::sin(a);
    }
    integral *= 2 * kPi * (0.5 * kPi / n);
    EXPECT_NEAR(integral / kPi, 1.0, 2e-3) << degrees << " degrees";
    const float cut = 0.5f * std::max(degrees, 1.0f) * kPi / 180.0f;  // Cycles' minimum: 1 degree
    EXPECT_EQ(area_spread_factor(l, std::cos(cut * 1.01f)), 0.0f) << degrees;
    EXPECT_GT(area_spread_factor(l, std::cos(cut * 0.99f)), 0.0f) << degrees;
  }
  Light none;
  set_area_spread(&none, kPi);
  EXPECT_EQ(area_spread_factor(none, 0.3f), 1.0f);
  set_area_spread(&none, 0.0f);  // a descriptor that does not say
  EXPECT_EQ(area_spread_factor(none, 0.01f), 1.0f);
}

}  // namespace
}  // namespace lt

namespace lt {
namespace {

// A mesh light whose material emits a constant keeps that radiance in its light, and a light sample
// returns it without running the program: the same as running it. One whose colour a node decides
// (Texture Coordinate's Generated) is not constant and runs the program per sample.
TEST(TriangleLight, ConstantEmissionEqualsRunningTheProgram) {
  for (bool constant : {true, false}) {
    ShaderCode e;
    if (constant) {
      e.emission(e.one(), {1, 0.5f, 0.25f}, 5);
    } else {
      e.emit_color(e.one(), e.tex_coord()[0], 5);
    }
    Material m(Program(e.code, e.k, e.registers, 0));
    Spectrum emitted;
    ASSERT_EQ(m.constant_emission(&emitted), constant);
    Scene s;
    s.materials.push_back(std::move(m));
    Mesh mesh;
    mesh.positions = {Vec3(-0.5f, -0.3f, 1.2f), Vec3(0.8f, 0.1f, 1.0f), Vec3(0.1f, 0.9f, 1.6f)};
    mesh.indices = {0, 1, 2};
    Instance inst;
    inst.mesh = s.geometry.add_mesh(std::move(mesh), s.warnings);
    inst.materials = {0};
    s.geometry.add_instance(inst, s.warnings);
    s.commit();
    const int i = s.lights.triangle_light(0, 0);
    ASSERT_GE(i, 0);
    Light run_it = s.lights.light(i);
    EXPECT_EQ(run_it.constant_emission, constant);
    run_it.constant_emission = false;
    for (Vec2 u : {Vec2{0.2f, 0.3f}, Vec2{0.7f, 0.6f}, Vec2{0.5f, 0.05f}}) {
      LightSample a, b;
      ASSERT_TRUE(s.lights.sample(s, i, Vec3(0.0f), u, &a));
      ASSERT_TRUE(triangle_light_sample(s, run_it, Vec3(0.0f), u, 0.5f, &b));
      for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(a.radiance[c], b.radiance[c]) << constant;
      if (constant) EXPECT_FLOAT_EQ(a.radiance[1], 2.5f);
    }
  }
}

}  // namespace
}  // namespace lt
