// Bad input through the C ABI: NULL pointers, non-finite and degenerate geometry, out-of-range
// indices, unknown enum values, cyclic materials, absurd settings, calls in the wrong state,
// cancellation and destruction while rendering. Failing calls must return the documented status
// and set their own lt_last_error() message; every image rendered here must be finite in every
// pass.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>

#include "scene_builders.h"
#include "shading/inputs.h"
#include "shading/program.h"
#include "shading/shaders.h"

using namespace lt_test;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

// lt_last_error() keeps the last failure's message: before each call under test, a different
// known failure sets a sentinel message that the call must replace with its own.
std::string sentinel(int which) {
  if (which == 0)
    lt_scene_create(nullptr);
  else
    lt_render_wait(nullptr);
  return lt_last_error();
}

// Runs `call`, expects status `code`, a non-empty message of its own, and returns the message.
template <class F>
std::string expect_failure(F call, int code, const char* text, int which_sentinel = 0) {
  const std::string before = sentinel(which_sentinel);
  const int status = call();
  EXPECT_EQ(status, code) << text;
  const char* e = lt_last_error();
  EXPECT_NE(e, nullptr) << text;
  std::string msg = e ? e : "";
  EXPECT_FALSE(msg.empty()) << text << ": lt_last_error() is empty";
  EXPECT_NE(msg, before) << text << ": the failing call did not set its own message";
  return msg;
}
#define EXPECT_FAILS(code, expr) expect_failure([&] { return (expr); }, (code), #expr)
#define EXPECT_INVALID(expr) EXPECT_FAILS(LT_ERROR_INVALID_ARGUMENT, expr)
// Evaluates `haystack` once (it is often the failing call itself).
#define EXPECT_CONTAINS(haystack, needle)                                                            \
  do {                                                                                               \
    const std::string h_ = (haystack);                                                               \
    EXPECT_NE(h_.find(needle), std::string::npos) << "\"" << needle << "\" not in \"" << h_ << "\""; \
  } while (0)

int warnings(const lt_scene* s) { return lt_scene_warning_count(s); }

bool has_warning(const lt_scene* s, const std::string& needle) {
  for (int i = 0; i < lt_scene_warning_count(s); ++i)
    if (std::string(lt_scene_warning(s, i)).find(needle) != std::string::npos) return true;
  return false;
}

// A lit, committed-ready scene: a floor plane, a camera, a sun and a dim world.
ScenePtr basic_scene() {
  ScenePtr s = new_scene();
  add_object(s.get(), plane(10, 10), add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}));
  add_light(s.get(), sun_light({0.2f, 0.1f, -1}, 3));
  set_world(s.get(), {0.1f, 0.1f, 0.1f}, 1);
  set_camera(s.get(), perspective_camera(look_at({0, -4, 3}, {0, 0, 0}), 35));
  return s;
}

// Commits and renders a small image; every pass must be finite.
Passes commit_and_render(lt_scene* s, int samples = 4) {
  EXPECT_EQ(lt_scene_commit(s), LT_OK) << lt_last_error();
  Passes p = render(s, render_settings(32, 24, samples, 1));
  EXPECT_EQ(p.first_non_finite(), "") << "a pass holds a NaN or Inf";
  EXPECT_EQ(p.status.state, LT_STATE_DONE);
  return p;
}

lt_render* start_long_render(lt_scene* s) {
  lt_render_settings rs = render_settings(400, 300, 1 << 20, 3);
  rs.max_bounces = rs.diffuse_bounces = 64;
  lt_render* r = nullptr;
  EXPECT_EQ(lt_render_start(s, &rs, &r), LT_OK) << lt_last_error();
  return r;
}

}  // namespace

TEST(ApiBadInput, VersionAndNoCrashOnNullHandles) {
  EXPECT_EQ(lt_abi_version(), LT_ABI_VERSION);
  int n = 0;
  const lt_abi_entry* layout = lt_abi_layout(&n);
  ASSERT_GT(n, 0);
  EXPECT_STREQ(layout[0].type, "lt_abi_entry");  // bindings read the table's own layout first
  EXPECT_EQ(layout[0].value, (long long)sizeof(lt_abi_entry));
  EXPECT_EQ(lt_abi_layout(nullptr), layout);
  ASSERT_NE(lt_version(), nullptr);
  EXPECT_GT(std::string(lt_version()).size(), 0u);
  // Functions without a status: NULL is a no-op.
  lt_scene_destroy(nullptr);
  lt_render_destroy(nullptr);
  lt_render_settings_default(nullptr);
  EXPECT_EQ(lt_scene_warning_count(nullptr), 0);
  ASSERT_NE(lt_scene_warning(nullptr, 0), nullptr);
  EXPECT_STREQ(lt_scene_warning(nullptr, 0), "");
  EXPECT_EQ(lt_pass_channels(-1), 0);
  EXPECT_EQ(lt_pass_channels(LT_PASS_COUNT), 0);
  EXPECT_EQ(lt_pass_channels(LT_PASS_COMBINED), 4);
}

