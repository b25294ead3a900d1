// White furnace tests through the C ABI: diffuse objects inside a uniform world of radiance 1.
//
// With albedo 1 and no emitters, every path's expected radiance is exactly 1 whatever the
// geometry (the rendering equation's solution is L = 1 everywhere). For a convex object every
// surface point sees only the world, so L = albedo exactly. Tolerances: 5 standard errors from the
// Variance pass (per pixel: sqrt(var); image mean: sqrt(sum var) / N), plus 1e-5 relative for float
// rounding where a pixel's variance is zero.
#include <gtest/gtest.h>

#include <cmath>

#include "scene_builders.h"

using namespace lt_test;

namespace {

constexpr double kSigmas = 5.0;

// Checks every selected pixel's R, G, B mean against `expected` and the selected image mean.
// select(x, y) picks the pixels to test; returns how many were tested.
template <class Select>
int check_pixels(const Passes& p, double expected, Select select) {
  double sum[3] = {0, 0, 0}, var[3] = {0, 0, 0};
  int n = 0, failures = 0;
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x) {
      if (!select(x, y)) continue;
      ++n;
      for (int c = 0; c < 3; ++c) {
        double m = p.rgba(x, y)[c], v = p.var(x, y)[c];
        sum[c] += m;
        var[c] += v;
        double tol = kSigmas * std::sqrt(v) + 1e-5 * expected;
        if (std::abs(m - expected) > tol && failures++ < 10)
          ADD_FAILURE() << "pixel (" << x << ", " << y << ") channel " << c << ": mean " << m << ", expected "
                        << expected << " +- " << tol << " (5 standard errors)";
      }
    }
  EXPECT_EQ(failures, 0) << "pixels outside 5 standard errors";
  for (int c = 0; c < 3; ++c) {
    double mean = sum[c] / n, se = std::sqrt(var[c]) / n;
    EXPECT_NEAR(mean, expected, kSigmas * se + 1e-5 * expected)
        << "image mean, channel " << c << " (standard error " << se << ", " << n << " pixels)";
    EXPECT_GT(se, 0.0) << "the estimator should be noisy here; a zero variance means the test is void";
  }
  return n;
}

// Camera on -Y looking at `target`.
void camera_towards(lt_scene* s, V3 eye, V3 target, float focal = 50) {
  set_camera(s, perspective_camera(look_at(eye, target), focal));
}

}  // namespace

TEST(ApiFurnace, ConvexSphereAlbedoOneIsOneEverywhere) {
  ScenePtr s = new_scene();
  int white = add_diffuse(s.get(), {1, 1, 1});
  add_object(s.get(), icosphere(1.0f, 3), white);
  set_world(s.get(), {1, 1, 1}, 1);
  camera_towards(s.get(), {0, -4, 0}, {0, 0, 0});
  ASSERT_EQ(lt_scene_commit(s.get()), LT_OK) << lt_last_error();

  lt_render_settings rs = render_settings(32, 32, 256, 7);
  rs.max_bounces = rs.diffuse_bounces = 128;
  Passes p = render(s.get(), rs);
  ASSERT_EQ(p.first_non_finite(), "");
  EXPECT_EQ(p.status.state, LT_STATE_DONE);
  EXPECT_EQ(p.status.nan_samples, 0u);
  // Every pixel, sphere, silhouette and background alike, has expectation 1.
  int n = check_pixels(p, 1.0, [](int, int) { return true; });
  EXPECT_EQ(n, 32 * 32);
}

TEST(ApiFurnace, ConvexSphereReflectsItsAlbedo) {
  // A convex surface sees only the world: L = albedo x 1 exactly, at any bounce limit >= 1.
  const float albedo = 0.5f;
  ScenePtr s = new_scene();
  int grey = add_diffuse(s.get(), {albedo, albedo, albedo});
  add_object(s.get(), icosphere(1.0f, 3), grey);
  set_world(s.get(), {1, 1, 1}, 1);
  camera_towards(s.get(), {0, -4, 0}, {0, 0, 0});
  ASSERT_EQ(lt_scene_commit(s.get()), LT_OK) << lt_last_error();

  lt_render_settings rs = render_settings(32, 32, 256, 11);
  rs.max_bounces = rs.diffuse_bounces = 128;
  rs.transparent_background = 1;  // alpha = coverage: pick the pixels whose every sample hit
  Passes p = render(s.get(), rs);
  ASSERT_EQ(p.first_non_finite(), "");
  EXPECT_EQ(p.status.nan_samples, 0u);
  int n = check_pixels(p, albedo, [&](int x, int y) { return p.rgba(x, y)[3] == 1.0f; });
  EXPECT_GT(n, 300) << "too few pixels fully on the sphere";
  // The background pixels (alpha 0) must be exactly black with a transparent film.
  int background = 0;
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x)
      if (p.rgba(x, y)[3] == 0.0f) {
        ++background;
        EXPECT_EQ(p.rgba(x, y)[0], 0.0f);
      }
  EXPECT_GT(background, 50);
}

