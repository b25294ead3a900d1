// Holdout as Cycles 3.4 renders it (integrators/path_state.h, hold_out): a holdout object leaves
// the film transparent and black where the camera sees it, light tracing included (BDPT's t = 1
// splats), and a Holdout closure of weight w takes w of the alpha, whatever the integrator.
#include <gtest/gtest.h>

#include "program_builder.h"
#include "scene_builders.h"
#include "shading/shaders.h"

namespace {

using namespace lt_test;

// Seen from above (3.6 x 1.8 m): on the left a diffuse plane that is a holdout object,
// on the right a plane of Mix Shader (Holdout 0.3, Diffuse 0.7); an area light over both, and,
// for the volumetric integrator, a fog box out of view (so that its media code runs).
ScenePtr holdout_scene(bool fog) {
  ScenePtr s = new_scene();
  set_world(s.get(), {0.2f, 0.3f, 0.4f}, 1);
  const int mesh = add_mesh(s.get(), plane(3, 4));  // past the frame's edges: no background
  const int white = add_diffuse(s.get(), {0.8f, 0.8f, 0.8f});
  lt_instance_desc d{};
  d.mesh = mesh;
  const Xform left = translate({-1.5f, 0, 0});
  std::copy(left.begin(), left.end(), d.transform);
  d.materials = &white;
  d.material_count = 1;
  d.visibility = LT_VISIBLE_ALL;
  d.holdout = 1;
  int id = -1;
  check(lt_scene_add_instance(s.get(), &d, &id), "lt_scene_add_instance");
  ShaderCode p;
  auto w = p.mix(p.one(), 0.7f);
  p.emit(lt::kOpHoldout, {w.first}, {});
  p.diffuse(w.second, {0.8f, 0.8f, 0.8f});
  add_instance(s.get(), mesh, add_material(s.get(), p), translate({1.5f, 0, 0}));
  add_light(s.get(), area_light(LT_AREA_SQUARE, 3, 3, translate({0, 0, 2}), 200));
  if (fog)
    add_object(s.get(), box({40, 40, 0}, {41, 41, 1}), add_volume_material(s.get(), volume(LT_VOLUME_PRINCIPLED, 1)));
  // A perspective camera: BDPT connects light vertices to it (t = 1), not to an orthographic one.
  set_camera(s.get(), perspective_camera(look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0})));
  check(lt_scene_commit(s.get()), "lt_scene_commit");
  return s;
}

TEST(Holdout, ObjectIsTransparentBlackAndClosureTakesItsWeightOfAlpha) {
  const int width = 32, height = 16, margin = 3;  // margin: past the pixel filter's reach
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    for (int transparent_film : {0, 1}) {
      SCOPED_TRACE("integrator " + std::to_string(integrator) + ", transparent film " +
                   std::to_string(transparent_film));
      ScenePtr s = holdout_scene(integrator == LT_INTEGRATOR_VOLPATH);
      lt_render_settings rs = render_settings(width, height, 16, 3);
      rs.integrator = integrator;
      rs.transparent_background = transparent_film;
      Passes p = render(s.get(), rs);
      ASSERT_EQ(p.first_non_finite(), "");
      double lit = 0;
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width / 2 - margin; ++x)
          for (int c = 0; c < 4; ++c) ASSERT_EQ(p.rgba(x, y)[c], 0.0f) << "held out pixel " << x << ", " << y;
        for (int x = width / 2 + margin; x < width; ++x) {
          ASSERT_NEAR(p.rgba(x, y)[3], 0.7f, 1e-5f) << "pixel " << x << ", " << y;
          lit += p.rgba(x, y)[0];
        }
      }
      EXPECT_GT(lit, 0.0);  // the Diffuse part of the mix is lit
    }
  }
}

}  // namespace
