// Cycles' light passes (docs/passes.md): per pixel, (Direct + Indirect) x Colour summed over the
// diffuse, glossy and transmission kinds, plus Volume Direct and Indirect, Emission and
// Environment, gives Combined back, for every integrator that fills them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "program_builder.h"
#include "scene_builders.h"

using namespace lt_test;

namespace {

// A Cornell-like box open towards the camera (the world seen past it), a rough glossy sphere, a
// sharp glass sphere, a rough glass sphere, a fog box and a square lamp under the ceiling.
ScenePtr passes_scene() {
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  const float half_pi = float(kPi / 2);
  const int white = add_diffuse(s, {0.73f, 0.73f, 0.73f}), red = add_diffuse(s, {0.65f, 0.05f, 0.05f});
  const int green = add_diffuse(s, {0.12f, 0.45f, 0.15f});
  add_object(s, plane(2, 6), white, translate({0, -2, 0}));
  add_object(s, plane(2, 2), white, compose(translate({0, 0, 2}), rotate({1, 0, 0}, 2 * half_pi)));
  add_object(s, plane(2, 2), white, compose(translate({0, 1, 1}), rotate({1, 0, 0}, half_pi)));
  add_object(s, plane(2, 2), red, compose(translate({-1, 0, 1}), rotate({0, 1, 0}, half_pi)));
  add_object(s, plane(2, 2), green, compose(translate({1, 0, 1}), rotate({0, 1, 0}, -half_pi)));
  add_object(s, icosphere(0.3f, 3), add_glossy(s, {0.9f, 0.8f, 0.6f}, 0.3f), translate({-0.5f, 0.3f, 0.3f}));
  add_object(s, uv_sphere(0.3f, 24, 12, true), add_glass(s, {1, 1, 1}, 0, 1.5f), translate({0.45f, -0.2f, 0.3f}));
  add_object(s, uv_sphere(0.2f, 16, 8, true), add_glass(s, {0.9f, 1, 0.9f}, 0.3f, 1.4f),
             translate({0.0f, -0.4f, 1.2f}));
  add_object(s, box({-0.9f, -0.9f, 0.8f}, {-0.2f, 0.2f, 1.6f}),
             add_volume_material(s, volume(LT_VOLUME_PRINCIPLED, 1.0f, 0.8f, 0.2f)));
  // A rough glass pane under the lamp, seen from below: the lamp lights it through (TransDir).
  add_object(s, plane(1.0f, 0.8f), add_glass(s, {1, 1, 1}, 0.4f, 1.5f),
             compose(translate({0.1f, 0.1f, 1.55f}), rotate({1, 0, 0}, -0.7f)));
  add_object(s, plane(0.3f, 0.3f), add_emission(s, {1, 0.9f, 0.7f}, 4),
             compose(translate({0.5f, 0.99f, 0.5f}), rotate({1, 0, 0}, half_pi)));
  add_light(s, area_light(LT_AREA_SQUARE, 0.5f, 0.5f, look_at({0, 0, 1.98f}, {0, 0, 0}, {0, 1, 0}), 60));
  set_world(s, {0.3f, 0.4f, 0.6f}, 0.5f);
  set_camera(s, perspective_camera(look_at({0, -4.0f, 1}, {0, 0, 1}), 35));
  check(lt_scene_commit(s), "commit");
  return sp;
}

// Pixels whose recombined light passes differ from Combined by more than float rounding, and the
// largest relative difference, for the integrator of `rs`.
struct Recombination {
  int bad = 0, pixels = 0;
  // Pixels off only where light-tracing splats (BDPT's t = 1) reached a kind whose Colour is zero
  // there: Cycles' division leaves such light out of the light passes (docs/passes.md).
  int zero_colour = 0;
  double worst = 0;
  std::string first;
};

Recombination recombine(const Passes& p, bool splats) {
  Recombination r;
  const int n = p.width * p.height;
  for (int i = 0; i < n; ++i) {
    ++r.pixels;
    bool bad = false, zero_colour = false, off = false;
    for (int col : {LT_PASS_DIFFUSE_COLOR, LT_PASS_GLOSSY_COLOR, LT_PASS_TRANSMISSION_COLOR}) {
      const float* c = &p.pass(col)[3 * i];
      zero_colour = zero_colour || (c[0] == 0 && c[1] == 0 && c[2] == 0);
    }
    for (int c = 0; c < 3; ++c) {
      double sum = 0, scale = std::abs(p.combined[4 * i + c]);
      auto v = [&](int pass) { return double(p.pass(pass)[3 * i + c]); };
      const int kinds[3][3] = {
          {LT_PASS_DIFFUSE_DIRECT, LT_PASS_DIFFUSE_INDIRECT, LT_PASS_DIFFUSE_COLOR},
          {LT_PASS_GLOSSY_DIRECT, LT_PASS_GLOSSY_INDIRECT, LT_PASS_GLOSSY_COLOR},
          {LT_PASS_TRANSMISSION_DIRECT, LT_PASS_TRANSMISSION_INDIRECT, LT_PASS_TRANSMISSION_COLOR}};
      for (const auto& k : kinds) {
        const double part = (v(k[0]) + v(k[1])) * v(k[2]);
        sum += part;
        scale += std::abs(v(k[0]) * v(k[2])) + std::abs(v(k[1]) * v(k[2]));
      }
      for (int pass : {LT_PASS_VOLUME_DIRECT, LT_PASS_VOLUME_INDIRECT, LT_PASS_EMISSION, LT_PASS_ENVIRONMENT}) {
        sum += v(pass);
        scale += std::abs(v(pass));
      }
      // Float rounding: each pass is a float mean of its own sums (and a quotient and product).
      const double diff = std::abs(sum - p.combined[4 * i + c]), tol = 1e-5 * scale + 1e-7;
      off = off || diff > tol;
      if (diff > tol && !(splats && zero_colour)) {
        bad = true;
        if (r.first.empty())
          r.first = "pixel " + std::to_string(i) + " channel " + std::to_string(c) + ": passes " + std::to_string(sum) +
                    ", combined " + std::to_string(p.combined[4 * i + c]);
      }
      if (scale > 0) r.worst = std::max(r.worst, diff / scale);
    }
    r.bad += bad;
    r.zero_colour += splats && zero_colour && off;
  }
  return r;
}

// Which passes carry light at all: each kind must show up in this scene, or the check is empty.
double pass_total(const Passes& p, int pass) {
  double t = 0;
  for (float x : p.pass(pass)) t += std::abs(x);
  return t;
}

void expect_recombines(int integrator, int samples) {
  ScenePtr s = passes_scene();
  lt_render_settings rs = render_settings(32, 24, samples, 3);
  rs.integrator = integrator;
  rs.volume_bounces = 2;
  const Passes p = render(s.get(), rs);
  ASSERT_EQ(p.first_non_finite(), "");
  const Recombination r = recombine(p, integrator == LT_INTEGRATOR_BIDIRECTIONAL);
  // The silhouettes against the world: a pixel or two wide.
  EXPECT_LT(r.zero_colour, r.pixels / 5);
  EXPECT_EQ(r.bad, 0) << r.bad << " of " << r.pixels << " pixels; first " << r.first << "; worst relative " << r.worst;
  for (int pass : {LT_PASS_DIFFUSE_DIRECT, LT_PASS_DIFFUSE_INDIRECT, LT_PASS_DIFFUSE_COLOR, LT_PASS_GLOSSY_DIRECT,
                   LT_PASS_GLOSSY_INDIRECT, LT_PASS_GLOSSY_COLOR, LT_PASS_TRANSMISSION_DIRECT,
                   LT_PASS_TRANSMISSION_INDIRECT, LT_PASS_TRANSMISSION_COLOR, LT_PASS_EMISSION, LT_PASS_ENVIRONMENT})
    EXPECT_GT(pass_total(p, pass), 0) << "pass " << pass << " is empty";
  if (integrator != LT_INTEGRATOR_PATH) {
    EXPECT_GT(pass_total(p, LT_PASS_VOLUME_DIRECT), 0);
    EXPECT_GT(pass_total(p, LT_PASS_VOLUME_INDIRECT), 0);
  } else {
    EXPECT_EQ(pass_total(p, LT_PASS_VOLUME_DIRECT), 0);  // PATH renders no media
  }
}

}  // namespace

