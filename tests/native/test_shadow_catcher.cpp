// Shadow catchers as Cycles 3.4 renders them (integrators/path.cpp's catcher split, core/film.cpp's
// read-back): seen from above, a diffuse catcher plane filling the frame under an area light, and a
// black occluder (no light of its own to add) hidden from the camera casting its shadow on the left.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "scene_builders.h"

namespace {

using namespace lt_test;

// occluder_seen: the occluder is grey and seen by the camera too (the matte then holds it).
ScenePtr catcher_scene(bool catcher, bool fog, bool occluder = true, bool occluder_seen = false) {
  ScenePtr s = new_scene();
  set_world(s.get(), {0.1f, 0.1f, 0.1f}, 1);
  add_object(s.get(), plane(8, 8), add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}), identity(), LT_VISIBLE_ALL, catcher);
  const unsigned occluder_visibility =
      !occluder ? 0u : (occluder_seen ? LT_VISIBLE_ALL : LT_VISIBLE_ALL & ~LT_VISIBLE_CAMERA);  // 0: seen by no ray
  add_object(s.get(), plane(2, 4), add_diffuse(s.get(), occluder_seen ? V3{0.5f, 0.5f, 0.5f} : V3{0, 0, 0}),
             translate({-1.0f, 0, 1}), occluder_visibility);
  add_light(s.get(), area_light(LT_AREA_SQUARE, 0.5f, 0.5f, translate({0, 0, 3}), 100));
  if (fog)
    add_object(s.get(), box({40, 40, 0}, {41, 41, 1}), add_volume_material(s.get(), volume(LT_VOLUME_PRINCIPLED, 1)));
  set_camera(s.get(), perspective_camera(look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0})));
  check(lt_scene_commit(s.get()), "lt_scene_commit");
  return s;
}

// Settings of a render with the Shadow Catcher pass on (the catcher transparent in Combined).
lt_render_settings pass_settings(int width, int height, int samples, unsigned seed, int integrator) {
  lt_render_settings rs = render_settings(width, height, samples, seed);
  rs.integrator = integrator;
  rs.passes |= 1u << LT_PASS_SHADOW_CATCHER;
  rs.shadow_catcher_approximate = 0;
  return rs;
}

// Mean of channel c of a 3-channel pass over columns [x0, x1).
double band_mean(const std::vector<float>& pass, int width, int height, int c, int x0, int x1) {
  double sum = 0;
  for (int y = 0; y < height; ++y)
    for (int x = x0; x < x1; ++x) sum += pass[(size_t(y) * width + x) * 3 + c];
  return sum / (double(height) * (x1 - x0));
}

TEST(ShadowCatcher, MatteIsTransparentAndThePassHoldsTheShadow) {
  const int width = 32, height = 16;
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    SCOPED_TRACE("integrator " + std::to_string(integrator));
    const bool fog = integrator != LT_INTEGRATOR_PATH;  // BDPT: with media, walks and stacks
    ScenePtr s = catcher_scene(true, fog);
    lt_render_settings rs = pass_settings(width, height, 32, 3, integrator);
    Passes p = render(s.get(), rs);
    ASSERT_EQ(p.first_non_finite(), "");
    // Only the catcher is seen: the matte is empty and fully transparent.
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        for (int c = 0; c < 4; ++c) ASSERT_EQ(p.rgba(x, y)[c], 0.0f) << "pixel " << x << ", " << y;
    const std::vector<float>& sc = p.pass(LT_PASS_SHADOW_CATCHER);
    ASSERT_FALSE(sc.empty());
    // Left: the occluder's shadow (about 0.05: the catcher-only path is lit by the lamp and the whole
    // sky; 0.3 if its light samples saw the occluder); right: what it hides of the sky.
    for (int c = 0; c < 3; ++c) {
      EXPECT_LT(band_mean(sc, width, height, c, 2, width / 4), 0.15);
      EXPECT_GT(band_mean(sc, width, height, c, 3 * width / 4, width), 0.95);
    }
    // Without the occluder both paths see the same scene with the same random numbers: their ratio
    // is 1 up to rounding.
    ScenePtr bare = catcher_scene(true, fog, false);
    Passes b = render(bare.get(), rs);
    for (float v : b.pass(LT_PASS_SHADOW_CATCHER)) ASSERT_NEAR(v, 1.0f, 1e-4f);
    // Approximated into Combined over the world behind (film opaque): the shadow darkens the world.
    rs.shadow_catcher_approximate = 1;
    Passes a = render(s.get(), rs);
    EXPECT_NEAR(a.rgba(width - 2, height / 2)[0], 0.1f, 5e-3f);
    EXPECT_LT(a.rgba(2, height / 2)[0], 0.05f);
    EXPECT_EQ(a.rgba(2, height / 2)[3], 1.0f);
    // ... or into alpha (film transparent): the shadow is opaque black, the rest transparent.
    rs.transparent_background = 1;
    Passes t = render(s.get(), rs);
    EXPECT_EQ(t.rgba(2, height / 2)[0], 0.0f);
    EXPECT_GT(t.rgba(2, height / 2)[3], 0.5f);
    EXPECT_LT(t.rgba(width - 2, height / 2)[3], 0.05f);
  }
}