TEST(ApiFurnace, ConcaveOpenBoxWithSphereManyBounces) {
  // A concave scene (a deep open box with a sphere in it, both sides diffuse, albedo 1): paths
  // bounce many times and Russian roulette ends most of them; the expectation is still exactly 1.
  ScenePtr s = new_scene();
  int white = add_diffuse(s.get(), {1, 1, 1});
  add_object(s.get(), box({-1, -1, 0}, {1, 1, 2.5f}, /*open_top=*/true), white);
  add_object(s.get(), icosphere(0.5f, 3), white, translate({0.2f, 0.1f, 0.5f}));
  set_world(s.get(), {1, 1, 1}, 1);
  camera_towards(s.get(), {0, -0.5f, 7}, {0, 0, 0.5f}, 80);
  ASSERT_EQ(lt_scene_commit(s.get()), LT_OK) << lt_last_error();

  lt_render_settings rs = render_settings(32, 32, 256, 3);
  rs.max_bounces = rs.diffuse_bounces = 128;
  Passes p = render(s.get(), rs);
  ASSERT_EQ(p.first_non_finite(), "");
  EXPECT_EQ(p.status.state, LT_STATE_DONE);
  EXPECT_EQ(p.status.nan_samples, 0u);
  check_pixels(p, 1.0, [](int, int) { return true; });

  // The test is only meaningful if the higher bounces carry a visible part of the light: with one
  // bounce the same view must be far darker than 1.
  rs.max_bounces = rs.diffuse_bounces = 1;
  Passes one = render(s.get(), rs);
  ASSERT_EQ(one.first_non_finite(), "");
  RegionStats st = region_stats(one, 0, 0, one.width, 0, one.height);
  EXPECT_LT(st.mean, 0.9) << "one bounce already gives almost everything: the scene does not test many bounces";
}

TEST(ApiFurnace, ClosedMirrorBoxRunsToTheBounceLimitUnamplified) {
  // A camera inside a closed box whose walls are perfect mirrors (reflectance 1) that also emit Le:
  // every camera path is deterministic and sees Le at each of its N + 2 hits (N = the bounce
  // limit; as in Cycles, N = 0 still lights the first hit), so every pixel is exactly (N + 2) Le
  // with zero variance. Russian roulette must neither
  // end nor amplify a path of throughput 1: a survival cap below 1 (0.95) makes the survivors of
  // 256 bounces weigh 1/0.95^253 ~ 4e5 and the image a handful of fireflies.
  const float le = 0.5f;
  const int bounces = 256;
  ScenePtr s = new_scene();
  lt_shader_node nodes[3] = {node(LT_NODE_ADD), node(LT_NODE_EMISSION), node(LT_NODE_GLOSSY)};
  nodes[0].child[0] = 1;
  nodes[0].child[1] = 2;
  nodes[1].color = nodes[2].color = constant(V3{1, 1, 1});
  nodes[1].strength = constant(le);
  nodes[2].roughness = constant(0.0f);
  int mirror = -1;
  check(lt_scene_add_material(s.get(), nodes, 3, 0, &mirror), "lt_scene_add_material");
  add_object(s.get(), box({-1, -1, -1}, {1, 1, 1}), mirror);
  camera_towards(s.get(), {0.1f, -0.7f, 0.05f}, {0.3f, 1, 0.2f}, 30);
  ASSERT_EQ(lt_scene_commit(s.get()), LT_OK) << lt_last_error();

  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_VOLPATH}) {
    lt_render_settings rs = render_settings(16, 16, 8, 5);
    rs.integrator = integrator;
    rs.max_bounces = rs.glossy_bounces = bounces;
    Passes p = render(s.get(), rs);
    ASSERT_EQ(p.first_non_finite(), "");
    EXPECT_EQ(p.status.nan_samples, 0u);
    const double expected = double(bounces + 2) * le;
    int failures = 0;
    for (int y = 0; y < p.height; ++y)
      for (int x = 0; x < p.width; ++x)
        for (int c = 0; c < 3; ++c)
          if (std::abs(p.rgba(x, y)[c] - expected) > 1e-3 * expected && failures++ < 5)
            ADD_FAILURE() << "integrator " << integrator << ", pixel (" << x << ", " << y << ") channel " << c
                          << ": " << p.rgba(x, y)[c] << ", expected " << expected;
  }
}
