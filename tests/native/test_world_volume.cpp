// World volumes through the C ABI (lt_scene_set_world_volume): closed-form absorption, Cycles 3.4's
// infinite escape distance (background and suns fully attenuated), scattering from a point light.
#include <gtest/gtest.h>

#include <cmath>

#include "scene_builders.h"

using namespace lt_test;

namespace {

// An orthographic camera at height h looking down at an emitter plane (radiance L) that fills the
// view, all inside a World volume; a white world behind. Every camera ray crosses exactly h.
ScenePtr world_fog_scene(const lt_volume_desc& d, float h, float L) {
  ScenePtr s = new_scene();
  add_object(s.get(), plane(20, 20), add_emission(s.get(), {1, 1, 1}, L));
  set_world(s.get(), {1, 1, 1}, 1);
  set_camera(s.get(), orthographic_camera(look_at({0, 0, h}, {0, 0, 0}, {0, 1, 0}), 2));
  check(lt_scene_set_world_volume(s.get(), &d, 1), "set_world_volume");
  check(lt_scene_commit(s.get()), "commit");
  return s;
}

}  // namespace

TEST(VolPathWorldVolume, AbsorbsExactlyExpMinusSigmaD) {
  // Volume Absorption of colour 0: sigma_a = density. Radiance L exp(-sigma_a h), within 5 SE.
  const float sigma = 0.3f, h = 2.5f, L = 2.0f;
  ScenePtr s = world_fog_scene(volume(LT_VOLUME_ABSORPTION, sigma, 0.0f), h, L);
  Passes p = render(s.get(), volpath_settings(16, 16, 64, 7));
  ASSERT_EQ(p.first_non_finite(), "");
  const double expected = L * std::exp(-double(sigma) * h);
  for (int c = 0; c < 3; ++c) {
    RegionStats r = region_stats(p, c, 0, 16, 0, 16);
    EXPECT_NEAR(r.mean, expected, kSigmas * r.standard_error + 1e-6) << "channel " << c;
    EXPECT_GT(r.standard_error, 0.0);
  }
  // PATH ignores media: the emitter unattenuated.
  lt_render_settings rs = render_settings(8, 8, 4, 7);
  Passes q = render(s.get(), rs);
  EXPECT_NEAR(q.rgba(4, 4)[0], L, 1e-4);
}

TEST(VolPathWorldVolume, HidesTheBackgroundAndSunLikeCycles) {
  // Cycles 3.4 integrates an escaped ray's world volume to infinity (even past the camera's clip
  // distance) and so do shadow rays to sun and world lights: all fully attenuated.
  ScenePtr s = new_scene();
  add_object(s.get(), plane(4, 4), add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}));
  add_light(s.get(), sun_light({0.3f, 0.2f, -1}, 3.0f));
  set_world(s.get(), {0.2f, 0.3f, 0.5f}, 1);
  lt_camera_desc cam = perspective_camera(look_at({0, -4, 1}, {0, 0, 1.6f}), 35);
  cam.clip_end = 20;
  set_camera(s.get(), cam);
  lt_volume_desc d = volume(LT_VOLUME_SCATTER, 0.05f);
  check(lt_scene_set_world_volume(s.get(), &d, 1), "set_world_volume");
  check(lt_scene_commit(s.get()), "commit");
  Passes p = render(s.get(), volpath_settings(16, 16, 16, 2));
  ASSERT_EQ(p.first_non_finite(), "");
  for (size_t i = 0; i < p.combined.size(); i += 4)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(p.combined[i + c], 0.0f) << "pixel " << i / 4;
}

TEST(VolPathWorldVolume, LitByAPointLightScattersAndConvergesAcrossSeeds) {
  // A scattering World volume seen against nothing, lit by a point light: single scattering is
  // positive and two independent seeds agree within 5 SE per 4x4 tile; a NULL desc is refused.
  ScenePtr s = new_scene();
  add_light(s.get(), point_light({0, 0, 0}, 100));
  set_camera(s.get(), perspective_camera(look_at({0, -3, 0}, {0, 0, 0}), 35));
  lt_volume_desc d = volume(LT_VOLUME_PRINCIPLED, 0.2f, 0.7f, 0.3f);
  EXPECT_NE(lt_scene_set_world_volume(s.get(), nullptr, 1), LT_OK);
  check(lt_scene_set_world_volume(s.get(), &d, 1), "set_world_volume");
  check(lt_scene_commit(s.get()), "commit");
  EXPECT_EQ(lt_scene_set_world_volume(s.get(), &d, 1), LT_ERROR_STATE);
  Passes a = render(s.get(), volpath_settings(16, 16, 64, 1)), b = render(s.get(), volpath_settings(16, 16, 64, 2));
  ASSERT_EQ(a.first_non_finite(), "");
  for (int ty = 0; ty < 4; ++ty)
    for (int tx = 0; tx < 4; ++tx) EXPECT_GT(region_stats(a, 0, 4 * tx, 4 * tx + 4, 4 * ty, 4 * ty + 4).mean, 0.0);
  EXPECT_EQ(differing_tiles(a, b, 4, kSigmas), "");
}
