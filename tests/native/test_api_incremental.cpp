// Incremental edits of a committed scene (the viewport's updates): moving an instance rebuilds
// only the top-level BVH, a material or light edit only the light sampler, a camera change or an
// instance's Object Info values nothing (its ray visibility the top level); and each edited scene
// renders bit for bit like a scene
// built from scratch in its final state (a sample's random numbers depend only on seed, pixel and
// sample index).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "scene_builders.h"

using namespace lt_test;

namespace {

struct Params {
  V3 box_at{0, 0, 0};
  V3 panel_at{0, 1.5f, 1.2f};
  V3 box_color{0.8f, 0.8f, 0.8f};
  float lamp_watts = 300;
  V3 eye{0.5f, -5, 2.5f};
  bool panel_emits = true;
  // The box's Object Info colour and pass index and its object attribute 5, which its material
  // reads when box_reads_object is set.
  bool box_reads_object = false;
  float box_object_color[4] = {0.2f, 0.6f, 0.9f, 1};
  int box_pass_index = 1;
  float box_tint[4] = {0.3f, 0.1f, 0.05f, 1};
  unsigned box_visibility = LT_VISIBLE_ALL;
};

constexpr int kTintId = 5;

ShaderCode diffuse_program(V3 c) {
  ShaderCode p;
  p.diffuse(p.one(), {c.x, c.y, c.z});
  return p;
}

ShaderCode panel_program(bool emits) {
  if (!emits) return diffuse_program({0.5f, 0.5f, 0.5f});
  ShaderCode p;
  p.emission(p.one(), {1, 1, 1}, 5);
  return p;
}

// Diffuse of Object Info's colour, emitting the object attribute kTintId's colour at a strength
// of the object's pass index.
ShaderCode object_program() {
  ShaderCode p;
  const std::vector<uint32_t> info = p.emit(lt::kOpObjectInfo, {}, {3, 3, 1, 1, 1});
  const std::vector<uint32_t> tint = p.emit(lt::kOpAttribute, {}, {3, 1, 1}, {kTintId, 1, 0});
  const uint32_t one = p.one();
  p.emit(lt::kOpDiffuse, {one, p.c3({0, 0, 0}), info[1], p.c1(0)}, {});
  p.emit(lt::kOpEmission, {one, tint[0], info[3]}, {});
  return p;
}

struct Ids {
  int box_instance = -1, box_material = -1, panel_instance = -1, panel_material = -1;
};

Xform panel_xf(V3 at) { return compose(translate(at), rotate({1, 0, 0}, 1.2f)); }

lt_light_desc lamp(float watts) {
  lt_light_desc l = point_light({-1, -2, 2.5f}, watts);
  l.radius = 0.3f;  // a lamp rays can hit (kept in the light set's list of hittable lamps)
  return l;
}

// Floor, a box, an emissive panel, a point light and a camera; instances in a fixed order.
ScenePtr build(const Params& p, Ids* ids) {
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  add_object(s, plane(20, 20), add_diffuse(s, {0.7f, 0.6f, 0.5f}));
  ids->box_material = add_material(s, p.box_reads_object ? object_program() : diffuse_program(p.box_color));
  lt_instance_desc box_desc{};
  box_desc.mesh = add_mesh(s, box({-0.5f, -0.5f, 0}, {0.5f, 0.5f, 1}));
  const Xform box_xf = translate(p.box_at);
  std::copy(box_xf.begin(), box_xf.end(), box_desc.transform);
  box_desc.materials = &ids->box_material;
  box_desc.material_count = 1;
  box_desc.visibility = p.box_visibility;
  std::copy(p.box_object_color, p.box_object_color + 4, box_desc.color);
  box_desc.pass_index = p.box_pass_index;
  box_desc.attribute_ids = &kTintId;
  box_desc.attribute_values = p.box_tint;
  box_desc.attribute_count = 1;
  check(lt_scene_add_instance(s, &box_desc, &ids->box_instance), "box");
  ids->panel_material = add_material(s, panel_program(p.panel_emits));
  ids->panel_instance = add_object(s, plane(0.6f, 0.6f), ids->panel_material, panel_xf(p.panel_at));
  add_light(s, lamp(p.lamp_watts));
  set_camera(s, perspective_camera(look_at(p.eye, {0, 0, 0.5f}), 35));
  check(lt_scene_commit(s), "commit");
  return sp;
}

lt_scene_stats stats(lt_scene* s) {
  lt_scene_stats st{};
  check(lt_scene_get_stats(s, &st), "stats");
  return st;
}

std::vector<float> image(lt_scene* s) {
  lt_render_settings rs = render_settings(48, 32, 4, 7);
  rs.threads = 2;
  return render(s, rs).combined;
}

void expect_same_image(lt_scene* edited, const Params& final_state) {
  Ids ids;
  ScenePtr fresh = build(final_state, &ids);
  std::vector<float> a = image(edited), b = image(fresh.get());
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)))
      << "the edited scene does not render like a scene built in its final state";
}

