// Light groups (Cycles' Combined_<group> passes): each is the radiance from its group's emitters,
// so where every emitter is in a group they sum to Combined's RGB per pixel, for every integrator
// (BDPT's light-tracing splats included); an emitter in no group is in none of them.
#include <gtest/gtest.h>

#include "scene_builders.h"

namespace {

using namespace lt_test;

// A floor and a glossy sphere lit by two area lights (groups 1 and 2: the core's k - 1), an
// emissive quad (group 2) and the world (group 1); with fog, a fog box around the sphere.
// `ungrouped`: the second area light is in no group.
ScenePtr grouped_scene(bool fog, bool ungrouped) {
  ScenePtr s = new_scene();
  set_world(s.get(), {0.1f, 0.15f, 0.2f}, 1);
  check(lt_scene_set_world_lightgroup(s.get(), 1), "lt_scene_set_world_lightgroup");
  add_object(s.get(), plane(8, 8), add_diffuse(s.get(), {0.7f, 0.7f, 0.7f}));
  add_object(s.get(), uv_sphere(0.6f, 24, 12, true), add_glossy(s.get(), {0.9f, 0.8f, 0.6f}, 0.2f),
             translate({0, 0, 0.6f}));
  const int lamp_mesh = add_mesh(s.get(), plane(0.4f, 0.4f)), emission = add_emission(s.get(), {1, 0.8f, 0.6f}, 20);
  add_instance(s.get(), lamp_mesh, emission, compose(translate({1.2f, 0.5f, 1.5f}), rotate({1, 0, 0}, 3.14159f)),
               LT_VISIBLE_ALL, 2);
  lt_light_desc a = area_light(LT_AREA_SQUARE, 1, 1, translate({-1, -1, 3}), 150);
  a.lightgroup = 1;
  add_light(s.get(), a);
  lt_light_desc b = area_light(LT_AREA_DISK, 0.5f, 0.5f, translate({1, -1.5f, 2.5f}), 80);
  b.lightgroup = ungrouped ? 0 : 2;
  add_light(s.get(), b);
  if (fog)
    add_object(s.get(), box({-1, -1, 0}, {1, 1, 1.5f}), add_volume_material(s.get(), volume(LT_VOLUME_SCATTER, 0.3f)));
  set_camera(s.get(), perspective_camera(look_at({0, -5, 2.5f}, {0, 0, 0.5f})));
  check(lt_scene_commit(s.get()), "lt_scene_commit");
  return s;
}

struct GroupedRender {
  Passes passes;
  std::vector<float> group[2];
};

GroupedRender render_groups(lt_scene* s, lt_render_settings rs) {
  const char* names[] = {"key", "fill"};
  rs.lightgroup_count = 2;
  rs.lightgroup_names = names;
  lt_render* raw = nullptr;
  check(lt_render_start(s, &rs, &raw), "lt_render_start");
  RenderPtr r(raw);
  check(lt_render_wait(r.get()), "lt_render_wait");
  GroupedRender out;
  out.passes = read_passes(r.get(), rs.width, rs.height);
  for (int g = 0; g < 2; ++g) {
    out.group[g].resize(size_t(rs.width) * rs.height * 3);
    check(lt_render_read_lightgroup_rows(r.get(), g, 0, rs.height, out.group[g].data(), out.group[g].size()),
          "lt_render_read_lightgroup_rows");
  }
  return out;
}

// Per pixel, the two groups sum to Combined's RGB; totals: each group's sum over the image.
void expect_groups_sum_to_combined(const GroupedRender& g, int width, int height, double totals[2]) {
  ASSERT_EQ(g.passes.first_non_finite(), "");
  totals[0] = totals[1] = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t i = (size_t(y) * width + x) * 3 + c;
        const float combined = g.passes.rgba(x, y)[c], sum = g.group[0][i] + g.group[1][i];
        ASSERT_NEAR(sum, combined, 1e-4f * std::abs(combined) + 1e-6f) << "pixel " << x << ", " << y;
        totals[0] += g.group[0][i];
        totals[1] += g.group[1][i];
      }
}