TEST(Passes, LightPassesRecombineToCombinedPath) { expect_recombines(LT_INTEGRATOR_PATH, 16); }
TEST(Passes, LightPassesRecombineToCombinedVolPath) { expect_recombines(LT_INTEGRATOR_VOLPATH, 16); }
TEST(Passes, LightPassesRecombineToCombinedBidirectional) { expect_recombines(LT_INTEGRATOR_BIDIRECTIONAL, 8); }

// ---- Ambient Occlusion (Cycles' integrate_surface_ao) ------------------------------------------

namespace {

// A floor and, 1 above it, a ceiling (both 200 wide: infinite for rays of length <= 2), seen from
// between them looking straight down. A cosine-distributed ray from the floor meets the ceiling at
// distance 1 / cos(theta): within the AO distance d exactly when cos(theta) > 1 / d, which has
// probability 1 - 1/d^2, so the AO pass is 1/d^2 (d >= 1), and 1 for d < 1. A ceiling that
// passes a fraction t of light (a Transparent BSDF of colour t) gives 1/d^2 + (1 - 1/d^2) t.
ScenePtr ao_scene(float ceiling_transparency) {
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  add_object(s, plane(200, 200), add_diffuse(s, {0.5f, 0.4f, 0.3f}));  // the pass is not the albedo
  int ceiling = add_diffuse(s, {0.8f, 0.8f, 0.8f});
  if (ceiling_transparency > 0) {
    ShaderCode p;
    p.transparent(p.one(), {ceiling_transparency, ceiling_transparency, ceiling_transparency});
    ceiling = add_material(s, p);
  }
  add_object(s, plane(200, 200), ceiling, translate({0, 0, 1}));
  set_world(s, {0.3f, 0.4f, 0.6f}, 1);
  set_camera(s, perspective_camera(look_at({0, 0, 0.5f}, {0, 0, 0}, {0, 1, 0}), 35));
  check(lt_scene_commit(s), "commit");
  return sp;
}

Passes render_ao(lt_scene* s, int integrator, float distance, bool ao) {
  lt_render_settings rs = render_settings(32, 24, 16, 5);
  rs.integrator = integrator;
  rs.ao_distance = distance;
  if (ao) rs.passes |= 1u << LT_PASS_AO;
  return render(s, rs);
}

// The AO pass's mean over the image and over 8 x 8 tiles against `expected`. Each sample's value
// is 0 or 1 (or, through the ceiling, 0..1 with variance at most that), so a mean of N samples has
// a standard error at most sqrt(e (1 - e) / N) for independent samples (the Sobol' points only
// lower it); 5 of them for the image, and Bonferroni's z for the 12 tiles (family 1e-3: 4.0).
void expect_ao(const Passes& p, double expected, const char* what) {
  const std::vector<float>& ao = p.pass(LT_PASS_AO);
  ASSERT_EQ(ao.size(), size_t(3 * p.width * p.height)) << what;
  const double var = std::max(expected * (1 - expected), 1e-12);
  double total = 0;
  for (int ty = 0; ty < p.height; ty += 8)
    for (int tx = 0; tx < p.width; tx += 8) {
      double sum = 0;
      for (int y = ty; y < ty + 8; ++y)
        for (int x = tx; x < tx + 8; ++x) {
          const float* v = &ao[3 * (size_t(y) * p.width + x)];
          EXPECT_TRUE(v[0] == v[1] && v[1] == v[2]) << what << ": grey rays give a grey pass";
          sum += v[0];
        }
      const double mean = sum / 64, se = std::sqrt(var / (64.0 * 16));
      EXPECT_NEAR(mean, expected, 4.0 * se + 1e-6) << what << " tile (" << tx << ", " << ty << ")";
      total += sum;
    }
  const double mean = total / (p.width * p.height), se = std::sqrt(var / (p.width * p.height * 16.0));
  EXPECT_NEAR(mean, expected, 5 * se + 1e-6) << what << ": image mean";
}

}  // namespace

TEST(Passes, AmbientOcclusionIsTheUnoccludedCosineFraction) {
  ScenePtr s = ao_scene(0), glass = ao_scene(0.5f);
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    const std::string name = "integrator " + std::to_string(integrator);
    const Passes p = render_ao(s.get(), integrator, 2, true);
    ASSERT_EQ(p.first_non_finite(), "");
    expect_ao(p, 0.25, (name + ", distance 2").c_str());
    expect_ao(render_ao(s.get(), integrator, 0.9f, true), 1.0, (name + ", distance 0.9").c_str());
    expect_ao(render_ao(glass.get(), integrator, 2, true), 0.25 + 0.75 * 0.5, (name + ", transparent").c_str());
    // The pass draws no random number of the path's: Combined is the same bits without it, and
    // a render that does not ask for it keeps no AO pass.
    const Passes without = render_ao(s.get(), integrator, 2, false);
    EXPECT_TRUE(without.pass(LT_PASS_AO).empty());
    EXPECT_EQ(std::memcmp(without.combined.data(), p.combined.data(), p.combined.size() * sizeof(float)), 0) << name;
  }
}