TEST(ApiBadInput, NullPointersEverywhere) {
  expect_failure([] { return lt_scene_create(nullptr); }, LT_ERROR_INVALID_ARGUMENT, "lt_scene_create(NULL)", 1);

  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  int id = -1;

  float pixels[4] = {1, 1, 1, 1};
  lt_image_desc img{1, 1, 4, pixels, 0, LT_INTERP_LINEAR, LT_EXTENSION_REPEAT};
  EXPECT_INVALID(lt_scene_add_image(nullptr, &img, &id));
  EXPECT_INVALID(lt_scene_add_image(s, nullptr, &id));
  EXPECT_INVALID(lt_scene_add_image(s, &img, nullptr));
  img.pixels = nullptr;
  EXPECT_INVALID(lt_scene_add_image(s, &img, &id));

  ShaderCode prog;
  prog.diffuse(prog.one(), {0.5f, 0.5f, 0.5f});
  const lt_shader_program pd = prog.desc();
  EXPECT_INVALID(lt_scene_add_material(nullptr, &pd, &id));
  EXPECT_INVALID(lt_scene_add_material(s, nullptr, &id));
  EXPECT_INVALID(lt_scene_add_material(s, &pd, nullptr));

  MeshData tri;
  tri.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  tri.triangles = {0, 1, 2};
  lt_mesh_desc md = tri.desc();
  EXPECT_INVALID(lt_scene_add_mesh(nullptr, &md, &id));
  EXPECT_INVALID(lt_scene_add_mesh(s, nullptr, &id));
  EXPECT_INVALID(lt_scene_add_mesh(s, &md, nullptr));
  md.positions = nullptr;
  EXPECT_INVALID(lt_scene_add_mesh(s, &md, &id));
  md = tri.desc();
  md.triangles = nullptr;
  EXPECT_INVALID(lt_scene_add_mesh(s, &md, &id));

  const int mesh = add_mesh(s, tri);
  lt_instance_desc inst{};
  inst.mesh = mesh;
  Xform xf = identity();
  std::copy(xf.begin(), xf.end(), inst.transform);
  inst.visibility = LT_VISIBLE_ALL;
  EXPECT_INVALID(lt_scene_add_instance(nullptr, &inst, &id));
  EXPECT_INVALID(lt_scene_add_instance(s, nullptr, &id));
  EXPECT_INVALID(lt_scene_add_instance(s, &inst, nullptr));
  inst.materials = nullptr;
  inst.material_count = 2;
  EXPECT_INVALID(lt_scene_add_instance(s, &inst, &id));

  lt_light_desc l = point_light({0, 0, 1}, 10);
  EXPECT_INVALID(lt_scene_add_light(nullptr, &l));
  EXPECT_INVALID(lt_scene_add_light(s, nullptr));
  lt_camera_desc c = perspective_camera(identity());
  EXPECT_INVALID(lt_scene_set_camera(nullptr, &c));
  EXPECT_INVALID(lt_scene_set_camera(s, nullptr));
  lt_world_desc w = world({1, 1, 1}, 1);
  EXPECT_INVALID(lt_scene_set_world(nullptr, &w));
  EXPECT_INVALID(lt_scene_set_world(s, nullptr));
  EXPECT_INVALID(lt_scene_commit(nullptr));

  ASSERT_EQ(lt_scene_commit(s), LT_OK) << lt_last_error();
  lt_render_settings rs = render_settings(16, 16, 2);
  lt_render* r = nullptr;
  EXPECT_INVALID(lt_render_start(nullptr, &rs, &r));
  EXPECT_INVALID(lt_render_start(s, nullptr, &r));
  EXPECT_INVALID(lt_render_start(s, &rs, nullptr));
  EXPECT_EQ(r, nullptr);

  ASSERT_EQ(lt_render_start(s, &rs, &r), LT_OK) << lt_last_error();
  RenderPtr rp(r);
  ASSERT_EQ(lt_render_wait(r), LT_OK);
  lt_render_status st;
  EXPECT_INVALID(lt_render_poll(nullptr, &st));
  EXPECT_INVALID(lt_render_poll(r, nullptr));
  EXPECT_INVALID(lt_render_cancel(nullptr));
  expect_failure([] { return lt_render_wait(nullptr); }, LT_ERROR_INVALID_ARGUMENT, "lt_render_wait(NULL)", 0);
  std::vector<float> buf(16 * 16 * 4);
  EXPECT_INVALID(lt_render_read_pass(nullptr, LT_PASS_COMBINED, buf.data(), buf.size()));
  EXPECT_INVALID(lt_render_read_pass(r, LT_PASS_COMBINED, nullptr, buf.size()));
  EXPECT_INVALID(lt_render_write_exr(nullptr, "/tmp/never_written.exr"));
  EXPECT_INVALID(lt_render_write_exr(r, nullptr));
  Passes p = read_passes(r, 16, 16);
  EXPECT_EQ(p.first_non_finite(), "");
}

TEST(ApiBadInput, NonFiniteVertexPositionsAreDroppedWithAWarning) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  // Four triangles: one clean, one with a NaN corner, one with an Inf corner, one with -Inf.
  MeshData m;
  m.positions = {-1,   -1,   0.5f,  1, -1, 0.5f, 0, 1, 0.5f,  // clean
                 kNaN, 0,    1,     1, 0,  1,    0, 1, 1,     // NaN
                 0,    kInf, 1,     1, 0,  1,    0, 1, 1,     // +Inf
                 0,    0,    -kInf, 1, 0,  1,    0, 1, 1};    // -Inf
  m.triangles = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  // NaN corner normals too: the mesh falls back to flat shading with a warning.
  for (int t = 0; t < 4; ++t) m.corner_normals.insert(m.corner_normals.end(), {0, 0, 1, kNaN, 0, 1, 0, 0, 1});
  const int before = warnings(s);
  add_object(s, m, add_diffuse(s, {0.5f, 0.5f, 0.5f}));
  EXPECT_GE(warnings(s), before + 2);
  EXPECT_TRUE(has_warning(s, "dropped 3")) << "the three non-finite triangles must be reported";
  EXPECT_TRUE(has_warning(s, "normals"));
  // A mesh whose every vertex is NaN: everything dropped, still no crash.
  MeshData all_nan;
  all_nan.positions = {kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN};
  all_nan.triangles = {0, 1, 2};
  add_object(s, all_nan, add_diffuse(s, {0.5f, 0.5f, 0.5f}));
  EXPECT_TRUE(has_warning(s, "dropped 1"));
  Passes p = commit_and_render(s);
  EXPECT_EQ(p.status.nan_samples, 0u);
}

TEST(ApiBadInput, DegenerateAndZeroAreaTrianglesAreDroppedWithAWarning) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  MeshData m;
  m.positions = {0, 0, 1, 1, 0, 1, 0, 1, 1,  // a good triangle
                 2, 0, 1, 3, 0, 1, 4, 0, 1,  // collinear: zero area
                 5, 5, 5};                   // a single point for repeated indices
  m.triangles = {0, 1, 2, 3, 4, 5, 6, 6, 6, 0, 0, 1, 2, 2, 2};
  add_object(s, m, add_diffuse(s, {0.5f, 0.5f, 0.5f}));
  EXPECT_TRUE(has_warning(s, "dropped 4")) << "collinear, a point and two repeated-index triangles";
  // An emissive mesh of degenerate triangles only: no light may come out of it.
  MeshData flat;
  flat.positions = {0, 0, 2, 1, 1, 2, 2, 2, 2};
  flat.triangles = {0, 1, 2};
  add_object(s, flat, add_emission(s, {1, 1, 1}, 100));
  commit_and_render(s);
}

