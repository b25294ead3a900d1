// Halting (samples, time limit, noise target), the image error estimate in lt_render_status and
// adaptive sampling through the C ABI. Whether the estimate predicts the error against a reference
// is tested in Blender (tests/blender/test_halting.py) on the test scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "scene_builders.h"

using namespace lt_test;

namespace {

// A diffuse room-like scene: floor, a box, an icosphere, an area and a point light.
ScenePtr small_scene() {
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  add_object(s, plane(10, 10), add_diffuse(s, {0.7f, 0.6f, 0.5f}));
  add_object(s, box({-1, -0.5f, 0}, {0, 0.5f, 1}), add_diffuse(s, {0.2f, 0.5f, 0.8f}));
  add_object(s, icosphere(0.5f, 3), add_diffuse(s, {0.8f, 0.3f, 0.3f}), translate({0.8f, 0, 0.5f}));
  add_light(s, area_light(LT_AREA_SQUARE, 0.5f, 0.5f, look_at({0, -1, 3}, {0, 0, 0}), 200));
  add_light(s, point_light({-2, -2, 2}, 100));
  set_world(s, {0.1f, 0.1f, 0.1f}, 1);
  set_camera(s, perspective_camera(look_at({0, -5, 2}, {0, 0, 0.5f}), 35));
  check(lt_scene_commit(s), "commit");
  return sp;
}

std::pair<float, float> count_range(const Passes& p) {
  auto [lo, hi] = std::minmax_element(p.sample_count.begin(), p.sample_count.end());
  return {*lo, *hi};
}

}  // namespace

TEST(ApiHalting, StopsAtSamplesWithAnEstimate) {
  ScenePtr s = small_scene();
  Passes p = render(s.get(), render_settings(32, 24, 8, 1));
  EXPECT_EQ(p.status.halt_reason, LT_HALT_SAMPLES);
  EXPECT_EQ(p.status.samples_done, 8);
  EXPECT_GT(p.status.rel_error, 0.0);
  EXPECT_TRUE(std::isfinite(p.status.rel_error));
  EXPECT_EQ(p.status.active_pixels, 32u * 24u);
  // One sample per pixel: no two halves, no estimate.
  Passes one = render(s.get(), render_settings(32, 24, 1, 1));
  EXPECT_LT(one.status.rel_error, 0.0);
}

// The issue asks for this timed check: the render stops within 10% of its time limit.
TEST(ApiHalting, TimeLimitStopsWithinTenPercent) {
  ScenePtr s = small_scene();
  lt_render_settings rs = render_settings(64, 48, 1 << 24, 2);
  rs.time_limit = 1.5f;
  rs.threads = 2;
  const auto t0 = std::chrono::steady_clock::now();
  lt_render* raw = nullptr;
  ASSERT_EQ(lt_render_start(s.get(), &rs, &raw), LT_OK) << lt_last_error();
  RenderPtr r(raw);
  ASSERT_EQ(lt_render_wait(r.get()), LT_OK);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Passes p = read_passes(r.get(), 64, 48);
  EXPECT_EQ(p.status.halt_reason, LT_HALT_TIME_LIMIT);
  EXPECT_NEAR(p.status.elapsed_seconds, 1.5, 0.15);
  EXPECT_NEAR(wall, 1.5, 0.15);
  // A pass cut part-way leaves pixels at most one sample apart, and every pixel has samples.
  auto [lo, hi] = count_range(p);
  EXPECT_GE(lo, 1.0f);
  EXPECT_LE(hi - lo, 1.0f);
  EXPECT_GE(lo, float(p.status.samples_done));
  EXPECT_EQ(p.first_non_finite(), "");
}

TEST(ApiHalting, NoiseTargetStopsOnceTheEstimateMeetsIt) {
  ScenePtr s = small_scene();
  lt_render_settings rs = render_settings(48, 32, 1 << 16, 3);
  rs.noise_target = 0.05f;
  Passes p = render(s.get(), rs);
  EXPECT_EQ(p.status.halt_reason, LT_HALT_NOISE_TARGET);
  EXPECT_LE(p.status.rel_error, 0.05);
  EXPECT_GT(p.status.rel_error, 0.0);
  EXPECT_GE(p.status.samples_done, rs.min_samples);
  EXPECT_LT(p.status.samples_done, 1 << 16);
  auto [lo, hi] = count_range(p);
  EXPECT_EQ(lo, hi);  // without adaptive sampling every pixel has every pass
}