TEST(ShadowCatcher, SceneWithoutCatcherRendersThePlaneAsAnObject) {
  const int width = 16, height = 8;
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    ScenePtr s = catcher_scene(false, false);
    lt_render_settings rs = render_settings(width, height, 8, 3);
    rs.integrator = integrator;
    rs.passes |= 1u << LT_PASS_SHADOW_CATCHER;
    Passes p = render(s.get(), rs);
    const std::vector<float>& sc = p.pass(LT_PASS_SHADOW_CATCHER);
    for (size_t i = 0; i < sc.size(); ++i) ASSERT_EQ(sc[i], 1.0f);  // no split: 1, as Cycles
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) ASSERT_EQ(p.rgba(x, y)[3], 1.0f);  // the plane, opaque
  }
}

// Per tile x tile pixels (and over the whole image, the last "tile"), the means over K renders
// (seeds 1..K) of Combined's R, G, B, A and the Shadow Catcher pass's R, G, B under settings a and
// b: a line for each that differ by more than 5 standard errors of their difference, each from
// the spread of its K renders' values (the pass is a ratio of means: no per-pixel variance).
std::string differing_catcher_tiles(lt_scene* s, lt_render_settings a, lt_render_settings b, int K, int tile) {
  const int w = a.width, h = a.height, nx = w / tile, ny = h / tile, cells = nx * ny + 1;
  auto tiles = [&](const Passes& p) {
    std::vector<double> m(size_t(cells) * 7, 0.0);
    const std::vector<float>& sc = p.pass(LT_PASS_SHADOW_CATCHER);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 7; ++c) {
          const double v = c < 4 ? p.rgba(x, y)[c] : sc[(size_t(y) * w + x) * 3 + c - 4];
          m[size_t((y / tile) * nx + x / tile) * 7 + c] += v / (tile * tile);
          m[size_t(cells - 1) * 7 + c] += v / (double(w) * h);
        }
    return m;
  };
  std::vector<double> sum[2], sq[2];
  for (int side = 0; side < 2; ++side) {
    sum[side].assign(size_t(cells) * 7, 0.0);
    sq[side].assign(size_t(cells) * 7, 0.0);
    lt_render_settings rs = side == 0 ? a : b;
    for (int k = 0; k < K; ++k) {
      rs.seed = unsigned(k + 1);
      Passes p = render(s, rs);
      if (!p.first_non_finite().empty()) return "non-finite " + p.first_non_finite();
      const std::vector<double> m = tiles(p);
      for (size_t i = 0; i < m.size(); ++i) {
        sum[side][i] += m[i];
        sq[side][i] += m[i] * m[i];
      }
    }
  }
  std::string out;
  for (size_t i = 0; i < sum[0].size(); ++i) {
    double mean[2], var[2];
    for (int side = 0; side < 2; ++side) {
      mean[side] = sum[side][i] / K;
      var[side] = std::max(0.0, (sq[side][i] - K * mean[side] * mean[side]) / (K - 1)) / K;
    }
    const double diff = std::abs(mean[0] - mean[1]), se = std::sqrt(var[0] + var[1]);
    if (diff > 5 * se + 1e-6) {
      const int cell = int(i / 7);
      out += (cell == cells - 1 ? std::string("image") : "tile " + std::to_string(cell)) + " channel " +
             std::to_string(i % 7) + ": " + std::to_string(mean[0]) + " vs " + std::to_string(mean[1]) + " (se " +
             std::to_string(se) + ")\n";
    }
  }
  return out;
}

