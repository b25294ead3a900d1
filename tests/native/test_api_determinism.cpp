// Determinism: a sample's random numbers depend only on (seed, pixel of the full frame, sample
// index, dimension), so thread count, tile order and the render border must not change a single
// bit of the film; a different seed must give a different image.
#include <gtest/gtest.h>

#include <cstring>

#include "scene_builders.h"

using namespace lt_test;

namespace {

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST(ApiDeterminism, ThreadCountAndBorderDoNotChangeABit) {
  ScenePtr s = varied_scene();
  lt_render_settings rs = render_settings(64, 48, 8, 1234);
  rs.max_bounces = 8;

  rs.threads = 1;
  Passes one = render(s.get(), rs);
  rs.threads = 2;
  Passes two = render(s.get(), rs);
  rs.threads = 0;  // all cores
  Passes all = render(s.get(), rs);
  for (const Passes* p : {&one, &two, &all}) {
    ASSERT_EQ(p->first_non_finite(), "");
    EXPECT_EQ(p->status.state, LT_STATE_DONE);
  }
  // The image is not trivial: lit, varied, with noise.
  RegionStats st = region_stats(one, 0, 0, one.width, 0, one.height);
  EXPECT_GT(st.mean, 0.01);
  EXPECT_GT(st.standard_error, 0.0);

  EXPECT_TRUE(same_bits(one.combined, two.combined)) << "Combined differs between 1 and 2 threads";
  EXPECT_TRUE(same_bits(one.combined, all.combined)) << "Combined differs between 1 thread and all cores";
  for (auto member : {&Passes::depth, &Passes::normal, &Passes::albedo, &Passes::variance, &Passes::sample_count})
    EXPECT_TRUE(same_bits(one.*member, two.*member)) << "a data pass differs between 1 and 2 threads";
  EXPECT_EQ(one.status.rays, two.status.rays);

  // A border region [x0, x1) x [y0, y1) (y from the bottom), not aligned to the 16-pixel tiles.
  const int x0 = 13, x1 = 50, y0 = 7, y1 = 30;
  rs.threads = 2;
  rs.border[0] = x0;
  rs.border[1] = x1;
  rs.border[2] = y0;
  rs.border[3] = y1;
  Passes border = render(s.get(), rs);
  ASSERT_EQ(border.first_non_finite(), "");
  ASSERT_EQ(border.width, x1 - x0);
  ASSERT_EQ(border.height, y1 - y0);
  int differing = 0;
  for (int y = 0; y < border.height; ++y)
    for (int x = 0; x < border.width; ++x)
      if (std::memcmp(border.rgba(x, y), one.rgba(x + x0, y + y0), 4 * sizeof(float)) != 0) ++differing;
  EXPECT_EQ(differing, 0) << "border pixels differ from the same pixels of the full frame";
}

// Bidirectional splats are merged tile by tile in a fixed order, and media draw their random
// numbers from the sample's sampler: 1, 2 and all threads give the same bits for BDPT and
// VOLPATH, also with fog (an invisible boundary) around the glossy sphere.
TEST(ApiDeterminism, ThreadCountDoesNotChangeABitWithBdptOrMedia) {
  for (bool fog : {false, true}) {
    ScenePtr s = varied_scene(fog);
    for (int integrator : {LT_INTEGRATOR_BIDIRECTIONAL, LT_INTEGRATOR_VOLPATH}) {
      if (!fog && integrator == LT_INTEGRATOR_VOLPATH) continue;  // equals PATH, tested above
      lt_render_settings rs = render_settings(48, 32, 4, 99);
      rs.integrator = integrator;
      rs.max_bounces = 8;
      rs.volume_bounces = 4;
      rs.threads = 1;
      Passes one = render(s.get(), rs);
      rs.threads = 2;
      Passes two = render(s.get(), rs);
      rs.threads = 0;
      Passes all = render(s.get(), rs);
      ASSERT_EQ(one.first_non_finite(), "");
      const std::string what = "integrator " + std::to_string(integrator) + (fog ? " with fog" : "");
      EXPECT_TRUE(same_bits(one.combined, two.combined)) << what << ": 1 vs 2 threads";
      EXPECT_TRUE(same_bits(one.combined, all.combined)) << what << ": 1 thread vs all cores";
      EXPECT_EQ(one.status.rays, two.status.rays) << what;
    }
  }
}

TEST(ApiDeterminism, DifferentSeedsGiveDifferentImages) {
  ScenePtr s = varied_scene();
  lt_render_settings rs = render_settings(64, 48, 4, 1);
  Passes a = render(s.get(), rs);
  Passes a2 = render(s.get(), rs);
  rs.seed = 2;
  Passes b = render(s.get(), rs);
  ASSERT_EQ(a.first_non_finite(), "");
  ASSERT_EQ(b.first_non_finite(), "");
  EXPECT_TRUE(same_bits(a.combined, a2.combined)) << "the same seed must reproduce the image";
  // Pixels whose samples are random (not background or pure emitters) must almost all change.
  int noisy = 0, changed = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      if (a.var(x, y)[0] <= 0) continue;
      ++noisy;
      if (std::memcmp(a.rgba(x, y), b.rgba(x, y), 3 * sizeof(float)) != 0) ++changed;
    }
  EXPECT_GT(noisy, a.width * a.height / 2);
  EXPECT_GT(changed, noisy * 95 / 100);
}
