// Shader AOVs as Cycles 3.4 writes them (AOV Output, film/aov_passes.h): the camera path adds its
// AOV values at each surface it meets through transparent passes up to the first whose alpha
// reaches the pass alpha threshold (integrators/path_state.h, single_pass_done); a colour AOV's
// fourth channel counts the writes. Every integrator alike.
#include <gtest/gtest.h>

#include <cmath>

#include "program_builder.h"
#include "scene_builders.h"
#include "shading/shaders.h"

namespace {

using namespace lt_test;

// A diffuse material that writes colour `c` to AOV 0 and `value` to AOV 1; `transparent`: the
// weight of a Transparent BSDF mixed in (alpha 1 - transparent).
int aov_material(lt_scene* s, Rgb c, float value, float transparent) {
  ShaderCode p;
  auto w = p.mix(p.one(), transparent);
  p.diffuse(w.first, {0.8f, 0.8f, 0.8f});
  if (transparent > 0) p.transparent(w.second, {1, 1, 1});
  p.emit(lt::kOpAovColor, {p.c3(c)}, {}, {0});
  p.emit(lt::kOpAovValue, {p.c1(value)}, {}, {1});
  return add_material(s, p);
}

// Seen from above: an opaque plane writing (0.2, 0.4, 0.6) and 0.7; over its right half a card of
// alpha 0.3 (Diffuse 0.8 x 0.3, Transparent 0.7) writing (1, 0, 0) and 0.25, which the camera
// passes with probability 0.7 / (0.7 + 0.24), the Transparent weight's share (Cycles' choice).
ScenePtr aov_scene(bool fog) {
  ScenePtr s = new_scene();
  set_world(s.get(), {0.2f, 0.2f, 0.2f}, 1);
  add_object(s.get(), plane(8, 8), aov_material(s.get(), {0.2f, 0.4f, 0.6f}, 0.7f, 0));
  add_object(s.get(), plane(4, 8), aov_material(s.get(), {1, 0, 0}, 0.25f, 0.7f), translate({2, 0, 0.5f}));
  add_light(s.get(), area_light(LT_AREA_SQUARE, 2, 2, translate({0, 0, 3}), 100));
  if (fog)
    add_object(s.get(), box({40, 40, 0}, {41, 41, 1}), add_volume_material(s.get(), volume(LT_VOLUME_SCATTER, 1)));
  set_camera(s.get(), perspective_camera(look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0})));
  check(lt_scene_commit(s.get()), "lt_scene_commit");
  return s;
}

struct AovRender {
  std::vector<float> colour, value;  // RGBA, X
};

AovRender render_aovs(lt_scene* s, lt_render_settings rs) {
  const char* names[] = {"paint", "mask"};
  const int colours[] = {1, 0};
  rs.aov_count = 2;
  rs.aov_names = names;
  rs.aov_colors = colours;
  lt_render* raw = nullptr;
  check(lt_render_start(s, &rs, &raw), "lt_render_start");
  RenderPtr r(raw);
  check(lt_render_wait(r.get()), "lt_render_wait");
  AovRender out;
  out.colour.resize(size_t(rs.width) * rs.height * 4);
  out.value.resize(size_t(rs.width) * rs.height);
  check(lt_render_read_aov_rows(r.get(), 0, 0, rs.height, out.colour.data(), out.colour.size()), "read AOV 0");
  check(lt_render_read_aov_rows(r.get(), 1, 0, rs.height, out.value.data(), out.value.size()), "read AOV 1");
  return out;
}

