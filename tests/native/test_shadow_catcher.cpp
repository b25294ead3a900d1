// Shadow catchers as Cycles 3.4 renders them (integrators/path.cpp's catcher split, core/film.cpp's
// read-back): seen from above, a diffuse catcher plane filling the frame under an area light, and a
// black occluder (no light of its own to add) hidden from the camera casting its shadow on the left.
#include <gtest/gtest.h>

#include "scene_builders.h"

namespace {

using namespace lt_test;

ScenePtr catcher_scene(bool catcher, bool fog, bool occluder = true) {
  ScenePtr s = new_scene();
  set_world(s.get(), {0.1f, 0.1f, 0.1f}, 1);
  const int white = add_diffuse(s.get(), {0.8f, 0.8f, 0.8f});
  lt_instance_desc d{};
  d.mesh = add_mesh(s.get(), plane(8, 8));
  const Xform id = translate({0, 0, 0});
  std::copy(id.begin(), id.end(), d.transform);
  d.materials = &white;
  d.material_count = 1;
  d.visibility = LT_VISIBLE_ALL;
  d.shadow_catcher = catcher;
  int out = -1;
  check(lt_scene_add_instance(s.get(), &d, &out), "lt_scene_add_instance");
  d.mesh = add_mesh(s.get(), plane(2, 4));
  if (!occluder) d.visibility = 0;  // there but seen by no ray
  const Xform above = translate({-1.0f, 0, 1});
  std::copy(above.begin(), above.end(), d.transform);
  const int black = add_diffuse(s.get(), {0, 0, 0});
  d.materials = &black;
  if (occluder) d.visibility = LT_VISIBLE_ALL & ~LT_VISIBLE_CAMERA;
  d.shadow_catcher = 0;
  check(lt_scene_add_instance(s.get(), &d, &out), "lt_scene_add_instance");
  add_light(s.get(), area_light(LT_AREA_SQUARE, 0.5f, 0.5f, translate({0, 0, 3}), 100));
  if (fog)
    add_object(s.get(), box({40, 40, 0}, {41, 41, 1}), add_volume_material(s.get(), volume(LT_VOLUME_PRINCIPLED, 1)));
  set_camera(s.get(), perspective_camera(look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0})));
  check(lt_scene_commit(s.get()), "lt_scene_commit");
  return s;
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
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_VOLPATH}) {
    SCOPED_TRACE("integrator " + std::to_string(integrator));
    ScenePtr s = catcher_scene(true, integrator == LT_INTEGRATOR_VOLPATH);
    lt_render_settings rs = render_settings(width, height, 32, 3);
    rs.integrator = integrator;
    rs.passes |= 1u << LT_PASS_SHADOW_CATCHER;
    rs.shadow_catcher_approximate = 0;
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
    ScenePtr bare = catcher_scene(true, integrator == LT_INTEGRATOR_VOLPATH, false);
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

TEST(ShadowCatcher, BidirectionalAndSceneWithoutCatcherRenderItAsAnObject) {
  const int width = 16, height = 8;
  for (bool catcher : {true, false}) {
    ScenePtr s = catcher_scene(catcher, false);
    lt_render_settings rs = render_settings(width, height, 8, 3);
    rs.integrator = catcher ? LT_INTEGRATOR_BIDIRECTIONAL : LT_INTEGRATOR_PATH;
    rs.passes |= 1u << LT_PASS_SHADOW_CATCHER;
    Passes p = render(s.get(), rs);
    const std::vector<float>& sc = p.pass(LT_PASS_SHADOW_CATCHER);
    for (size_t i = 0; i < sc.size(); ++i) ASSERT_EQ(sc[i], 1.0f);  // no split: 1, as Cycles
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) ASSERT_EQ(p.rgba(x, y)[3], 1.0f);  // the plane, opaque
  }
}

}  // namespace
