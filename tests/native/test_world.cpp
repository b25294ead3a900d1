// The world as a shader program (scene/lights/world.h): constant programs fold into a colour with no
// sampling map; otherwise the map's pdf follows the program's evaluation at the map's pixel
// centres; Light Path flags of escaped rays and of light sampling; the map's resolution rule; the
// Environment Texture's projections. Sampling against the pdf: test_light_sampling.cpp's
// world_image and world_procedural cases.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "integrators/path_state.h"
#include "lantern/lantern.h"
#include "program_builder.h"
#include "scene/scene.h"

namespace lt {
namespace {

// Background(colour 0.2 0.3 0.5 strength 2) mixed 0.25 with Background(1 1 1, 0.5): constant.
ShaderCode constant_world() {
  ShaderCode p;
  const std::vector<uint32_t> w = p.emit(kOpMixWeights, {p.one(), p.c1(0.25f)}, {3, 3});
  p.emission(w[0], {0.2f, 0.3f, 0.5f}, 2);
  p.emission(w[1], {1, 1, 1}, 0.5f);
  return p;
}

std::unique_ptr<Scene> world_scene(const ShaderCode& p, int map_resolution, int images = 0) {
  auto s = std::make_unique<Scene>();
  for (int i = 0; i < images; ++i) {
    std::vector<float> px(48 * 24 * 3, 0.5f);
    s->images.push_back(std::make_unique<Image>(48, 24, 3, px.data(), false, Interpolation::Linear, Extension::Repeat));
  }
  s->world.set_program(std::make_shared<const Program>(p.code, p.k, p.registers, s->images.size()), map_resolution);
  s->world_set = true;
  s->commit();
  return s;
}

TEST(World, ConstantProgramBuildsNoTable) {
  auto s = world_scene(constant_world(), 0);
  EXPECT_FALSE(s->world.has_map());
  EXPECT_EQ(s->world.map_width(), 0);
  ASSERT_GE(s->lights.world_light(), 0);
  const Spectrum expected = 0.75f * 2 * Spectrum(0.2f, 0.3f, 0.5f) + 0.25f * 0.5f * Spectrum(1.0f);
  for (Vec3 d : {Vec3(1, 0, 0), Vec3(0, 0, -1), normalize(Vec3(0.3f, -0.5f, 0.8f))}) {
    const Spectrum L = s->world.radiance(d);
    EXPECT_NEAR(L.x, expected.x, 1e-6f);
    EXPECT_NEAR(L.z, expected.z, 1e-6f);
    EXPECT_FLOAT_EQ(world_pdf(s->world, d), uniform_sphere_pdf());
  }
  // And through the ABI: a colour world has no table either.
  lt_scene* scene = nullptr;
  ASSERT_EQ(lt_scene_create(&scene), LT_OK);
  ShaderCode p = constant_world();
  const lt_shader_program prog = p.desc();
  ASSERT_EQ(lt_scene_set_world_program(scene, &prog, 0, LT_VISIBLE_CAMERA), LT_OK) << lt_last_error();
  ASSERT_EQ(lt_scene_commit(scene), LT_OK) << lt_last_error();
  lt_scene_stats stats;
  ASSERT_EQ(lt_scene_get_stats(scene, &stats), LT_OK);
  EXPECT_EQ(stats.world_map_width, 0u);
  lt_scene_destroy(scene);
}

TEST(World, MapPdfFollowsTheProgram) {
  auto s = world_scene(noise_world(), 64);
  ASSERT_TRUE(s->world.has_map());
  EXPECT_EQ(s->world.map_width(), 64);
  EXPECT_EQ(s->world.map_height(), 32);
  // At every pixel centre the pdf is average(|L|) over one constant: 2 pi^2 times the map's mean.
  double ratio0 = -1;
  float worst = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x) {
      const Vec3 d = equirectangular_to_direction({(x + 0.5f) / 64, (y + 0.5f) / 32});
      const float a = average(abs(s->world.radiance(d)));
      ASSERT_GT(a, 0);
      const double ratio = world_pdf(s->world, d) / a;
      if (ratio0 < 0) ratio0 = ratio;
      worst = std::max(worst, float(std::abs(ratio / ratio0 - 1)));
    }
  EXPECT_LT(worst, 2e-4f);
  // The radiance a sample returns is the program's at its exact direction (not the map's value).
  LightSample ls;
  ASSERT_TRUE(world_sample(s->world, Vec2{0.37f, 0.61f}, &ls));
  const Spectrum exact = s->world.radiance(ls.wi);
  EXPECT_EQ(ls.radiance.x, exact.x);
  EXPECT_FLOAT_EQ(ls.pdf, world_pdf(s->world, ls.wi));
}

TEST(World, LightPathSeesTheRay) {
  // Mix by Is Camera Ray: 0 a warm light (every ray but camera rays), 1 a grey backdrop.
  ShaderCode p;
  const uint32_t camera = p.emit(kOpLightPath, {}, {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1})[0];
  const std::vector<uint32_t> w = p.emit(kOpMixWeights, {p.one(), camera}, {3, 3});
  p.emission(w[0], {1.0f, 0.75f, 0.45f}, 2);
  p.emission(w[1], {0.5f, 0.5f, 0.5f}, 1);
  auto s = world_scene(p, 0);
  ASSERT_TRUE(s->world.has_map());
  EXPECT_EQ(s->world.map_width(), 1024);  // no Environment Texture: Cycles' default
  const Vec3 d = normalize(Vec3(0.2f, 0.4f, 0.7f));
  // Light sampling (Cycles' PATH_RAY_EMISSION): the light.
  EXPECT_NEAR(s->world.radiance(d).x, 2.0f, 1e-6f);
  LightSample ls;
  ASSERT_TRUE(world_sample(s->world, Vec2{0.5f, 0.5f}, &ls));
  EXPECT_NEAR(ls.radiance.y, 1.5f, 1e-6f);
  // An escaped camera ray: the backdrop; after a diffuse bounce: the light.
  Bounces b;
  ShadingContext c = world_context(d);
  describe_ray(b, kVisCamera, &c);
  EXPECT_NEAR(s->world.radiance(c).x, 0.5f, 1e-6f);
  b.add(BounceKind::Diffuse);
  c = world_context(d);
  describe_ray(b, kVisDiffuse, &c);
  EXPECT_NEAR(s->world.radiance(c).x, 2.0f, 1e-6f);
  EXPECT_NEAR(s->world.mean(), (2.0f + 1.5f + 0.9f) / 3, 1e-4f);
}

TEST(World, MapResolution) {
  ShaderCode p;
  p.emit_color(p.one(), p.environment(p.tex_coord()[0], 0));
  EXPECT_EQ(world_scene(p, 0, 1)->world.map_width(), 48);  // automatic: the image's size
  EXPECT_EQ(world_scene(p, 0, 1)->world.map_height(), 24);
  EXPECT_EQ(world_scene(p, 256, 1)->world.map_width(), 256);  // Cycles' sample_map_resolution
  EXPECT_EQ(world_scene(p, 256, 1)->world.map_height(), 128);
}

// An image whose linear lookup inside it returns (u, v, 0): a projection's coordinates read back.
TEST(World, EnvironmentProjections) {
  const int n = 64;
  std::vector<float> px(size_t(n) * n * 3);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      px[(size_t(y) * n + x) * 3] = (x + 0.5f) / n;
      px[(size_t(y) * n + x) * 3 + 1] = (y + 0.5f) / n;
      px[(size_t(y) * n + x) * 3 + 2] = 0;
    }
  std::vector<std::unique_ptr<Image>> images;
  images.push_back(std::make_unique<Image>(n, n, 3, px.data(), false, Interpolation::Linear, Extension::Extend));
  for (uint32_t projection : {0u, 1u}) {
    ShaderCode p;
    // The Normal output (object space N) as the vector: the test sets it directly.
    p.emit_color(p.one(), p.environment(p.tex_coord()[1], 0, projection));
    const Program prog(p.code, p.k, p.registers, 1);
    struct Case {
      Vec3 d;
      float u, v;
    };
    // Cycles' direction_to_equirectangular and direction_to_mirrorball (kernel/camera/projection.h).
    const std::vector<Case> cases =
        projection == 0
            ? std::vector<Case>{{Vec3(1, 0, 0), 0.5f, 0.5f},
                                {Vec3(0, 1, 0), 0.25f, 0.5f},
                                {normalize(Vec3(-1, -1, 1)), 0.875f, 1 - std::acos(1 / std::sqrt(3.0f)) / kPi}}
            : std::vector<Case>{{Vec3(0, -2, 0), 0.5f, 0.5f},  // normalised first
                                {Vec3(1, 0, 0), 0.5f * (1 / std::sqrt(2.0f) + 1), 0.5f},
                                {normalize(Vec3(0.3f, 0.2f, 0.5f)), 0, 0}};
    for (const Case& k : cases) {
      ShadingContext c;
      c.set_normal_values(k.d, Vec3(0.0f));
      float u = k.u, v = k.v;
      if (projection == 1 && k.u == 0) {  // the general formula
        Vec3 d = k.d;
        d.y -= 1;
        const float div = 2 * std::sqrt(std::max(-0.5f * d.y, 0.0f));
        u = 0.5f * (d.x / div + 1);
        v = 0.5f * (d.z / div + 1);
      }
      const Spectrum L = prog.run(c, images, nullptr, nullptr);
      EXPECT_NEAR(L.x, u, 1e-5f) << projection;
      EXPECT_NEAR(L.y, v, 1e-5f) << projection;
    }
  }
}

}  // namespace
}  // namespace lt