TEST(ApiBadInput, ZeroAreaAndBlackLightsAreLeftOutWithAWarning) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  int before = warnings(s);
  for (int shape : {LT_AREA_SQUARE, LT_AREA_RECTANGLE, LT_AREA_DISK, LT_AREA_ELLIPSE}) {
    lt_light_desc l = area_light(shape, 0, 1, look_at({0, 0, 2}, {0, 0, 0}), 100);
    EXPECT_EQ(lt_scene_add_light(s, &l), LT_OK) << lt_last_error();
    EXPECT_EQ(warnings(s), ++before) << "shape " << shape;
  }
  lt_light_desc thin = area_light(LT_AREA_RECTANGLE, 1, 0, look_at({0, 0, 2}, {0, 0, 0}), 100);
  EXPECT_EQ(lt_scene_add_light(s, &thin), LT_OK);
  EXPECT_EQ(warnings(s), ++before);
  // A zero-scale transform gives zero area too.
  lt_light_desc squashed = area_light(LT_AREA_SQUARE, 1, 1, compose(translate({0, 0, 2}), scale({0, 0, 0})), 100);
  EXPECT_EQ(lt_scene_add_light(s, &squashed), LT_OK);
  EXPECT_EQ(warnings(s), ++before);
  EXPECT_TRUE(has_warning(s, "area"));
  lt_light_desc black = point_light({0, 0, 1}, 0);
  EXPECT_EQ(lt_scene_add_light(s, &black), LT_OK);
  EXPECT_EQ(warnings(s), ++before);
  commit_and_render(s);
}

TEST(ApiBadInput, EmptyMeshesWarnAndRender) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  const int mat = add_diffuse(s, {0.5f, 0.5f, 0.5f});
  const int before = warnings(s);
  MeshData empty;
  const int e = add_mesh(s, empty);
  EXPECT_EQ(warnings(s), before + 1);
  EXPECT_TRUE(has_warning(s, "no triangles"));
  add_instance(s, e, mat);
  MeshData points_only;
  points_only.positions = {0, 0, 0, 1, 1, 1};
  add_instance(s, add_mesh(s, points_only), mat, translate({0, 0, 1}));
  EXPECT_EQ(warnings(s), before + 2);
  commit_and_render(s);
}

TEST(ApiBadInput, ZeroScaleAndNonFiniteInstanceTransformsWarnAndRender) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  const int mesh = add_mesh(s, icosphere(0.5f, 2));
  const int glow = add_emission(s, {1, 1, 1}, 10);  // would become triangle lights if kept
  int before = warnings(s);
  // Scaled to a point: nothing to see or to emit, as in Cycles (no warning).
  add_instance(s, mesh, glow, scale({0, 0, 0}));
  EXPECT_EQ(warnings(s), before);
  Xform nan_xf = translate({kNaN, 0, 0});
  add_instance(s, mesh, glow, nan_xf);
  EXPECT_EQ(warnings(s), ++before);
  EXPECT_TRUE(has_warning(s, "non-finite"));
  Xform inf_xf = scale({kInf, 1, 1});
  add_instance(s, mesh, glow, inf_xf);
  EXPECT_EQ(warnings(s), ++before);
  // Scaled to a line: nothing has an area either.
  add_instance(s, mesh, glow, scale({1, 0, 0}));
  EXPECT_EQ(warnings(s), before);
  Passes p = commit_and_render(s);
  EXPECT_EQ(p.status.nan_samples, 0u);
  // Only the two meshes' own BVHs were built: collapsed instances get no world-space copy.
  lt_scene_stats st{};
  ASSERT_EQ(lt_scene_get_stats(s, &st), LT_OK);
  EXPECT_EQ(st.mesh_bvh_builds, 2u);
}

// A mesh flattened by a zero scale on one axis renders as the plane it lies in (Cycles 3.4
// renders it black; README). Embree's instancing needs an inverse, so Lantern traces a
// world-space copy of the mesh: per 8x8 tile, the
// flattened box's image agrees with a plane's within 5 standard errors, emission included. Then
// the flattened instance is moved, as the viewport does, and still agrees.
TEST(ApiBadInput, FlattenedMeshRendersAsItsPlane) {
  auto scene = [](bool flattened, float height) {
    ScenePtr s = new_scene();
    lt_scene* sc = s.get();
    add_object(sc, plane(10, 10), add_diffuse(sc, {0.5f, 0.5f, 0.5f}));
    const int white = add_diffuse(sc, {0.8f, 0.8f, 0.8f});
    if (flattened) {
      // A box whose top and bottom faces both land on z = height.
      add_object(sc, box({-1, -1, -1}, {1, 1, 1}), white, compose(translate({0, 0, height}), scale({1, 1, 0})));
    } else {
      add_object(sc, plane(2, 2), white, translate({0, 0, height}));
    }
    // A flattened emitter: its top and bottom faces become lights, its flattened sides do not;
    // the same as two coincident emissive squares facing up and down.
    const int glow = add_emission(sc, {1, 0.9f, 0.7f}, 4);
    if (flattened) {
      add_object(sc, box({-0.2f, -0.2f, -0.2f}, {0.2f, 0.2f, 0.2f}), glow,
                 compose(translate({1.5f, 0.5f, 0.05f}), scale({1, 1, 0})));
    } else {
      MeshData down = plane(0.4f, 0.4f);
      flip_winding(down);
      add_object(sc, plane(0.4f, 0.4f), glow, translate({1.5f, 0.5f, 0.05f}));
      add_object(sc, down, glow, translate({1.5f, 0.5f, 0.05f}));
    }
    add_light(sc, area_light(LT_AREA_SQUARE, 1, 1, translate({0.5f, -0.5f, 3}), 300));
    set_camera(sc, perspective_camera(look_at({0, -4, 4}, {0, 0, 0}), 35));
    return s;
  };
  const int w = 32, h = 24, tile = 8;
  auto compare = [&](lt_scene* a, lt_scene* b, const char* what) {
    Passes pa = render(a, render_settings(w, h, 64, 1)), pb = render(b, render_settings(w, h, 64, 2));
    ASSERT_EQ(pa.first_non_finite(), "");
    ASSERT_EQ(pb.first_non_finite(), "");
    EXPECT_EQ(differing_tiles(pa, pb, tile, 5), "") << what << ": flattened box vs plane";
  };
  ScenePtr flat = scene(true, 0.4f), plain = scene(false, 0.4f);
  const int before = warnings(flat.get());
  ASSERT_EQ(lt_scene_commit(flat.get()), LT_OK) << lt_last_error();
  ASSERT_EQ(lt_scene_commit(plain.get()), LT_OK) << lt_last_error();
  EXPECT_EQ(warnings(flat.get()), before) << "a flattened mesh is not an error";
  compare(flat.get(), plain.get(), "at 0.4 m");
  // Move both up (the flattened box is instance 1, the plane too).
  Xform up = compose(translate({0, 0, 0.8f}), scale({1, 1, 0}));
  ASSERT_EQ(lt_scene_set_instance_transform(flat.get(), 1, up.data()), LT_OK) << lt_last_error();
  ASSERT_EQ(lt_scene_commit(flat.get()), LT_OK) << lt_last_error();
  ScenePtr plain_up = scene(false, 0.8f);
  ASSERT_EQ(lt_scene_commit(plain_up.get()), LT_OK);
  compare(flat.get(), plain_up.get(), "moved to 0.8 m");
}