// The box's values as p gives them.
int set_box_values(lt_scene* s, const Ids& ids, const Params& p) {
  return lt_scene_set_instance_values(s, ids.box_instance, p.box_visibility, p.box_object_color, p.box_pass_index,
                                      &kTintId, p.box_tint, 1);
}

}  // namespace

TEST(ApiIncremental, MovingAnInstanceRebuildsOnlyTheTopLevel) {
  Params p;
  Ids ids;
  ScenePtr sp = build(p, &ids);
  lt_scene* s = sp.get();
  const lt_scene_stats before = stats(s);
  EXPECT_EQ(before.mesh_bvh_builds, 3u);
  EXPECT_EQ(before.top_bvh_builds, 1u);
  std::vector<float> original = image(s);

  p.box_at = {0.8f, 0.3f, 0};
  Xform xf = translate(p.box_at);
  check(lt_scene_set_instance_transform(s, ids.box_instance, xf.data()), "move");
  p.panel_at = {-0.5f, 1.2f, 1.5f};  // an emitter moves: its triangle lights must follow
  Xform pxf = panel_xf(p.panel_at);
  check(lt_scene_set_instance_transform(s, ids.panel_instance, pxf.data()), "move panel");
  check(lt_scene_commit(s), "recommit");
  const lt_scene_stats after = stats(s);
  EXPECT_EQ(after.mesh_bvh_builds, before.mesh_bvh_builds);
  EXPECT_EQ(after.top_bvh_builds, before.top_bvh_builds + 1);
  std::vector<float> moved = image(s);
  EXPECT_NE(0, std::memcmp(original.data(), moved.data(), original.size() * sizeof(float)))
      << "moving the box changed nothing in the image";
  expect_same_image(s, p);
}

TEST(ApiIncremental, MaterialAndLightEditsDoNotRebuildTheBvh) {
  Params p;
  Ids ids;
  ScenePtr sp = build(p, &ids);
  lt_scene* s = sp.get();
  const lt_scene_stats before = stats(s);

  p.box_color = {0.9f, 0.1f, 0.1f};
  const ShaderCode red = diffuse_program(p.box_color);
  const lt_shader_program red_desc = red.desc();
  check(lt_scene_set_material(s, ids.box_material, &red_desc), "material");
  // The panel stops emitting: its triangles must leave the light sampler.
  p.panel_emits = false;
  const ShaderCode panel = panel_program(false);
  const lt_shader_program panel_desc = panel.desc();
  check(lt_scene_set_material(s, ids.panel_material, &panel_desc), "panel");
  p.lamp_watts = 800;
  check(lt_scene_clear_lights(s), "clear lights");
  add_light(s, lamp(p.lamp_watts));
  check(lt_scene_commit(s), "recommit");
  const lt_scene_stats after = stats(s);
  EXPECT_EQ(after.mesh_bvh_builds, before.mesh_bvh_builds);
  EXPECT_EQ(after.top_bvh_builds, before.top_bvh_builds);
  EXPECT_EQ(after.light_sampler_builds, before.light_sampler_builds + 1);
  expect_same_image(s, p);
}