TEST(Lightgroups, SumToCombinedPerPixelForEveryIntegrator) {
  const int width = 24, height = 18;
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    SCOPED_TRACE("integrator " + std::to_string(integrator));
    ScenePtr s = grouped_scene(integrator == LT_INTEGRATOR_VOLPATH, false);
    lt_render_settings rs = render_settings(width, height, 8, 5);
    rs.integrator = integrator;
    GroupedRender g = render_groups(s.get(), rs);
    double total[2];
    expect_groups_sum_to_combined(g, width, height, total);
    EXPECT_GT(total[0], 0.0);  // both groups light the image
    EXPECT_GT(total[1], 0.0);
  }
}

TEST(Lightgroups, AnUngroupedEmitterIsInNone) {
  // The disk light in no group: the groups' sum is Combined without it, less than Combined.
  ScenePtr s = grouped_scene(false, true);
  lt_render_settings rs = render_settings(24, 18, 8, 5);
  GroupedRender g = render_groups(s.get(), rs);
  double combined = 0, groups = 0;
  for (int y = 0; y < rs.height; ++y)
    for (int x = 0; x < rs.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t i = (size_t(y) * rs.width + x) * 3 + c;
        combined += g.passes.rgba(x, y)[c];
        groups += g.group[0][i] + g.group[1][i];
      }
  EXPECT_LT(groups, 0.95 * combined);
  // Without light groups the render keeps none (and reading one is an error).
  lt_render* raw = nullptr;
  check(lt_render_start(s.get(), &rs, &raw), "lt_render_start");
  RenderPtr r(raw);
  check(lt_render_wait(r.get()), "lt_render_wait");
  std::vector<float> buf(size_t(rs.width) * rs.height * 3);
  EXPECT_EQ(lt_render_read_lightgroup_rows(r.get(), 0, 0, rs.height, buf.data(), buf.size()),
            LT_ERROR_INVALID_ARGUMENT);
  // ...and its Combined is the same bits: light groups draw no random number.
  const Passes plain = read_passes(r.get(), rs.width, rs.height);
  EXPECT_EQ(plain.combined, g.passes.combined);
}

// Volume emission in light groups (Cycles files it under the emitting volume's object,
// shade_volume.h): a scattering and emitting box (group `box_group`, 0: none) around a diffuse
// sphere, a second emitting box overlapping it (group 2, twice the emission) and an area light
// (group 2). Everything else is black.
ScenePtr emissive_volume_scene(int box_group) {
  ScenePtr s = new_scene();
  set_world(s.get(), {0, 0, 0}, 0);
  add_object(s.get(), plane(8, 8), add_diffuse(s.get(), {0.7f, 0.7f, 0.7f}));
  add_object(s.get(), uv_sphere(0.4f, 24, 12, true), add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}), translate({0, 0, 0.6f}));
  auto emissive_box = [&](const lt_volume_desc& scatter, float strength, const float color[3], float x0, float x1,
                          int group) {
    lt_volume_desc c[2] = {scatter, volume(LT_VOLUME_EMISSION, 0.0f)};
    c[1].emission_strength = strength;
    std::copy(color, color + 3, c[1].emission_color);
    const int material = add_volume_material(s.get(), c, 2);
    add_instance(s.get(), add_mesh(s.get(), box({x0, -1, 0}, {x1, 1, 1.5f})), material, identity(), LT_VISIBLE_ALL,
                 group);
  };
  const float warm[3] = {1.0f, 0.6f, 0.3f}, cool[3] = {0.3f, 0.6f, 1.0f};
  emissive_box(volume(LT_VOLUME_SCATTER, 0.4f), 0.5f, warm, -1.2f, 0.6f, box_group);
  emissive_box(volume(LT_VOLUME_ABSORPTION, 0.2f), 1.0f, cool, 0.2f, 1.4f, 2);
  lt_light_desc a = area_light(LT_AREA_SQUARE, 1, 1, translate({-1, -1, 3}), 100);
  a.lightgroup = 2;
  add_light(s.get(), a);
  set_camera(s.get(), perspective_camera(look_at({0, -5, 2.5f}, {0, 0, 0.5f})));
  check(lt_scene_commit(s.get()), "lt_scene_commit");
  return s;
}