TEST(ApiBadInput, OutOfRangeIndicesNameTheIndex) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  int id = -1;

  MeshData tri;
  tri.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  tri.triangles = {0, 1, 3};
  lt_mesh_desc md = tri.desc();
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_add_mesh(s, &md, &id)), "index 3");
  tri.triangles = {0, -7, 2};
  md = tri.desc();
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_add_mesh(s, &md, &id)), "-7");
  md.vertex_count = -1;
  EXPECT_INVALID(lt_scene_add_mesh(s, &md, &id));
  md = tri.desc();
  md.triangle_count = -2;
  EXPECT_INVALID(lt_scene_add_mesh(s, &md, &id));

  tri.triangles = {0, 1, 2};
  const int mesh = add_mesh(s, tri);
  lt_instance_desc inst{};
  inst.mesh = 99;
  Xform xf = identity();
  std::copy(xf.begin(), xf.end(), inst.transform);
  inst.visibility = LT_VISIBLE_ALL;
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_add_instance(s, &inst, &id)), "99");
  inst.mesh = -1;
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_add_instance(s, &inst, &id)), "-1");
  inst.mesh = mesh;
  int mats[2] = {0, 42};
  inst.materials = mats;
  inst.material_count = 2;
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_add_instance(s, &inst, &id)), "42");
  mats[1] = -2;
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_add_instance(s, &inst, &id)), "-2");
  inst.material_count = -1;
  EXPECT_INVALID(lt_scene_add_instance(s, &inst, &id));

  lt_world_desc w = world({1, 1, 1}, 1);
  w.image = 4;
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_set_world(s, &w)), "4");

  EXPECT_STREQ(lt_scene_warning(s, -1), "");
  EXPECT_STREQ(lt_scene_warning(s, 1000), "");

  ASSERT_EQ(lt_scene_commit(s), LT_OK);
  lt_render_settings rs = render_settings(8, 8, 1);
  Passes ok = render(s, rs);
  EXPECT_EQ(ok.first_non_finite(), "");
  lt_render* r = nullptr;
  ASSERT_EQ(lt_render_start(s, &rs, &r), LT_OK);
  RenderPtr rp(r);
  lt_render_wait(r);
  std::vector<float> buf(8 * 8 * 4);
  EXPECT_CONTAINS(EXPECT_INVALID(lt_render_read_pass(r, 99, buf.data(), buf.size())), "99");
  EXPECT_CONTAINS(EXPECT_INVALID(lt_render_read_pass(r, -1, buf.data(), buf.size())), "-1");
}

TEST(ApiBadInput, UnknownEnumValuesListTheValidNames) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  int id = -1;

  for (int type : {-1, 4, 1000}) {
    lt_light_desc l = point_light({0, 0, 1}, 10);
    l.type = type;
    std::string msg = EXPECT_INVALID(lt_scene_add_light(s, &l));
    for (const char* name : {"POINT", "SPOT", "AREA", "SUN"}) EXPECT_CONTAINS(msg, name);
  }
  for (int type : {-1, 3, 1000}) {
    lt_camera_desc c = perspective_camera(identity());
    c.type = type;
    std::string msg = EXPECT_INVALID(lt_scene_set_camera(s, &c));
    for (const char* name : {"PERSPECTIVE", "ORTHOGRAPHIC", "PANORAMA"}) EXPECT_CONTAINS(msg, name);
  }
  for (int type : {-1, 6, 1000}) {
    lt_camera_desc c = panorama_camera(identity(), LT_PANORAMA_EQUIRECTANGULAR);
    c.panorama_type = type;
    std::string msg = EXPECT_INVALID(lt_scene_set_camera(s, &c));
    for (const char* name : {"EQUIRECTANGULAR", "FISHEYE_EQUIDISTANT", "FISHEYE_EQUISOLID", "MIRRORBALL",
                             "FISHEYE_LENS_POLYNOMIAL", "EQUIANGULAR_CUBEMAP_FACE"})
      EXPECT_CONTAINS(msg, name);
  }
  {
    // A lens polynomial's coefficients must be finite (any finite ones render: PanoramaBadInput).
    lt_camera_desc c = panorama_camera(identity(), LT_PANORAMA_FISHEYE_LENS_POLYNOMIAL);
    c.fisheye_polynomial[3] = NAN;
    EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_set_camera(s, &c)), "finite");
  }
  // Other enums: refused with a message.
  lt_camera_desc c = perspective_camera(identity());
  c.sensor_fit = 3;
  EXPECT_INVALID(lt_scene_set_camera(s, &c));
  lt_light_desc area = area_light(9, 1, 1, identity(), 10);
  EXPECT_INVALID(lt_scene_add_light(s, &area));
  float px[3] = {1, 1, 1};
  lt_image_desc img{1, 1, 3, px, 0, 3, LT_EXTENSION_REPEAT};
  EXPECT_INVALID(lt_scene_add_image(s, &img, &id));
  img.interpolation = LT_INTERP_LINEAR;
  img.extension = 3;
  EXPECT_INVALID(lt_scene_add_image(s, &img, &id));
  img.extension = LT_EXTENSION_REPEAT;
  img.channels = 2;
  EXPECT_INVALID(lt_scene_add_image(s, &img, &id));

  ASSERT_EQ(lt_scene_commit(s), LT_OK);
  lt_render* r = nullptr;
  lt_render_settings rs = render_settings(8, 8, 1);
  rs.integrator = LT_INTEGRATOR_COUNT;
  // The valid names come from lt_abi_layout's table, without the sentinel.
  EXPECT_CONTAINS(EXPECT_INVALID(lt_render_start(s, &rs, &r)), "valid: PATH, BIDIRECTIONAL, VOLPATH, VOLUME_DEBUG");
  rs = render_settings(8, 8, 1);
  rs.filter = 3;
  EXPECT_INVALID(lt_render_start(s, &rs, &r));
  rs.filter = -1;
  EXPECT_INVALID(lt_render_start(s, &rs, &r));
  EXPECT_EQ(r, nullptr);
}