TEST(Aovs, WrittenThroughTransparentSurfacesUpToTheAlphaThreshold) {
  const int width = 32, height = 16, margin = 3;  // margin: past the pixel filter's reach of the card's edge
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    SCOPED_TRACE("integrator " + std::to_string(integrator));
    ScenePtr s = aov_scene(integrator == LT_INTEGRATOR_VOLPATH);
    lt_render_settings rs = render_settings(width, height, 16, 9);
    rs.integrator = integrator;
    AovRender a = render_aovs(s.get(), rs);
    double behind = 0;
    int card = 0;
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width / 2 - margin; ++x) {  // the opaque plane alone: exact
        const float* c = &a.colour[(size_t(y) * width + x) * 4];
        ASSERT_NEAR(c[0], 0.2f, 1e-6f);
        ASSERT_NEAR(c[1], 0.4f, 1e-6f);
        ASSERT_NEAR(c[2], 0.6f, 1e-6f);
        ASSERT_EQ(c[3], 1.0f);
        ASSERT_NEAR(a.value[size_t(y) * width + x], 0.7f, 1e-6f);
      }
      for (int x = width / 2 + margin; x < width; ++x) {  // the card always, the plane when passed
        const float* c = &a.colour[(size_t(y) * width + x) * 4];
        const float passed = c[3] - 1;  // the fraction of samples that reached the plane
        ASSERT_NEAR(c[0], 1 + 0.2f * passed, 1e-5f);
        ASSERT_NEAR(c[2], 0.6f * passed, 1e-5f);
        ASSERT_NEAR(a.value[size_t(y) * width + x], 0.25f + 0.7f * passed, 1e-5f);
        behind += passed;
        ++card;
      }
    }
    // 16 samples per pixel: the mean over the card's n pixels has a standard error of at most
    // sqrt(p (1 - p) / (16 n)) (less: the samples are stratified); within 5 of them.
    const double p = 0.7 / (0.7 + 0.3 * 0.8), se = std::sqrt(p * (1 - p) / (16.0 * card));
    EXPECT_NEAR(behind / card, p, 5 * se);

    // With the threshold at 0.2 the card (alpha 0.3) is the last surface written: exactly.
    rs.pass_alpha_threshold = 0.2f;
    AovRender t = render_aovs(s.get(), rs);
    for (int y = 0; y < height; ++y)
      for (int x = width / 2 + margin; x < width; ++x) {
        const float* c = &t.colour[(size_t(y) * width + x) * 4];
        ASSERT_EQ(c[0], 1.0f);
        ASSERT_EQ(c[2], 0.0f);
        ASSERT_EQ(c[3], 1.0f);
        ASSERT_NEAR(t.value[size_t(y) * width + x], 0.25f, 1e-6f);
      }
  }
}

// The World's AOV Outputs (Cycles evaluates the background shader, AOVs included, where a camera
// ray escapes through transparent passes; shade_background.h, svm_node_aov_check): the plane of
// aov_scene on the left half only, over the sky on the right the card, which the camera passes
// to the world with probability p; the world writes (0.9, 0.5, 0.1) and 0.3. Not through an opaque
// surface, not with a transparent film (Cycles does not evaluate the world there).
TEST(Aovs, TheWorldWritesWhereTheCameraRayEscapes) {
  ScenePtr s = new_scene();
  ShaderCode w;
  w.emission(w.one(), {0.2f, 0.2f, 0.2f}, 1);
  w.emit(lt::kOpAovColor, {w.c3({0.9f, 0.5f, 0.1f})}, {}, {0});
  w.emit(lt::kOpAovValue, {w.c1(0.3f)}, {}, {1});
  const lt_shader_program world = w.desc();
  check(lt_scene_set_world_program(s.get(), &world, 0, LT_VISIBLE_CAMERA), "lt_scene_set_world_program");
  add_object(s.get(), plane(4, 8), aov_material(s.get(), {0.2f, 0.4f, 0.6f}, 0.7f, 0), translate({-2, 0, 0}));
  add_object(s.get(), plane(4, 8), aov_material(s.get(), {1, 0, 0}, 0.25f, 0.7f), translate({2, 0, 0.5f}));
  add_light(s.get(), area_light(LT_AREA_SQUARE, 2, 2, translate({0, 0, 3}), 100));
  set_camera(s.get(), perspective_camera(look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0})));
  check(lt_scene_commit(s.get()), "lt_scene_commit");
  const int width = 32, height = 16, margin = 3;
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    SCOPED_TRACE("integrator " + std::to_string(integrator));
    lt_render_settings rs = render_settings(width, height, 16, 9);
    rs.integrator = integrator;
    for (bool film_transparent : {false, true}) {
      rs.transparent_background = film_transparent;
      const AovRender a = render_aovs(s.get(), rs);
      double escaped = 0;
      int card = 0;
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width / 2 - margin; ++x) {  // the opaque plane: its own AOVs alone
          const float* c = &a.colour[(size_t(y) * width + x) * 4];
          ASSERT_NEAR(c[0], 0.2f, 1e-6f);
          ASSERT_EQ(c[3], 1.0f);
          ASSERT_NEAR(a.value[size_t(y) * width + x], 0.7f, 1e-6f);
        }
        for (int x = width / 2 + margin; x < width; ++x) {
          const float* c = &a.colour[(size_t(y) * width + x) * 4];
          const float passed = c[3] - 1;  // the share of samples that escaped past the card
          if (film_transparent) ASSERT_EQ(passed, 0.0f);
          ASSERT_NEAR(c[0], 1 + 0.9f * passed, 1e-5f);
          ASSERT_NEAR(c[1], 0.5f * passed, 1e-5f);
          ASSERT_NEAR(c[2], 0.1f * passed, 1e-5f);
          ASSERT_NEAR(a.value[size_t(y) * width + x], 0.25f + 0.3f * passed, 1e-5f);
          escaped += passed;
          ++card;
        }
      }
      if (film_transparent) continue;
      const double p = 0.7 / (0.7 + 0.3 * 0.8), se = std::sqrt(p * (1 - p) / (16.0 * card));  // as above
      EXPECT_NEAR(escaped / card, p, 5 * se);
    }
  }
}

}  // namespace