TEST(ApiIncremental, CameraChangesNeedNoCommit) {
  Params p;
  Ids ids;
  ScenePtr sp = build(p, &ids);
  lt_scene* s = sp.get();
  const lt_scene_stats before = stats(s);
  p.eye = {-2, -4, 1.5f};
  set_camera(s, perspective_camera(look_at(p.eye, {0, 0, 0.5f}), 35));
  expect_same_image(s, p);  // rendered without a new commit
  const lt_scene_stats after = stats(s);
  EXPECT_EQ(after.top_bvh_builds, before.top_bvh_builds);
  EXPECT_EQ(after.light_sampler_builds, before.light_sampler_builds);
}

TEST(ApiIncremental, InstanceValuesAreSetInPlaceAndNeedNoCommit) {
  Params p;
  p.box_reads_object = true;
  Ids ids;
  ScenePtr sp = build(p, &ids);
  lt_scene* s = sp.get();
  const lt_scene_stats before = stats(s);
  const std::vector<float> original = image(s);
  const float color[4] = {0.9f, 0.3f, 0.1f, 0.5f}, tint[4] = {0.05f, 0.2f, 0.4f, 1};
  std::copy(color, color + 4, p.box_object_color);
  std::copy(tint, tint + 4, p.box_tint);
  p.box_pass_index = 3;
  // Refused as lt_scene_add_instance refuses them, and then nothing changes.
  const float bad_color[4] = {0.9f, NAN, 0.1f, 1};
  EXPECT_EQ(lt_scene_set_instance_values(s, ids.box_instance, LT_VISIBLE_ALL, bad_color, 3, &kTintId, tint, 1),
            LT_ERROR_INVALID_ARGUMENT);
  const int bad_id = -1;
  EXPECT_EQ(lt_scene_set_instance_values(s, ids.box_instance, LT_VISIBLE_ALL, color, 3, &bad_id, tint, 1),
            LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_scene_set_instance_values(s, ids.box_instance, LT_VISIBLE_ALL, color, 3, &kTintId, nullptr, 1),
            LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_scene_set_instance_values(s, 99, LT_VISIBLE_ALL, color, 3, &kTintId, tint, 1),
            LT_ERROR_INVALID_ARGUMENT);
  const std::vector<float> refused = image(s);
  EXPECT_EQ(0, std::memcmp(original.data(), refused.data(), original.size() * sizeof(float)));

  ASSERT_EQ(set_box_values(s, ids, p), LT_OK) << lt_last_error();
  const std::vector<float> edited = image(s);  // rendered without a new commit
  EXPECT_NE(0, std::memcmp(original.data(), edited.data(), original.size() * sizeof(float)))
      << "the new values changed nothing in the image";
  expect_same_image(s, p);
  const lt_scene_stats after = stats(s);
  EXPECT_EQ(after.top_bvh_builds, before.top_bvh_builds);
  EXPECT_EQ(after.light_sampler_builds, before.light_sampler_builds);
  // Without attributes: Attribute reads none (0, emitting black), as in a scene built so.
  ASSERT_EQ(lt_scene_set_instance_values(s, ids.box_instance, LT_VISIBLE_ALL, color, 3, nullptr, nullptr, 0), LT_OK)
      << lt_last_error();
  std::fill(p.box_tint, p.box_tint + 3, 0.0f);
  expect_same_image(s, p);
  EXPECT_EQ(stats(s).mesh_bvh_builds, before.mesh_bvh_builds);
}