// make(group) builds a scene whose one emitter under test is in `group` (1, or 0: none) and every
// other emitter in group 2. Every emitter grouped: the groups sum to Combined per pixel. Group 1
// holds the emitter's light alone: the same render with it in no group has the same Combined
// (light groups draw no random number) and its light in neither group, so its Combined minus its
// groups is group 1 there.
void expect_group_one_holds_the_emitter(ScenePtr (*make)(int)) {
  const int width = 24, height = 18;
  for (int integrator : {LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    SCOPED_TRACE("integrator " + std::to_string(integrator));
    ScenePtr s = make(1);
    lt_render_settings rs = render_settings(width, height, 8, 5);
    rs.integrator = integrator;
    const GroupedRender g = render_groups(s.get(), rs);
    double total[2];
    expect_groups_sum_to_combined(g, width, height, total);
    const double key = total[0];
    ScenePtr u = make(0);
    const GroupedRender h = render_groups(u.get(), rs);
    EXPECT_EQ(h.passes.combined, g.passes.combined);
    double rest = 0;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        for (int c = 0; c < 3; ++c) {
          const size_t i = (size_t(y) * width + x) * 3 + c;
          EXPECT_EQ(h.group[0][i], 0.0f);
          EXPECT_EQ(h.group[1][i], g.group[1][i]);
          rest += h.passes.rgba(x, y)[c] - h.group[1][i];
        }
    EXPECT_GT(key, 0.0);
    EXPECT_NEAR(rest, key, 1e-4 * key);
  }
}

TEST(Lightgroups, VolumeEmissionIsInItsObjectsGroup) { expect_group_one_holds_the_emitter(emissive_volume_scene); }

// A Volume object's emission (fire.vdb: Emission Strength from its 'flame' grid, blackbody from
// 'temperature') is in the group its object is put in (lt_scene_set_volume_grid_lightgroup; 0:
// none), here overlapping an emitting mesh volume of group 2.
ScenePtr emissive_grid_scene(int grid_group) {
  ScenePtr s = new_scene();
  set_world(s.get(), {0, 0, 0}, 0);
  add_object(s.get(), plane(8, 8), add_diffuse(s.get(), {0.7f, 0.7f, 0.7f}));
  lt_volume_desc fire = volume(LT_VOLUME_PRINCIPLED, 2.0f, 0.5f);
  fire.emission_strength = 1.0f;
  fire.emission_strength_grid = "flame";
  const float orange[3] = {1.0f, 0.45f, 0.1f}, white[3] = {1, 1, 1};
  std::copy(orange, orange + 3, fire.emission_color);
  fire.blackbody_intensity = 1.0f;
  std::copy(white, white + 3, fire.blackbody_tint);
  fire.temperature = 1500.0f;
  fire.temperature_attribute = "temperature";
  Xform xf = identity();
  int id = -1;
  check(lt_scene_add_volume_grid(s.get(), (std::string(LANTERN_TEST_VDB_DIR) + "/fire.vdb").c_str(), "density",
                                 xf.data(), 0, 0.001f, 0.0f, &fire, 1, &id),
        "lt_scene_add_volume_grid");
  check(lt_scene_set_volume_grid_lightgroup(s.get(), id, grid_group), "lt_scene_set_volume_grid_lightgroup");
  lt_volume_desc c[2] = {volume(LT_VOLUME_ABSORPTION, 0.2f), volume(LT_VOLUME_EMISSION, 0.0f)};
  c[1].emission_strength = 0.3f;
  add_instance(s.get(), add_mesh(s.get(), box({0.1f, -1, 0}, {1.4f, 1, 1.5f})), add_volume_material(s.get(), c, 2),
               identity(), LT_VISIBLE_ALL, 2);
  set_camera(s.get(), perspective_camera(look_at({0, -5, 1.5f}, {0, 0, 0.7f})));
  check(lt_scene_commit(s.get()), "lt_scene_commit");
  return s;
}

TEST(Lightgroups, VolumeObjectEmissionIsInItsObjectsGroup) { expect_group_one_holds_the_emitter(emissive_grid_scene); }

}  // namespace
