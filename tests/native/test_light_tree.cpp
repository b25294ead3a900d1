// The light tree (scene/lights/light_tree.*): next-event estimation's pick at a shading point
// returns exactly the probability pmf_nee gives for that light, its frequencies follow those
// probabilities (chi-square, with a bin for "no light"), and renders of a many-light scene with
// the tree have the same mean as with the power pick, for the path tracer, the volumetric path
// tracer (points in a medium: no normal) and BDPT (s = 1 and its MIS weights).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "api/handles.h"
#include "chi2.h"
#include "core/film.h"
#include "integrators/bdpt_test_hooks.h"
#include "integrators/integrator.h"
#include "scene_builders.h"

namespace lt_test {
namespace {

// A room's floor and back wall lit by 48 lamps of every bounded kind (points with and without a
// radius, spots, rectangles and disks) of unequal powers, an emissive icosphere (80 triangles),
// a dim constant world and a sun: the tree holds 128 lights beside two infinite ones.
ScenePtr many_lights_scene(lt::LightSelection selection, bool fog = false) {
  ScenePtr s = new_scene();
  lt_scene* sc = s.get();
  const int grey = add_diffuse(sc, {0.6f, 0.6f, 0.6f});
  // A glossy floor under large lamps: BSDF samples often reach lamps, so MIS weights matter.
  add_object(sc, plane(6, 6), add_glossy(sc, {0.8f, 0.8f, 0.8f}, 0.4f));
  add_object(sc, plane(6, 3), grey, compose(translate({0, 3, 1.5f}), rotate({1, 0, 0}, 1.5707963f)));
  uint32_t state = 12345;
  auto rnd = [&]() {
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float(1 << 24);
  };
  for (int i = 0; i < 48; ++i) {
    const V3 p{-2.5f + 5 * rnd(), -2.5f + 5 * rnd(), 0.3f + 1.5f * rnd()};
    const float watts = 5 + 200 * rnd() * rnd();
    switch (i % 4) {
      case 0: {
        lt_light_desc l = point_light(p, watts);
        l.radius = i % 8 == 0 ? 0.1f : 0.0f;
        add_light(sc, l);
        break;
      }
      case 1:
        add_light(sc, spot_light(p, {p.x + rnd() - 0.5f, p.y + rnd() - 0.5f, 0}, watts, 0.6f + rnd(), 0.3f));
        break;
      case 2:
        add_light(sc, area_light(LT_AREA_RECTANGLE, 0.9f, 0.6f, look_at(p, {p.x, p.y + 0.3f, 0}), watts));
        break;
      default:
        add_light(sc, area_light(LT_AREA_DISK, 0.8f, 0.8f, look_at(p, {p.x + 0.5f, p.y, 0}), watts));
        break;
    }
  }
  add_object(sc, icosphere(0.3f, 1), add_emission(sc, {1, 0.8f, 0.6f}, 3), translate({1, 1, 0.8f}));
  set_world(sc, {0.2f, 0.3f, 0.4f}, 0.3f);
  // A sun with an angle: BDPT's weights do not sum to one with a delta sun (a known gap of
  // bdpt.cpp's, not of light picking: the power pick shows it too).
  add_light(sc, sun_light({0.3f, 0.4f, -1}, 0.5f, 0.05f));
  if (fog) {
    const int fog_material = add_volume_material(sc, volume(LT_VOLUME_PRINCIPLED, 0.5f));
    add_object(sc, box({-3, -3, 0.01f}, {3, 3, 2.9f}), fog_material);
  }
  set_camera(sc, perspective_camera(look_at({0, -7, 4}, {0, 0.5f, 0.5f}), 30));
  sc->scene.lights.set_selection(selection);
  check(lt_scene_commit(sc), "commit");
  return s;
}

TEST(LightTree, PickEqualsPmfAndFollowsItByChiSquare) {
  ScenePtr s = many_lights_scene(lt::LightSelection::Tree);
  const lt::LightSet& lights = s->scene.lights;
  ASSERT_EQ(lights.selection(), lt::LightSelection::Tree);
  ASSERT_EQ(lights.size(), 48u + 80u + 2u);
  ASSERT_EQ(lights.tree().node_count(), 2 * (48u + 80u) - 1);
  std::mt19937 gen(7);  // not the renderer's Sampler: independent of the sampler under test
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  auto u1 = [&]() { return std::min(uniform(gen), lt::kOneMinusEpsilon); };
  const int n_lights = int(lights.size());
  const double alpha = lt::test::sidak_alpha(0.01, lt::test::kChi2SuiteTests);
  for (int k = 0; k < 8; ++k) {
    // Shading points over the room, half on surfaces (a random normal), half in a medium.
    const lt::Vec3 p(-3 + 6 * u1(), -3 + 6 * u1(), 3 * u1());
    const lt::Vec3 n = k % 2 ? lt::Vec3(0.0f) : lt::sample_uniform_sphere(lt::Vec2{u1(), u1()});
    std::vector<double> pmf(n_lights);
    double total = 0;
    for (int l = 0; l < n_lights; ++l) {
      pmf[l] = lights.pmf_nee(p, n, l);
      ASSERT_TRUE(pmf[l] >= 0 && pmf[l] <= 1) << l;
      total += pmf[l];
    }
    ASSERT_LE(total, 1 + 1e-5) << "point " << k;
    // Every light of non-zero power that can reach p is in the tree: the lamps here all can.
    EXPECT_GT(total, 0.5) << "point " << k;
    const int N = 300000;
    std::vector<double> count(n_lights + 1, 0.0);  // the last bin: no light picked
    int mismatches = 0;
    for (int i = 0; i < N; ++i) {
      float q;
      const int l = lights.pick_nee(p, n, u1(), &q);
      if (l < 0) {
        count[n_lights] += 1;
        continue;
      }
      count[l] += 1;
      if (q != float(pmf[l])) ++mismatches;  // bit-exact: MIS divides by the same number
    }
    EXPECT_EQ(mismatches, 0) << "point " << k;
    // Pearson's test, bins of expected count below 5 pooled.
    std::vector<std::pair<double, double>> bins;  // expected, observed
    for (int l = 0; l < n_lights; ++l) {
      if (pmf[l] == 0) {
        EXPECT_EQ(count[l], 0) << "light " << l << " picked with pmf 0 at point " << k;
        continue;
      }
      bins.push_back({N * pmf[l], count[l]});
    }
    bins.push_back({N * std::max(0.0, 1 - total), count[n_lights]});
    std::sort(bins.begin(), bins.end());
    double chi2 = 0, pool_e = 0, pool_o = 0;
    int dof = -1;
    for (auto [e, o] : bins) {
      if (e < 5 || pool_e > 0) {
        pool_e += e;
        pool_o += o;
        if (pool_e < 5) continue;
        e = pool_e, o = pool_o;
        pool_e = pool_o = 0;
      }
      chi2 += (o - e) * (o - e) / e;
      ++dof;
    }
    if (pool_e > 0) chi2 += (pool_o - pool_e) * (pool_o - pool_e) / std::max(pool_e, 1e-9), ++dof;
    const double pv = lt::test::chi2_survival(chi2, dof);
    EXPECT_GT(pv, alpha) << "point " << k << ": chi2 " << chi2 << " dof " << dof;
  }
}

// The tree stays at most 63 levels deep (the bit trail's width) when splits find nothing: 100k
// lights at one point, and 100k on a line with geometric spacing; every light is reachable.
TEST(LightTree, DegenerateLayoutsStayShallowAndComplete) {
  for (int layout = 0; layout < 2; ++layout) {
    std::vector<lt::LightTree::Item> items;
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
      lt::LightBounds b;
      const lt::Vec3 p = layout == 0 ? lt::Vec3(1, 2, 3) : lt::Vec3(std::pow(1.0001f, float(i)), 0, 0);
      b.box.extend(p);
      b.phi = 1;
      b.cos_o = -1;
      b.cos_e = 0;
      items.push_back({i, b});
    }
    lt::LightTree tree;
    tree.build(items, n);
    ASSERT_EQ(tree.node_count(), size_t(2 * n - 1));
    const lt::Vec3 p(-5, 1, 0);
    double total = 0;
    for (int i = 0; i < n; ++i) total += tree.pmf(p, lt::Vec3(0.0f), i);
    EXPECT_NEAR(total, 1, 1e-3) << "layout " << layout;
  }
}

// Tree and power pick render the same means (per 8 x 8 tile and over the image). BDPT with its
// light subpaths cut to the light vertex: strategies s = 0 and s = 1, whose pixels are independent
// (splats would make the Variance pass understate the error); its other strategies' weights are
// checked by BdptMisWeightsSumToOne.
void expect_same_mean(int integrator, bool fog) {
  ScenePtr tree = many_lights_scene(lt::LightSelection::Tree, fog);
  ScenePtr power = many_lights_scene(lt::LightSelection::Power, fog);
  ASSERT_EQ(power->scene.lights.selection(), lt::LightSelection::Power);
  lt_render_settings st = render_settings(32, 24, fog ? 128 : 512, 3);
  st.integrator = integrator;
  if (integrator == LT_INTEGRATOR_BIDIRECTIONAL) st.max_light_length = 1;
  Passes a = render(tree.get(), st);
  st.seed = 4;
  Passes b = render(power.get(), st);
  ASSERT_EQ(a.first_non_finite(), "");
  ASSERT_EQ(b.first_non_finite(), "");
  EXPECT_EQ(differing_tiles(a, b, 8, kSigmas), "");
  for (int c = 0; c < 3; ++c) {
    RegionStats ra = region_stats(a, c, 0, a.width, 0, a.height), rb = region_stats(b, c, 0, b.width, 0, b.height);
    const double se = std::hypot(ra.standard_error, rb.standard_error);
    EXPECT_LT(std::abs(ra.mean - rb.mean), kSigmas * se)
        << "channel " << c << ": tree " << ra.mean << " se " << se << " power " << rb.mean;
  }
}

TEST(LightTree, PathMeanEqualsPowerPick) { expect_same_mean(LT_INTEGRATOR_PATH, false); }
TEST(LightTree, VolpathMeanEqualsPowerPick) { expect_same_mean(LT_INTEGRATOR_VOLPATH, true); }
TEST(LightTree, BdptMeanEqualsPowerPick) { expect_same_mean(LT_INTEGRATOR_BIDIRECTIONAL, false); }

// BDPT's weights of every strategy that can sample a path sum to one in the many-light scene,
// where s = 1 picks the light with the tree and light subpaths by power (mis_weight's lambda).
TEST(LightTree, BdptMisWeightsSumToOne) {
  ScenePtr s = many_lights_scene(lt::LightSelection::Tree);
  const lt::Scene& scene = s->scene;
  const int size = 32;
  lt::Camera camera(scene.camera, size, size);
  lt::FilterSampler filter(lt::FilterType::BlackmanHarris, 1.5f);
  lt::IntegratorSettings is;
  is.max_bounces = 6;
  is.max_light_length = 64;
  lt::RenderContext ctx{scene, camera, filter, is, 0, 0, size, size};
  int checked = 0;
  double worst = 0;
  for (int i = 0; i < 10000; ++i) {
    const int px = i % size, py = (i / size) % size;
    lt::Sampler sampler(11, uint32_t(py * size + px), uint32_t(i));
    lt::CameraSample cs;
    cs.pixel_center = {px + 0.5f, py + 0.5f};
    cs.film = cs.pixel_center;
    camera.generate(cs.film.x, cs.film.y, &cs.ray);
    for (float sum : lt::bdpt_mis_weight_sums(ctx, cs, sampler)) {
      ++checked;
      worst = std::max(worst, std::isfinite(sum) ? std::abs(sum - 1.0) : 1e9);
    }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_LT(worst, 1e-3) << checked << " paths";
}

}  // namespace
}  // namespace lt_test