TEST(ApiBadInput, NonFiniteParametersAreRefused) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  int id = -1;
  lt_light_desc l = point_light({0, 0, 1}, 10);
  l.color[1] = kNaN;
  EXPECT_INVALID(lt_scene_add_light(s, &l));
  l = point_light({0, 0, 1}, -kInf);
  EXPECT_INVALID(lt_scene_add_light(s, &l));
  l = point_light({0, 0, 1}, 10);
  l.transform[3] = kInf;
  EXPECT_INVALID(lt_scene_add_light(s, &l));
  l = point_light({0, 0, 1}, 10);
  l.radius = kNaN;
  EXPECT_INVALID(lt_scene_add_light(s, &l));
  l = sun_light({0, 0, -1}, 1);
  l.angle = -1;
  EXPECT_INVALID(lt_scene_add_light(s, &l));
  l = spot_light({0, 0, 1}, {0, 0, 0}, 10, kNaN, 0);
  EXPECT_INVALID(lt_scene_add_light(s, &l));

  lt_camera_desc c = perspective_camera(identity());
  c.focal_length = kNaN;
  EXPECT_INVALID(lt_scene_set_camera(s, &c));
  c = perspective_camera(identity());
  c.focal_length = 0;
  EXPECT_INVALID(lt_scene_set_camera(s, &c));
  c = perspective_camera(identity());
  c.clip_end = c.clip_start;
  EXPECT_INVALID(lt_scene_set_camera(s, &c));
  c = perspective_camera(scale({0, 0, 0}));
  EXPECT_INVALID(lt_scene_set_camera(s, &c));

  lt_world_desc w = world({1, 1, 1}, kInf);
  EXPECT_INVALID(lt_scene_set_world(s, &w));
  w = world({kNaN, 1, 1}, 1);
  EXPECT_INVALID(lt_scene_set_world(s, &w));

  ShaderCode nan_colour;
  nan_colour.diffuse(nan_colour.one(), {0.5f, 0.5f, kNaN});
  lt_shader_program d = nan_colour.desc();
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_add_material(s, &d, &id)), "constant");
  ShaderCode inf_ior;
  inf_ior.glass(inf_ior.one(), {1, 1, 1}, 0, kInf);
  d = inf_ior.desc();
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_add_material(s, &d, &id)), "constant");

  float px[3] = {kNaN, 1, kInf};
  lt_image_desc img{1, 1, 3, px, 0, LT_INTERP_LINEAR, LT_EXTENSION_REPEAT};
  // Non-finite texels are either refused or sanitised; a textured world must then render finite.
  if (lt_scene_add_image(s, &img, &id) == LT_OK) {
    lt_world_desc tw = world({1, 1, 1}, 1);
    tw.image = id;
    EXPECT_EQ(lt_scene_set_world(s, &tw), LT_OK) << lt_last_error();
  } else {
    EXPECT_GT(std::string(lt_last_error()).size(), 0u);
  }
  Passes p = commit_and_render(s);
  EXPECT_EQ(p.status.nan_samples, 0u);
}

TEST(ApiBadInput, MalformedShaderProgramsAreRefused) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  int id = -1;
  auto refused = [&](const ShaderCode& p, const char* says) {
    const lt_shader_program d = p.desc();
    EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_add_material(s, &d, &id)), says);
  };
  {  // an opcode no family knows
    ShaderCode p;
    p.emit(7777, {p.one()}, {});
    refused(p, "7777");
  }
  {  // a register read before an instruction writes it
    ShaderCode p;
    p.emission(3u << 24 | 5u, {1, 1, 1}, 1);
    refused(p, "register 5");
  }
  {  // a constant past the pool
    ShaderCode p;
    p.emission(lt::kConstBit | 3u << 24 | 99u, {1, 1, 1}, 1);
    refused(p, "past the constants");
  }
  {  // a vector where a float belongs
    ShaderCode p;
    p.emit(lt::kOpEmission, {p.one(), p.c3({1, 1, 1}), p.c3({1, 1, 1})}, {});
    refused(p, "size");
  }
  {  // an operand missing
    ShaderCode p;
    p.emit(lt::kOpEmission, {p.one(), p.c3({1, 1, 1})}, {});
    refused(p, "operand count");
  }
  {  // cut short
    ShaderCode p;
    p.emission(p.one(), {1, 1, 1}, 1);
    p.code.pop_back();
    refused(p, "cut short");
  }
  {  // a register written twice
    ShaderCode p;
    auto w = p.mix(p.one(), 0.5f);
    p.code.insert(p.code.end(), p.code.begin(), p.code.end());
    p.diffuse(w.first, {1, 1, 1});
    refused(p, "twice");
  }
  {  // an image that does not exist (the scene has none)
    ShaderCode p;
    p.emit(lt::kOpImage, {p.c3({0, 0, 0})}, {3, 1}, {3, 0});
    refused(p, "image 3");
  }
  {  // too many registers
    ShaderCode p;
    p.diffuse(p.one(), {1, 1, 1});
    p.registers = 1 << 20;
    refused(p, "registers");
  }
  // A valid program still goes in after all that.
  ShaderCode ok;
  auto [a, b] = ok.mix(ok.one(), 0.25f);
  ok.diffuse(a, {0.3f, 0.3f, 0.3f});
  ok.glossy(b, {0.8f, 0.8f, 0.8f}, 0.4f);
  const lt_shader_program d = ok.desc();
  ASSERT_EQ(lt_scene_add_material(s, &d, &id), LT_OK) << lt_last_error();
  add_object(s, icosphere(0.5f, 2), id, translate({0, 0, 0.5f}));
  EXPECT_EQ(commit_and_render(s).status.nan_samples, 0u);
}