TEST(ApiIncremental, VisibilityEditsRebuildTheTopLevel) {
  Params p;
  Ids ids;
  ScenePtr sp = build(p, &ids);
  lt_scene* s = sp.get();
  const lt_scene_stats before = stats(s);
  // The first instance hidden from some rays (Embree's context filter from now on).
  p.box_visibility = LT_VISIBLE_ALL & ~LT_VISIBLE_CAMERA;
  ASSERT_EQ(set_box_values(s, ids, p), LT_OK) << lt_last_error();
  lt_render_settings rs = render_settings(8, 8, 1, 1);
  lt_render* r = nullptr;
  EXPECT_EQ(lt_render_start(s, &rs, &r), LT_ERROR_STATE) << "a changed visibility needs a commit";
  check(lt_scene_commit(s), "recommit");
  lt_scene_stats after = stats(s);
  EXPECT_EQ(after.mesh_bvh_builds, before.mesh_bvh_builds);
  EXPECT_EQ(after.top_bvh_builds, before.top_bvh_builds + 1);
  expect_same_image(s, p);
  // Another partial visibility: the top level only.
  p.box_visibility = LT_VISIBLE_ALL & ~LT_VISIBLE_SHADOW;
  ASSERT_EQ(set_box_values(s, ids, p), LT_OK) << lt_last_error();
  check(lt_scene_commit(s), "recommit");
  const lt_scene_stats last = stats(s);
  EXPECT_EQ(last.mesh_bvh_builds, after.mesh_bvh_builds);
  EXPECT_EQ(last.top_bvh_builds, after.top_bvh_builds + 1);
  expect_same_image(s, p);
  // Seen by every ray again: as a scene built so, without the filter.
  p.box_visibility = LT_VISIBLE_ALL;
  ASSERT_EQ(set_box_values(s, ids, p), LT_OK) << lt_last_error();
  check(lt_scene_commit(s), "recommit");
  expect_same_image(s, p);
}

TEST(ApiIncremental, EditsAreRefusedWhileARenderExistsAndRendersNeedACommit) {
  Params p;
  Ids ids;
  ScenePtr sp = build(p, &ids);
  lt_scene* s = sp.get();
  lt_render* r = nullptr;
  lt_render_settings rs = render_settings(16, 16, 1);
  check(lt_render_start(s, &rs, &r), "start");
  Xform xf = translate({1, 0, 0});
  EXPECT_EQ(LT_ERROR_STATE, lt_scene_set_instance_transform(s, ids.box_instance, xf.data()));
  EXPECT_EQ(LT_ERROR_STATE, lt_scene_clear_lights(s));
  lt_camera_desc cam = perspective_camera(look_at({1, -5, 2}, {0, 0, 0}));
  EXPECT_EQ(LT_ERROR_STATE, lt_scene_set_camera(s, &cam));
  check(lt_render_wait(r), "wait");
  lt_render_destroy(r);

  check(lt_scene_set_instance_transform(s, ids.box_instance, xf.data()), "move");
  r = nullptr;
  EXPECT_EQ(LT_ERROR_STATE, lt_render_start(s, &rs, &r));
  EXPECT_EQ(r, nullptr);
  EXPECT_EQ(LT_ERROR_INVALID_ARGUMENT, lt_scene_set_instance_transform(s, 99, xf.data()));
  Xform bad = xf;
  bad[3] = NAN;
  EXPECT_EQ(LT_ERROR_INVALID_ARGUMENT, lt_scene_set_instance_transform(s, ids.box_instance, bad.data()));
  // Adding geometry to a committed scene stays refused.
  MeshData m = box({0, 0, 0}, {1, 1, 1});
  lt_mesh_desc d = m.desc();
  int id = -1;
  EXPECT_EQ(LT_ERROR_STATE, lt_scene_add_mesh(s, &d, &id));
  check(lt_scene_commit(s), "recommit");
  check(lt_render_start(s, &rs, &r), "start after recommit");
  check(lt_render_wait(r), "wait");
  lt_render_destroy(r);
}