// Bidirectional's catcher split (bdpt.cpp) against the path tracer's, with the occluder hidden
// from the camera (the pass holds its whole shadow) or seen (the matte holds it): Combined
// (catcher transparent, or its shadow approximated into alpha or over the world) and the Shadow
// Catcher pass agree per tile and over the image.
TEST(ShadowCatcher, BidirectionalAgreesWithPathTracing) {
  ScenePtr hidden = catcher_scene(true, false), seen = catcher_scene(true, false, true, true);
  struct Case {
    lt_scene* scene;
    int approximate, transparent;
  };
  for (Case c : {Case{hidden.get(), 0, 0}, Case{seen.get(), 0, 0}, Case{seen.get(), 1, 1}, Case{hidden.get(), 1, 0}}) {
    SCOPED_TRACE(std::string(c.scene == seen.get() ? "occluder seen" : "occluder hidden") + ", approximate " +
                 std::to_string(c.approximate) + ", transparent " + std::to_string(c.transparent));
    lt_render_settings pt = pass_settings(32, 16, 64, 0, LT_INTEGRATOR_PATH);
    pt.shadow_catcher_approximate = c.approximate;
    pt.transparent_background = c.transparent;
    lt_render_settings bd = pt;
    bd.integrator = LT_INTEGRATOR_BIDIRECTIONAL;
    EXPECT_EQ(differing_catcher_tiles(c.scene, pt, bd, 6, 8), "");
  }
}

// The catcher-only path sees the media of catchers alone (Cycles re-inits the volume stack at the
// split, without the World volume): in an absorbing volume (sigma 0.1) that is no catcher, a box
// around the camera, the lamp and the catcher or the World volume, Combined is dimmed along the
// camera ray (5 m) and the lamp's light (3 m) but the catcher-only light is not, so the pass over
// the central 8 x 8 pixels is exp(-0.8) (the rays' slant there adds under 0.6 %; over 8 seeds the
// spread was 0.001). Keeping the camera's stack (and the global media) dims both alike: the pass
// was 1.
TEST(ShadowCatcher, CatcherOnlyPathLeavesOutVolumesAroundTheCamera) {
  for (bool world : {false, true}) {
    ScenePtr s = new_scene();
    add_object(s.get(), plane(8, 8), add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}), identity(), LT_VISIBLE_ALL, true);
    add_light(s.get(), area_light(LT_AREA_SQUARE, 0.5f, 0.5f, translate({0, 0, 3}), 100));
    const lt_volume_desc fog = volume(LT_VOLUME_ABSORPTION, 0.1f, 0);
    if (world)
      check(lt_scene_set_world_volume(s.get(), &fog, 1), "lt_scene_set_world_volume");
    else
      add_object(s.get(), box({-10, -10, -1}, {10, 10, 5.5f}), add_volume_material(s.get(), fog));
    set_camera(s.get(), perspective_camera(look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0})));
    check(lt_scene_commit(s.get()), "lt_scene_commit");
    const int size = 32;
    for (int integrator : {LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
      SCOPED_TRACE(std::string(world ? "World volume" : "box") + ", integrator " + std::to_string(integrator));
      Passes p = render(s.get(), pass_settings(size, size, 64, 5, integrator));
      ASSERT_EQ(p.first_non_finite(), "");
      const std::vector<float>& sc = p.pass(LT_PASS_SHADOW_CATCHER);
      double sum = 0;
      for (int y = size / 2 - 4; y < size / 2 + 4; ++y)
        for (int x = size / 2 - 4; x < size / 2 + 4; ++x)
          for (int c = 0; c < 3; ++c) sum += sc[(size_t(y) * size + x) * 3 + c];
      EXPECT_NEAR(sum / (8 * 8 * 3), std::exp(-0.8), 0.01);
    }
  }
}

}  // namespace