TEST(ApiBadInput, AbsurdRenderSettingsAreRefused) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  ASSERT_EQ(lt_scene_commit(s), LT_OK);
  lt_render* r = nullptr;
  auto refused = [&](lt_render_settings rs, const char* what) {
    SCOPED_TRACE(what);
    expect_failure([&] { return lt_render_start(s, &rs, &r); }, LT_ERROR_INVALID_ARGUMENT, what);
    EXPECT_EQ(r, nullptr);
  };
  lt_render_settings rs = render_settings(0, 10, 1);
  refused(rs, "width 0");
  rs = render_settings(10, 0, 1);
  refused(rs, "height 0");
  rs = render_settings(-1, -1, 1);
  refused(rs, "-1 x -1");
  rs = render_settings(100000, 100000, 1);
  refused(rs, "100000 x 100000");
  rs = render_settings(65536, 65536, 1);
  refused(rs, "65536 x 65536: too many pixels");
  rs = render_settings(1, 70000, 1);
  refused(rs, "1 x 70000");
  rs = render_settings(8, 8, 0);
  refused(rs, "0 samples");
  rs = render_settings(8, 8, -3);
  refused(rs, "negative samples");
  rs = render_settings(8, 8, 1);
  rs.max_bounces = -1;
  refused(rs, "negative bounces");
  rs = render_settings(8, 8, 1);
  rs.max_bounces = 100000;
  refused(rs, "huge bounces");
  rs = render_settings(8, 8, 1);
  rs.diffuse_bounces = -2;
  refused(rs, "negative diffuse bounces");
  rs = render_settings(8, 8, 1);
  rs.filter_width = 0;
  refused(rs, "filter width 0");
  rs = render_settings(8, 8, 1);
  rs.filter_width = kNaN;
  refused(rs, "filter width NaN");
  rs = render_settings(8, 8, 1);
  rs.clamp_direct = kNaN;
  refused(rs, "clamp NaN");
  rs = render_settings(8, 8, 1);
  rs.clamp_indirect = -1;
  refused(rs, "negative clamp");
  rs = render_settings(8, 8, 1);
  rs.threads = -1;
  refused(rs, "negative threads");
  int borders[][4] = {{4, 4, 0, 8}, {5, 3, 0, 8}, {0, 9, 0, 8}, {-1, 4, 0, 8}, {0, 8, 6, 2}, {0, 8, 0, 9}};
  for (auto& b : borders) {
    rs = render_settings(8, 8, 1);
    std::copy(b, b + 4, rs.border);
    refused(rs, "bad border");
  }
  // Still usable: a 1 x 1 render works.
  Passes p = render(s, render_settings(1, 1, 2));
  EXPECT_EQ(p.first_non_finite(), "");
}

TEST(ApiBadInput, RenderBeforeCommitAndEditsAfterCommitAreStateErrors) {
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  lt_render* r = nullptr;
  lt_render_settings rs = render_settings(8, 8, 1);
  EXPECT_FAILS(LT_ERROR_STATE, lt_render_start(s, &rs, &r));
  EXPECT_EQ(r, nullptr);

  // A committed scene without a camera cannot render either.
  ScenePtr no_camera = new_scene();
  ASSERT_EQ(lt_scene_commit(no_camera.get()), LT_OK);
  EXPECT_INVALID(lt_render_start(no_camera.get(), &rs, &r));

  ASSERT_EQ(lt_scene_commit(s), LT_OK);
  EXPECT_EQ(lt_scene_commit(s), LT_OK) << "a second commit is harmless";
  int id = -1;
  float px[3] = {1, 1, 1};
  lt_image_desc img{1, 1, 3, px, 0, LT_INTERP_LINEAR, LT_EXTENSION_REPEAT};
  EXPECT_FAILS(LT_ERROR_STATE, lt_scene_add_image(s, &img, &id));
  ShaderCode prog;
  prog.diffuse(prog.one(), {0.5f, 0.5f, 0.5f});
  const lt_shader_program pd = prog.desc();
  EXPECT_FAILS(LT_ERROR_STATE, lt_scene_add_material(s, &pd, &id));
  MeshData tri;
  tri.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  tri.triangles = {0, 1, 2};
  lt_mesh_desc md = tri.desc();
  EXPECT_FAILS(LT_ERROR_STATE, lt_scene_add_mesh(s, &md, &id));
  lt_instance_desc inst{};
  inst.mesh = 0;
  Xform xf = identity();
  std::copy(xf.begin(), xf.end(), inst.transform);
  EXPECT_FAILS(LT_ERROR_STATE, lt_scene_add_instance(s, &inst, &id));
  // The refused edits changed nothing: the scene renders.
  Passes p = render(s, rs);
  EXPECT_EQ(p.first_non_finite(), "");
  // Lights, camera and world are incremental edits (test_api_incremental.cpp): refused only while
  // a render of the scene exists.
  ASSERT_EQ(lt_render_start(s, &rs, &r), LT_OK);
  lt_light_desc l = point_light({0, 0, 1}, 10);
  EXPECT_FAILS(LT_ERROR_STATE, lt_scene_add_light(s, &l));
  lt_camera_desc c = perspective_camera(identity());
  EXPECT_FAILS(LT_ERROR_STATE, lt_scene_set_camera(s, &c));
  lt_world_desc w = world({1, 1, 1}, 1);
  EXPECT_FAILS(LT_ERROR_STATE, lt_scene_set_world(s, &w));
  ASSERT_EQ(lt_render_wait(r), LT_OK);
  lt_render_destroy(r);
  EXPECT_EQ(lt_scene_add_light(s, &l), LT_OK);
}