TEST(ApiHalting, AdaptiveSamplingStopsConvergedPixelsOnly) {
  ScenePtr s = small_scene();
  lt_render_settings rs = render_settings(48, 32, 1 << 16, 4);
  rs.noise_target = 0.03f;
  rs.adaptive = 1;
  rs.min_samples = 8;
  Passes p = render(s.get(), rs);
  EXPECT_EQ(p.status.halt_reason, LT_HALT_NOISE_TARGET);
  EXPECT_LE(p.status.rel_error, 0.03);
  auto [lo, hi] = count_range(p);
  EXPECT_GE(lo, 8.0f);
  EXPECT_EQ(hi, float(p.status.samples_done));
  EXPECT_LT(lo, hi);
  // The pixels that took the last pass are exactly those still active.
  size_t at_max = size_t(std::count(p.sample_count.begin(), p.sample_count.end(), hi));
  EXPECT_EQ(at_max, p.status.active_pixels);
  EXPECT_LT(p.status.active_pixels, 48u * 32u);
  EXPECT_EQ(p.first_non_finite(), "");

  // Decisions depend on the film only: the thread count changes no bit.
  rs.threads = 1;
  Passes q = render(s.get(), rs);
  EXPECT_EQ(std::memcmp(p.combined.data(), q.combined.data(), p.combined.size() * sizeof(float)), 0);
  EXPECT_EQ(p.sample_count, q.sample_count);
}

TEST(ApiHalting, BidirectionalSplatsGetAnEstimate) {
  ScenePtr s = small_scene();
  lt_render_settings rs = render_settings(32, 24, 1 << 12, 5);
  rs.integrator = LT_INTEGRATOR_BIDIRECTIONAL;
  rs.noise_target = 0.08f;
  rs.adaptive = 1;
  Passes p = render(s.get(), rs);
  EXPECT_EQ(p.status.halt_reason, LT_HALT_NOISE_TARGET);
  EXPECT_LE(p.status.rel_error, 0.08);
  EXPECT_GT(p.status.rel_error, 0.0);
  EXPECT_EQ(p.first_non_finite(), "");
}

TEST(ApiHalting, BadHaltingSettingsAreRefused) {
  ScenePtr s = small_scene();
  auto refused = [&](lt_render_settings rs, const char* needle) {
    lt_render* r = nullptr;
    EXPECT_EQ(lt_render_start(s.get(), &rs, &r), LT_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(r, nullptr);
    EXPECT_NE(std::strstr(lt_last_error(), needle), nullptr) << lt_last_error();
  };
  lt_render_settings rs = render_settings(8, 8, 4);
  rs.adaptive = 1;
  refused(rs, "adaptive sampling needs a noise target");
  rs = render_settings(8, 8, 4);
  rs.time_limit = -1;
  refused(rs, "time limit");
  rs = render_settings(8, 8, 4);
  rs.noise_target = std::nanf("");
  refused(rs, "noise target");
  rs = render_settings(8, 8, 4);
  rs.min_samples = 0;
  refused(rs, "min samples");
}

TEST(ApiHalting, PixelsWithoutFiniteSamplesDoNotBlockTheNoiseTarget) {
  // An emitter so strong (colour 10 x strength 1e38) that every sample seeing it overflows to
  // infinity and is discarded: those pixels never hold 2 finite samples. They are left out of the
  // estimate and counted, so the noise target still stops the render (it never did before: the
  // estimate waited for every pixel's second sample).
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  add_object(s, plane(10, 10), add_diffuse(s, {0.7f, 0.6f, 0.5f}));
  add_object(s, plane(1, 1), add_emission(s, {10, 10, 10}, 1e38f), translate({0, 0, 1}));
  set_world(s, {0.5f, 0.5f, 0.5f}, 1);
  set_camera(s, perspective_camera(look_at({0, -0.01f, 5}, {0, 0, 0}), 35));
  check(lt_scene_commit(s), "commit");
  lt_render_settings rs = render_settings(24, 24, 4096, 3);
  rs.noise_target = 0.05f;
  rs.min_samples = 4;
  rs.max_bounces = rs.diffuse_bounces = 0;  // the floor's light from the emitter would overflow too
  Passes p = render(s, rs);
  ASSERT_EQ(p.first_non_finite(), "");
  EXPECT_EQ(p.status.halt_reason, LT_HALT_NOISE_TARGET);
  EXPECT_LT(p.status.samples_done, 4096);
  EXPECT_GT(p.status.nan_samples, 0u);
  EXPECT_GT(p.status.unestimated_pixels, 0u);
  EXPECT_LT(p.status.unestimated_pixels, 24u * 24u / 4);
  EXPECT_GE(p.status.rel_error, 0.0);
  EXPECT_LE(p.status.rel_error, 0.05);
}