// lt_scene_set_volume_grid_motion (ABI 26): only a Volume object's grid moves, by 0 or an odd
// count from 3 to 129 finite, invertible steps, before the commit.
TEST(ApiBadInput, VolumeGridMotionIsRefusedUnlessItIsAGridsValidMotion) {
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  lt_volume_desc d = {};
  d.node = LT_VOLUME_SCATTER;
  d.color[0] = d.color[1] = d.color[2] = 1;
  d.density = 1;
  const Xform id = identity();
  int grid = -1;
  ASSERT_EQ(lt_scene_add_volume_grid(s, (std::string(LANTERN_TEST_VDB_DIR) + "/cloud.vdb").c_str(), "density",
                                     id.data(), 0, 0.001f, 0.0f, &d, 1, &grid),
            LT_OK)
      << lt_last_error();
  float steps[36];
  for (int k = 0; k < 3; ++k) {
    const Xform m = translate({0.5f * float(k - 1), 0, 0});
    std::copy(m.begin(), m.end(), steps + 12 * k);
  }
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_set_volume_grid_motion(s, grid + 1, steps, 3)), "not a Volume object");
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_set_volume_grid_motion(s, grid, steps, 2)), "motion steps");
  EXPECT_INVALID(lt_scene_set_volume_grid_motion(s, grid, nullptr, 3));
  EXPECT_INVALID(lt_scene_set_volume_grid_motion(nullptr, grid, steps, 3));
  float bad[36];
  std::copy(steps, steps + 36, bad);
  bad[12 + 5] = kNaN;
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_set_volume_grid_motion(s, grid, bad, 3)), "not finite");
  std::fill(bad + 24, bad + 36, 0.0f);  // the last step scaled to nothing
  std::copy(steps + 12, steps + 24, bad + 12);
  EXPECT_INVALID(lt_scene_set_volume_grid_motion(s, grid, bad, 3));
  lt_scene_stats st{};
  EXPECT_EQ(lt_scene_set_volume_grid_motion(s, grid, steps, 3), LT_OK) << lt_last_error();
  ASSERT_EQ(lt_scene_get_stats(s, &st), LT_OK);
  EXPECT_EQ(st.moving_volumes, 1u);
  EXPECT_EQ(lt_scene_set_volume_grid_motion(s, grid, steps, 0), LT_OK) << lt_last_error();
  ASSERT_EQ(lt_scene_get_stats(s, &st), LT_OK);
  EXPECT_EQ(st.moving_volumes, 0u);
  ASSERT_EQ(lt_scene_commit(s), LT_OK);
  EXPECT_FAILS(LT_ERROR_STATE, lt_scene_set_volume_grid_motion(s, grid, steps, 3));
}

TEST(ApiBadInput, ReadPassWithAWrongBufferSize) {
  ScenePtr sp = basic_scene();
  ASSERT_EQ(lt_scene_commit(sp.get()), LT_OK);
  lt_render_settings rs = render_settings(10, 6, 2);
  rs.passes = (1u << LT_PASS_COUNT) - 1;  // every pass, AO and Vector too
  lt_render* r = nullptr;
  ASSERT_EQ(lt_render_start(sp.get(), &rs, &r), LT_OK);
  RenderPtr rp(r);
  ASSERT_EQ(lt_render_wait(r), LT_OK);
  for (int pass = 0; pass < LT_PASS_COUNT; ++pass) {
    const size_t need = size_t(10 * 6 * lt_pass_channels(pass));
    std::vector<float> buf(need + 8, -1.0f);
    for (size_t wrong : {size_t(0), need - 1, need + 1, size_t(10 * 6), need * 2}) {
      if (wrong == need) continue;
      std::string msg = EXPECT_INVALID(lt_render_read_pass(r, pass, buf.data(), wrong));
      EXPECT_CONTAINS(msg, std::to_string(need));
    }
    EXPECT_EQ(buf[0], -1.0f) << "a refused read must not write";
    EXPECT_EQ(lt_render_read_pass(r, pass, buf.data(), need), LT_OK);
  }
  Passes p = read_passes(r, 10, 6);
  EXPECT_EQ(p.first_non_finite(), "");
}

TEST(ApiBadInput, CancelRightAfterStart) {
  ScenePtr sp = basic_scene();
  add_object(sp.get(), icosphere(1, 3), add_diffuse(sp.get(), {0.9f, 0.9f, 0.9f}), translate({0, 0, 1}));
  ASSERT_EQ(lt_scene_commit(sp.get()), LT_OK);
  const auto t0 = std::chrono::steady_clock::now();
  lt_render* r = start_long_render(sp.get());
  ASSERT_NE(r, nullptr);
  RenderPtr rp(r);
  EXPECT_EQ(lt_render_cancel(r), LT_OK);
  EXPECT_EQ(lt_render_wait(r), LT_OK);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(seconds, 2.0) << "cancel must stop a render within a pass";
  Passes p = read_passes(r, 400, 300);
  EXPECT_EQ(p.status.state, LT_STATE_CANCELLED);
  EXPECT_LT(p.status.samples_done, p.status.samples_total);
  EXPECT_EQ(p.first_non_finite(), "");
  EXPECT_EQ(lt_render_cancel(r), LT_OK) << "cancelling twice is harmless";
  EXPECT_EQ(lt_render_wait(r), LT_OK) << "waiting twice is harmless";
}

TEST(ApiBadInput, CancelAfterSomeSamplesKeepsAConsistentImage) {
  ScenePtr sp = basic_scene();
  ASSERT_EQ(lt_scene_commit(sp.get()), LT_OK);
  lt_render* r = start_long_render(sp.get());
  ASSERT_NE(r, nullptr);
  RenderPtr rp(r);
  lt_render_status st{};
  const auto t0 = std::chrono::steady_clock::now();
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ASSERT_EQ(lt_render_poll(r, &st), LT_OK);
    // Reading while rendering gives a finite image.
    Passes live = read_passes(r, 400, 300);
    ASSERT_EQ(live.first_non_finite(), "");
  } while (st.samples_done < 2 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60));
  ASSERT_GE(st.samples_done, 2);
  EXPECT_EQ(st.state, LT_STATE_RUNNING);
  EXPECT_GT(st.rays, 0u);
  ASSERT_EQ(lt_render_cancel(r), LT_OK);
  ASSERT_EQ(lt_render_wait(r), LT_OK);
  Passes p = read_passes(r, 400, 300);
  EXPECT_EQ(p.status.state, LT_STATE_CANCELLED);
  EXPECT_EQ(p.first_non_finite(), "");
  // Each pixel holds the completed passes, plus at most the one interrupted.
  int bad = 0;
  for (float c : p.sample_count)
    if (c < p.status.samples_done || c > p.status.samples_done + 1) ++bad;
  EXPECT_EQ(bad, 0) << "pixels whose sample count is not " << p.status.samples_done << " or one more";
}

TEST(ApiBadInput, DestroyWhileRunning) {
  ScenePtr sp = basic_scene();
  ASSERT_EQ(lt_scene_commit(sp.get()), LT_OK);
  // Right after the start.
  auto t0 = std::chrono::steady_clock::now();
  lt_render* r = start_long_render(sp.get());
  ASSERT_NE(r, nullptr);
  lt_render_destroy(r);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 2.0);
  // After some progress, and two renders of one scene at once.
  lt_render* a = start_long_render(sp.get());
  lt_render* b = start_long_render(sp.get());
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  t0 = std::chrono::steady_clock::now();
  lt_render_destroy(a);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 2.0);
  Passes p = read_passes(b, 400, 300);
  EXPECT_EQ(p.first_non_finite(), "");
  lt_render_destroy(b);
  // The scene is still usable.
  Passes q = render(sp.get(), render_settings(8, 8, 2));
  EXPECT_EQ(q.first_non_finite(), "");
}

TEST(ApiBadInput, LongProgramsRunAndHugeOnesAreRefused) {
  // 40 nested Mix Shaders (a chain of weights) shade as one diffuse closure at the end: programs
  // are linear, so their cost grows with their length, never with sharing.
  ScenePtr sp = basic_scene();
  lt_scene* s = sp.get();
  ShaderCode p;
  uint32_t w = p.one();
  for (int i = 0; i < 40; ++i) w = p.mix(w, 0.0f).first;
  p.diffuse(w, {0.5f, 0.5f, 0.5f});
  int id = -1;
  lt_shader_program d = p.desc();
  ASSERT_EQ(lt_scene_add_material(s, &d, &id), LT_OK) << lt_last_error();
  // Longer than the core takes: refused with a message, not allocated.
  d.code_words = lt::kMaxProgramWords + 1;
  EXPECT_CONTAINS(EXPECT_INVALID(lt_scene_add_material(s, &d, &id)), "length");
  add_object(s, icosphere(0.5f, 1), id, translate({0, 0, 0.5f}));
  EXPECT_EQ(commit_and_render(s, 1).status.nan_samples, 0u);
}

TEST(ApiBadInput, GlassIorBelowOneReflectsTotallyAsCycles) {
  // A smooth glass slab of IOR 0.75 (an optically thinner inside, as an air bubble in water) in
  // front of an emitter, in a black world. Seen head-on the emitter shows through it; seen at 60
  // degrees from the slab's normal, beyond the critical angle asin(0.75) = 48.6 degrees, the slab
  // reflects totally and shows the black world. Clamping the IOR to 1 (as Lantern once did) makes
  // the slab vanish and both views see the emitter. IOR 0 is 1e-5 (Cycles' fmaxf(ior, 1e-5f)): a
  // near-perfect mirror from outside, and finite.
  for (float ior : {0.75f, 0.0f}) {
    ScenePtr sp = new_scene();
    lt_scene* s = sp.get();
    const int material = add_glass(s, {1, 1, 1}, 0, ior);
    add_object(s, box({-20, -0.2f, -20}, {20, 0.2f, 20}), material);
    add_object(s, plane(60, 60), add_emission(s, {1, 1, 1}, 1),
               compose(translate({0, 2, 0}), rotate({1, 0, 0}, 1.5707964f)));
    const float a = 60 * 3.14159265f / 180;
    double mean[2];
    for (int view = 0; view < 2; ++view) {
      const float angle = view ? a : 0;
      set_camera(s, perspective_camera(look_at({-4 * std::sin(angle), -4 * std::cos(angle), 0}, {0, 0, 0}), 200));
      check(lt_scene_commit(s), "commit");
      Passes p = render(s, render_settings(8, 8, 16, 1));
      ASSERT_EQ(p.first_non_finite(), "") << "ior " << ior;
      EXPECT_EQ(p.status.nan_samples, 0u) << "ior " << ior;
      mean[view] = region_stats(p, 0, 0, 8, 0, 8).mean;
    }
    if (ior > 0) {
      EXPECT_GT(mean[0], 0.9) << "head-on, the emitter shows through the slab (transmittance (1 - 0.02)^2)";
      EXPECT_LT(mean[1], 1e-3) << "at 60 degrees the slab reflects totally";
    } else {
      EXPECT_LT(mean[0], 1e-3) << "IOR 1e-5 is a mirror head-on";
    }
  }
}

// Embree traces only rays whose origin and direction components are within 1.844e18 (its
// FLT_LARGE; Debian's build asserts on others and aborts the process). A camera, geometry or a
// light beyond that range must render (such rays miss and such shadow rays are blocked), finite,
// with a warning that says so, never abort. Found by fuzz_abi (a camera 1e19 away).
TEST(ApiBadInput, CoordinatesBeyondEmbreesRangeRenderWithAWarning) {
  {  // the camera far away
    ScenePtr sp = basic_scene();
    set_camera(sp.get(), perspective_camera(look_at({0, -1e19f, 3}, {0, 0, 0}), 35));
    commit_and_render(sp.get());
    EXPECT_TRUE(has_warning(sp.get(), "beyond")) << "camera";
  }
  {  // an orthographic camera wider than the range
    ScenePtr sp = basic_scene();
    set_camera(sp.get(), orthographic_camera(look_at({0, -4, 3}, {0, 0, 0}), 1e30f));
    commit_and_render(sp.get());
    EXPECT_TRUE(has_warning(sp.get(), "beyond")) << "orthographic camera";
  }
  {  // geometry scaled beyond the range, and a lamp out there
    ScenePtr sp = basic_scene();
    add_object(sp.get(), icosphere(1, 1), add_diffuse(sp.get(), {0.5f, 0.5f, 0.5f}), scale({1e25f, 1e25f, 1e25f}));
    add_light(sp.get(), point_light({1e30f, 0, 0}, 1e30f));
    commit_and_render(sp.get());
    EXPECT_TRUE(has_warning(sp.get(), "beyond")) << "geometry";
  }
}
