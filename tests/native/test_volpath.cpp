// The volumetric path tracer through the C ABI: energy conservation in a white furnace, identity
// with the path tracer on scenes without media, extremes, VDB volumes and their errors.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "api/handles.h"
#include "core/label_font.h"
#include "scene_builders.h"

using namespace lt_test;

namespace {

std::string vdb(const std::string& name) { return std::string(LANTERN_TEST_VDB_DIR) + "/" + name; }

// A medium sphere of radius `r` at the origin seen from -Y, in a uniform white world.
ScenePtr furnace_scene(float density, float albedo, float g, float r) {
  ScenePtr s = new_scene();
  int m = add_volume_material(s.get(), volume(LT_VOLUME_PRINCIPLED, density, albedo, g));
  add_object(s.get(), icosphere(r, 3), m);
  set_world(s.get(), {1, 1, 1}, 1);
  set_camera(s.get(), perspective_camera(look_at({0, -4 * r, 0}, {0, 0, 0}), 50));
  check(lt_scene_commit(s.get()), "commit");
  return s;
}

// Combined of one render as the ABI reads it (labelled) and as the film holds it without labels.
struct LabelledRender {
  int width = 0, height = 0;
  std::vector<float> labelled, plain;
  const float* at(const std::vector<float>& img, int x, int y) const { return &img[(size_t(y) * width + x) * 4]; }
};

LabelledRender render_labelled(lt_scene* s, const lt_render_settings& rs, int w, int h) {
  lt_render* raw = nullptr;
  check(lt_render_start(s, &rs, &raw), "lt_render_start");
  RenderPtr r(raw);
  check(lt_render_wait(r.get()), "lt_render_wait");
  LabelledRender out;
  out.width = w;
  out.height = h;
  out.labelled.assign(size_t(w) * h * 4, -1.0f);
  out.plain.assign(out.labelled.size(), -1.0f);
  check(lt_render_read_pass(r.get(), LT_PASS_COMBINED, out.labelled.data(), out.labelled.size()), "read_pass");
  r->job->film().read(lt::Pass::Combined, out.plain.data(), /*labels=*/false);
  return out;
}

}  // namespace

TEST(VolPath, FurnaceAlbedoOneMediumReturnsTheWorld) {
  ScenePtr s = furnace_scene(1.5f, 1.0f, 0.5f, 1.0f);
  lt_render_settings rs = volpath_settings(24, 24, 128, 3);
  rs.max_bounces = 1024;
  rs.volume_bounces = 1024;
  Passes p = render(s.get(), rs);
  ASSERT_EQ(p.first_non_finite(), "");
  double sum = 0, var = 0;
  int failures = 0;
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x)
      for (int c = 0; c < 3; ++c) {
        double m = p.rgba(x, y)[c], v = p.var(x, y)[c];
        sum += m;
        var += v;
        if (std::abs(m - 1.0) > kSigmas * std::sqrt(v) + 1e-5 && failures++ < 10)
          ADD_FAILURE() << "pixel (" << x << ", " << y << ") channel " << c << ": " << m;
      }
  int n = 3 * p.width * p.height;
  EXPECT_NEAR(sum / n, 1.0, kSigmas * std::sqrt(var) / n + 1e-5);
  EXPECT_GT(var, 0.0) << "the medium should make the estimate noisy";
}

TEST(VolPath, SingleScatteringLosesEnergyInTheFurnace) {
  // Cycles' default volume_bounces = 0: one scattering event, so the sphere is darker than the world.
  ScenePtr s = furnace_scene(3.0f, 1.0f, 0.0f, 1.0f);
  Passes p = render(s.get(), volpath_settings(16, 16, 32, 3));
  ASSERT_EQ(p.first_non_finite(), "");
  EXPECT_LT(p.rgba(8, 8)[0], 0.9f);
}

// A camera inside an absorbing medium box (an invisible boundary) starts its rays in the medium:
// the centre sees the white world through 1 of the medium, exp(-1); from outside, through the box,
// exp(-2). The stack is initialised by tracing only where the camera may be inside a medium
// object's bounds (Scene::may_be_inside_boundary, as Cycles'), everywhere when that object moves.
TEST(VolPath, CameraInsideAMediumStartsInIt) {
  const auto render_from = [](const lt::Vec3& eye, bool moving, lt::Scene** committed) {
    ScenePtr s = new_scene();
    const int m = add_volume_material(s.get(), volume(LT_VOLUME_PRINCIPLED, 1.0f, 0.0f));  // absorption only
    lt_instance_desc d{};
    d.mesh = add_mesh(s.get(), box({-1, -1, -1}, {1, 1, 1}));
    const Xform xf = identity(), before = translate({0, 0, -1e-4f}), after = translate({0, 0, 1e-4f});
    std::copy(xf.begin(), xf.end(), d.transform);
    float steps[36];  // three steps, the centre one the transform
    std::copy(before.begin(), before.end(), steps);
    std::copy(xf.begin(), xf.end(), steps + 12);
    std::copy(after.begin(), after.end(), steps + 24);
    if (moving) {
      d.motion_transforms = steps;
      d.motion_step_count = 3;
    }
    d.materials = &m;
    d.material_count = 1;
    d.visibility = LT_VISIBLE_ALL;
    int id = -1;
    check(lt_scene_add_instance(s.get(), &d, &id), "lt_scene_add_instance");
    set_world(s.get(), {1, 1, 1}, 1);
    set_camera(s.get(), perspective_camera(look_at({eye.x, eye.y, eye.z}, {0, 1, 0}), 200));
    check(lt_scene_commit(s.get()), "commit");
    *committed = &s->scene;
    lt_render_settings rs = volpath_settings(8, 8, 256, 5);
    Passes p = render(s.get(), rs);
    double centre = 0;
    for (int y = 2; y < 6; ++y)
      for (int x = 2; x < 6; ++x) centre += p.rgba(x, y)[0] / 16.0;
    EXPECT_EQ(p.first_non_finite(), "");
    return std::make_pair(std::move(s), centre);
  };
  for (bool moving : {false, true}) {
    SCOPED_TRACE(moving ? "moving box" : "still box");
    lt::Scene* scene = nullptr;
    auto inside = render_from({0, 0, 0}, moving, &scene);
    EXPECT_TRUE(scene->may_be_inside_boundary({0, 0, 0}));
    EXPECT_EQ(scene->may_be_inside_boundary({0, -4, 0}), moving);
    EXPECT_NEAR(inside.second, std::exp(-1.0), 0.03);
    auto outside = render_from({0, -4, 0}, moving, &scene);
    EXPECT_NEAR(outside.second, std::exp(-2.0), 0.03);
  }
}

// A room whose wall material carries the fog (as a Blender user would fill a room: one mesh, a
// surface and a Volume output) renders as the same walls around an invisible fog box just inside
// them, per 8x8 tile within 5 SE, for VOLPATH and BDPT. Next-event estimation from a wall, towards
// the lamp inside, must not enter the fog a second time.
TEST(VolPath, MediumOfAnOpaqueBoundaryIsEnteredOnce) {
  const float inset = 1e-3f;
  lt_volume_desc fog = volume(LT_VOLUME_PRINCIPLED, 0.7f, 0.8f, 0.2f);
  auto room = [&](bool walls_carry_fog) {
    ScenePtr s = new_scene();
    int walls = add_diffuse(s.get(), {0.7f, 0.7f, 0.7f});
    if (walls_carry_fog) check(lt_scene_set_material_volume(s.get(), walls, &fog, 1, 0), "wall medium");
    add_object(s.get(), box({-1, -1, 0}, {1, 1, 2}), walls);
    if (!walls_carry_fog)
      add_object(s.get(), box({-1 + inset, -1 + inset, inset}, {1 - inset, 1 - inset, 2 - inset}),
                 add_volume_material(s.get(), fog));
    add_light(s.get(), area_light(LT_AREA_SQUARE, 0.5f, 0.5f, translate({0.3f, 0.2f, 1.9f}), 40));
    set_camera(s.get(), perspective_camera(look_at({-0.8f, -0.9f, 1.2f}, {0.4f, 0.5f, 0.6f}), 35));
    check(lt_scene_commit(s.get()), "commit");
    return s;
  };
  ScenePtr a = room(true), b = room(false);
  for (int integrator : {LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    lt_render_settings rs = render_settings(32, 32, 256, 3);
    rs.integrator = integrator;
    rs.volume_bounces = 4;
    rs.max_light_length = 1;  // BDPT as path tracing with NEE: independent pixels for the Variance pass
    Passes pa = render(a.get(), rs);
    rs.seed = 4;
    Passes pb = render(b.get(), rs);
    ASSERT_EQ(pa.first_non_finite(), "");
    EXPECT_EQ(differing_tiles(pa, pb, 8, kSigmas), "") << "integrator " << integrator;
  }
}

TEST(VolPath, EqualsPathWithoutMedia) {
  ScenePtr s = new_scene();
  int white = add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}), red = add_diffuse(s.get(), {0.8f, 0.1f, 0.1f});
  add_object(s.get(), box({-1, -1, 0}, {1, 1, 2}), white);
  add_object(s.get(), icosphere(0.4f, 2), red, translate({0.2f, 0.1f, 0.4f}));
  add_light(s.get(), point_light({0, 0, 1.8f}, 100));
  set_world(s.get(), {0.2f, 0.2f, 0.2f}, 1);
  set_camera(s.get(), perspective_camera(look_at({0, -0.9f, 1}, {0, 0, 1}), 20));
  check(lt_scene_commit(s.get()), "commit");
  lt_render_settings rs = render_settings(32, 32, 16, 5);
  Passes a = render(s.get(), rs);
  rs.integrator = LT_INTEGRATOR_VOLPATH;
  Passes b = render(s.get(), rs);
  // Per 8x8 tile and channel: means within 5 standard errors of each other.
  EXPECT_EQ(differing_tiles(a, b, 8, kSigmas), "");
}

// The bounce limits end a path at a collision in a medium as at a surface: past the diffuse
// limit, a collision in fog was lit by next-event estimation and scattered on (Blender's thin_fog
// read 0.2-0.3 % above Cycles at its diffuse limit of 4; +3 % at a limit of 1). Thin fog filling a
// room lit by an area lamp just above it; BDPT with light length 1 (path tracing with
// next-event estimation, its own limits) per 8x8 tile and in the image mean, each render's pixels
// independent (Variance pass).
TEST(VolPath, BounceLimitsEndPathsInMediaAsAtSurfaces) {
  ScenePtr s = new_scene();
  lt_scene* sc = s.get();
  const int white = add_diffuse(sc, {0.8f, 0.8f, 0.8f}), red = add_diffuse(sc, {0.8f, 0.1f, 0.1f});
  add_object(sc, plane(2, 2), white);
  MeshData ceiling = plane(2, 2);
  flip_winding(ceiling);
  add_object(sc, ceiling, white, translate({0, 0, 2}));
  add_object(sc, plane(2, 2), white, compose(translate({0, 1, 1}), rotate({1, 0, 0}, float(M_PI / 2))));
  add_object(sc, plane(2, 2), red, compose(translate({-1, 0, 1}), rotate({0, 1, 0}, float(M_PI / 2))));
  add_object(sc, plane(2, 2), white, compose(translate({1, 0, 1}), rotate({0, 1, 0}, float(-M_PI / 2))));
  add_object(sc, box({-0.95f, -0.95f, 0.02f}, {0.95f, 0.95f, 1.92f}),
             add_volume_material(sc, volume(LT_VOLUME_PRINCIPLED, 0.1f, 0.9f)));
  add_light(sc, area_light(LT_AREA_SQUARE, 0.5f, 0.5f, translate({0, 0, 1.98f}), 50));
  set_camera(sc, perspective_camera(look_at({0, -3.8f, 1.0f}, {0, 0, 1.0f}), 50));
  check(lt_scene_commit(sc), "commit");
  const int size = 32;
  for (int volume_bounces : {0, 2}) {
    lt_render_settings vp = volpath_settings(size, size, 128, 3);
    lt_render_settings pt = vp;
    pt.integrator = LT_INTEGRATOR_BIDIRECTIONAL;
    pt.max_light_length = 1;
    pt.seed = 4;
    for (lt_render_settings* r : {&vp, &pt}) {
      r->max_bounces = 12;
      r->diffuse_bounces = 1;
      r->volume_bounces = volume_bounces;
    }
    const Passes a = render(sc, vp), b = render(sc, pt);
    EXPECT_EQ(differing_tiles(a, b, 8, kSigmas), "") << "volume bounces " << volume_bounces;
    EXPECT_EQ(differing_tiles(a, b, size, kSigmas), "") << "image mean, volume bounces " << volume_bounces;
  }
}

// A point lamp with a radius is a disk facing the path's last scattering, also where the ray
// crossed an invisible boundary on its way (Cycles keeps the ray's origin there): the top of an
// empty volume box passing 0.1 below the lamp's centre, inside its radius of 0.3, changes nothing
// (it turned the disks hit from the floor towards the boundary, against the densities that
// weigh those hits: the image mean fell 21 %, 16 standard errors). Per 8x8 tile and in the mean,
// for the volumetric path tracer and BDPT's camera walk.
TEST(VolPath, PointLampDisksFaceTheLastScatteringThroughBoundaries) {
  auto scene = [](bool box_around) {
    ScenePtr s = new_scene();
    lt_scene* sc = s.get();
    add_object(sc, plane(4, 4), add_glossy(sc, {0.8f, 0.8f, 0.8f}, 0.4f));
    if (box_around)
      add_object(sc, box({-2, -2, -1}, {2, 2, 0.4f}), add_volume_material(sc, volume(LT_VOLUME_PRINCIPLED, 0.0f)));
    lt_light_desc lamp = point_light({0, 0, 0.5f}, 20);
    lamp.radius = 0.3f;
    add_light(sc, lamp);
    set_camera(sc, perspective_camera(look_at({0, -2.5f, 1.5f}, {0, 0, 0}), 35));
    check(lt_scene_commit(sc), "commit");
    return s;
  };
  ScenePtr plain = scene(false), boxed = scene(true);
  const int size = 32;
  const Passes a = render(plain.get(), volpath_settings(size, size, 64, 5));
  const Passes b = render(boxed.get(), volpath_settings(size, size, 64, 6));
  EXPECT_EQ(differing_tiles(a, b, 8, kSigmas), "");
  EXPECT_EQ(differing_tiles(a, b, size, kSigmas), "") << "image mean";
  // BDPT's camera walk the same (light length 1: no splats, so its pixels are independent).
  lt_render_settings bd = volpath_settings(size, size, 64, 7);
  bd.integrator = LT_INTEGRATOR_BIDIRECTIONAL;
  bd.max_light_length = 1;
  const Passes c = render(boxed.get(), bd);
  EXPECT_EQ(differing_tiles(a, c, 8, kSigmas), "") << "BDPT";
  EXPECT_EQ(differing_tiles(a, c, size, kSigmas), "") << "BDPT, image mean";
}

TEST(VolPath, ExtremesAreFiniteAndBounded) {
  struct Case {
    float density, albedo, g, scale;
  };
  const Case cases[] = {{1e-6f, 1, 0, 1},       {1e6f, 1, 0, 1},          {1e6f, 0, 0, 1},     {1, 0, 0, 1},
                        {1, 1, -0.99f, 1},      {1, 1, 0.99f, 1},         {1e3f, 1, 0, 1e-3f}, {1e-4f, 1, 0, 1e4f},
                        {1e6f, 1, 0.99f, 1e4f}, {1e-6f, 0, -0.99f, 1e-3f}};
  for (const Case& k : cases) {
    ScenePtr s = new_scene();
    int m = add_volume_material(s.get(), volume(LT_VOLUME_PRINCIPLED, k.density, k.albedo, k.g));
    add_object(s.get(), icosphere(k.scale, 2), m);
    int white = add_diffuse(s.get(), {0.8f, 0.8f, 0.8f});
    add_object(s.get(), box({-3 * k.scale, -3 * k.scale, -2 * k.scale}, {3 * k.scale, 3 * k.scale, -1.5f * k.scale}),
               white);
    add_light(s.get(), point_light({0, -2 * k.scale, 2 * k.scale}, 100 * k.scale * k.scale));
    set_world(s.get(), {0.5f, 0.5f, 0.5f}, 1);
    lt_camera_desc cam = perspective_camera(look_at({0, -5 * k.scale, 0}, {0, 0, 0}), 35);
    cam.clip_start = 1e-4f * k.scale;
    cam.clip_end = 1e3f * k.scale;
    set_camera(s.get(), cam);
    check(lt_scene_commit(s.get()), "commit");
    for (int integrator : {LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
      lt_render_settings rs = volpath_settings(16, 16, 4);
      rs.integrator = integrator;
      rs.volume_bounces = 64;
      auto t0 = std::chrono::steady_clock::now();
      Passes p = render(s.get(), rs);
      double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const std::string what = "integrator " + std::to_string(integrator) + " density " + std::to_string(k.density) +
                               " albedo " + std::to_string(k.albedo) + " g " + std::to_string(k.g) + " scale " +
                               std::to_string(k.scale);
      EXPECT_EQ(p.first_non_finite(), "") << what;
      EXPECT_EQ(p.status.nan_samples, 0u) << what;
      EXPECT_LT(secs, 20.0) << what;
    }
  }
}

TEST(VolPath, VdbVolumeThroughTheAbi) {
  for (int estimator : {LT_VOLUME_RAY_MARCHING, LT_VOLUME_TRACKING}) {
    ScenePtr s = new_scene();
    lt_volume_desc d = volume(LT_VOLUME_PRINCIPLED, 5, 1);
    Xform xf = identity();
    int id = -1;
    ASSERT_EQ(lt_scene_add_volume_grid(s.get(), vdb("density.vdb").c_str(), "density", xf.data(), 0, 0.001f, 0.0f, &d,
                                       1, &id),
              LT_OK)
        << lt_last_error();
    EXPECT_GE(id, 0);
    set_world(s.get(), {1, 1, 1}, 1);
    // The grid spans about [0.7, 2.2] x [-2, -0.5] x [0.7, 2.2].
    set_camera(s.get(), perspective_camera(look_at({1.45f, -6, 1.45f}, {1.45f, -1.25f, 1.45f}), 50));
    check(lt_scene_commit(s.get()), "commit");
    lt_render_settings rs = volpath_settings(16, 16, 16);
    rs.volume_estimator = estimator;
    rs.volume_bounces = 16;
    Passes p = render(s.get(), rs);
    ASSERT_EQ(p.first_non_finite(), "");
    // Over the central pixels: at 16 samples one pixel's samples can all come through at 1 (the
    // centre pixel did when the pixel filter's sampling changed).
    double centre = 0;
    for (int y = 4; y < 12; ++y)
      for (int x = 4; x < 12; ++x) centre += p.rgba(x, y)[0] / 64.0;
    EXPECT_LT(centre, 0.99) << "the cloud should dim the centre (single scattering loses light)";
    EXPECT_GT(centre, 0.0);
    EXPECT_NEAR(p.rgba(0, 0)[0], 1.0f, 1e-4f) << "the corner sees the world only";
    // The debug view renders its four panels.
    rs.integrator = LT_INTEGRATOR_VOLUME_DEBUG;
    Passes dbg = render(s.get(), rs);
    ASSERT_EQ(dbg.first_non_finite(), "");
    EXPECT_LT(dbg.rgba(12, 12)[0], 0.99f) << "transmittance, ratio tracking panel (top right)";
    EXPECT_GT(dbg.rgba(4, 4)[0], 1.0f) << "sampled distance panel (bottom left): metres from the camera";
  }
}

TEST(VolPath, VdbErrorsThroughTheAbi) {
  lt_volume_desc d = volume(LT_VOLUME_PRINCIPLED, 1);
  Xform xf = identity();
  struct Case {
    std::string file, grid, expect;
  };
  const Case cases[] = {{"missing.vdb", "density", "missing.vdb"},
                        {"no_density.vdb", "density", "temperature"},
                        {"empty.vdb", "density", "empty.vdb"},
                        {"vector.vdb", "density", "vector.vdb"}};
  for (const Case& c : cases) {
    ScenePtr s = new_scene();
    int id = -1;
    EXPECT_EQ(
        lt_scene_add_volume_grid(s.get(), vdb(c.file).c_str(), c.grid.c_str(), xf.data(), 0, 0.001f, 0.0f, &d, 1, &id),
        LT_ERROR_IO)
        << c.file;
    std::string msg = lt_last_error();
    EXPECT_NE(msg.find(c.expect), std::string::npos) << c.file << ": " << msg;
    EXPECT_EQ(lt_scene_commit(s.get()), LT_OK);
  }
  ScenePtr s = new_scene();
  int id;
  lt_volume_desc bad = d;
  bad.node = 7;
  EXPECT_EQ(lt_scene_add_volume_grid(s.get(), vdb("density.vdb").c_str(), "density", xf.data(), 0, 0.001f, 0.0f, &bad,
                                     1, &id),
            LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_scene_set_material_volume(s.get(), 3, &d, 1, 1), LT_ERROR_INVALID_ARGUMENT);
  bad = d;
  bad.density = NAN;
  int m = add_diffuse(s.get(), {1, 1, 1});
  EXPECT_EQ(lt_scene_set_material_volume(s.get(), m, &bad, 1, 0), LT_ERROR_INVALID_ARGUMENT);
}

TEST(VolPath, DebugViewLabelsEachPanel) {
  ScenePtr s = furnace_scene(2.0f, 0.8f, 0.0f, 1.0f);
  // 96x40: four 48x20 panels, labels at 1x (43x9 with the outline, one pixel in from the corner).
  lt_render_settings rs = render_settings(96, 40, 4, 7);
  rs.integrator = LT_INTEGRATOR_VOLUME_DEBUG;
  LabelledRender img = render_labelled(s.get(), rs, 96, 40);
  const char* names[4] = {"T MARCH", "T RATIO", "D MARCH", "D DELTA"};
  std::vector<int> expect(96 * 40, lt::kLabelNone);  // from the font's glyphs, outline around them
  for (int panel = 0; panel < 4; ++panel) {
    const int gx0 = (panel % 2) * 48 + 2, gy0 = (panel < 2 ? 39 : 19) - 2;  // glyph top-left
    for (int i = 0; names[panel][i]; ++i)
      for (int gy = 0; gy < 7; ++gy)
        for (int gx = 0; gx < 5; ++gx)
          if ((lt::label_glyph(names[panel][i])[gy] >> (4 - gx)) & 1) {
            const int x = gx0 + 6 * i + gx, y = gy0 - gy;
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx)
                if (expect[(y + dy) * 96 + x + dx] == lt::kLabelNone) expect[(y + dy) * 96 + x + dx] = lt::kLabelBlack;
          }
    for (int i = 0; names[panel][i]; ++i)
      for (int gy = 0; gy < 7; ++gy)
        for (int gx = 0; gx < 5; ++gx)
          if ((lt::label_glyph(names[panel][i])[gy] >> (4 - gx)) & 1)
            expect[(gy0 - gy) * 96 + gx0 + 6 * i + gx] = lt::kLabelWhite;
    // The T's or D's top row: white, outlined above and to the left.
    EXPECT_EQ(expect[gy0 * 96 + gx0 + 1], lt::kLabelWhite);
    EXPECT_EQ(expect[(gy0 + 1) * 96 + gx0], lt::kLabelBlack);
    EXPECT_EQ(expect[gy0 * 96 + gx0 - 1], lt::kLabelBlack);
  }
  int white = 0, black = 0, changed = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 96; ++x) {
      const float *a = img.at(img.labelled, x, y), *b = img.at(img.plain, x, y);
      const int e = expect[y * 96 + x];
      if (e == lt::kLabelNone) {
        EXPECT_EQ(std::memcmp(a, b, 4 * sizeof(float)), 0) << "unlabelled pixel changed at " << x << "," << y;
        continue;
      }
      const float v = e == lt::kLabelWhite ? 1.0f : 0.0f;
      EXPECT_TRUE(a[0] == v && a[1] == v && a[2] == v && a[3] == 1.0f) << "label pixel " << x << "," << y;
      (e == lt::kLabelWhite ? white : black) += 1;
      changed += std::memcmp(a, b, 4 * sizeof(float)) != 0;
    }
  EXPECT_GT(white, 4 * 60);
  EXPECT_GT(black, 4 * 60);
  EXPECT_GT(changed, 4 * 60) << "the label must differ from the render beneath it";

  // 2x for panels 200 px wide or more, clipped to a border region (the top-left panel's corner).
  rs = render_settings(420, 40, 2, 7);
  rs.integrator = LT_INTEGRATOR_VOLUME_DEBUG;
  rs.border[0] = 0, rs.border[1] = 60, rs.border[2] = 20, rs.border[3] = 40;
  LabelledRender big = render_labelled(s.get(), rs, 60, 20);
  for (int x = 2; x < 12; ++x)
    for (int y : {16, 17}) EXPECT_EQ(big.at(big.labelled, x, y)[0], 1.0f) << "2x T bar at " << x << "," << y;
  EXPECT_EQ(big.at(big.labelled, 1, 17)[0], 0.0f);
  EXPECT_EQ(big.at(big.labelled, 12, 17)[0], 0.0f);
  EXPECT_EQ(big.at(big.labelled, 5, 18)[0], 0.0f);
  EXPECT_EQ(big.at(big.labelled, 6, 15)[0], 1.0f) << "2x T stem";

  // No labels in panels too small to hold them (20x8), nor for the other integrators.
  for (int integrator : {LT_INTEGRATOR_VOLUME_DEBUG, LT_INTEGRATOR_VOLPATH}) {
    rs = render_settings(integrator == LT_INTEGRATOR_VOLPATH ? 96 : 40, integrator == LT_INTEGRATOR_VOLPATH ? 40 : 16,
                         2, 7);
    rs.integrator = integrator;
    LabelledRender plain = render_labelled(s.get(), rs, rs.width, rs.height);
    EXPECT_EQ(std::memcmp(plain.labelled.data(), plain.plain.data(), plain.labelled.size() * sizeof(float)), 0)
        << "integrator " << integrator;
  }
}

// Volume shader mixes and emission (issue 12 item 2): a box of Add Shader(Volume Absorption,
// Emission) seen head-on through an orthographic camera, no lights and a black world: every pixel
// is the closed form E (1 - exp(-sigma_a d)) / sigma_a over the box's depth d = 2, for VOLPATH and
// BDPT (strategy s = 0), with no random numbers involved (homogeneous medium); then the same
// volume as a World volume seen to infinity.
TEST(VolPath, VolumeEmissionIntegratesInClosedForm) {
  ScenePtr s = new_scene();
  lt_volume_desc c[2] = {volume(LT_VOLUME_ABSORPTION, 1.2f, 0.5f), volume(LT_VOLUME_EMISSION, 0.0f)};
  c[1].emission_strength = 2.0f;
  const float color[3] = {1.0f, 0.5f, 0.25f};
  std::memcpy(c[1].emission_color, color, sizeof(color));
  int mat = add_diffuse(s.get(), {0, 0, 0});
  check(lt_scene_set_material_volume(s.get(), mat, c, 2, 1), "set_material_volume");
  add_object(s.get(), box({-1, -1, 0}, {1, 1, 2}), mat);
  set_world(s.get(), {0, 0, 0}, 0);
  set_camera(s.get(), orthographic_camera(look_at({0, -4, 1}, {0, 0, 1}), 1.0f));
  check(lt_scene_commit(s.get()), "commit");
  const double sigma = 1.2 * 0.5, d = 2.0;
  for (int integrator : {LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    lt_render_settings rs = render_settings(8, 8, 4, 2);
    rs.integrator = integrator;
    Passes p = render(s.get(), rs);
    ASSERT_EQ(p.first_non_finite(), "");
    for (int ch = 0; ch < 3; ++ch) {
      const double expected = 2.0 * color[ch] * -std::expm1(-sigma * d) / sigma;
      EXPECT_NEAR(p.rgba(4, 4)[ch], expected, 1e-4 * expected) << "integrator " << integrator << " channel " << ch;
    }
  }
  // A World volume emits too: an escaping ray crosses it to infinity, E / sigma_a per channel.
  ScenePtr w = new_scene();
  EXPECT_EQ(lt_scene_set_world_volume(w.get(), c, 0), LT_ERROR_INVALID_ARGUMENT);
  check(lt_scene_set_world_volume(w.get(), c, 2), "set_world_volume");
  set_world(w.get(), {0, 0, 0}, 0);
  set_camera(w.get(), orthographic_camera(look_at({0, -4, 1}, {0, 0, 1}), 1.0f));
  check(lt_scene_commit(w.get()), "commit");
  for (int integrator : {LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    lt_render_settings rs = render_settings(8, 8, 4, 2);
    rs.integrator = integrator;
    Passes p = render(w.get(), rs);
    for (int ch = 0; ch < 3; ++ch) {
      const double expected = 2.0 * color[ch] / sigma;
      EXPECT_NEAR(p.rgba(4, 4)[ch], expected, 1e-4 * expected)
          << "world, integrator " << integrator << " channel " << ch;
    }
  }
  // Grids are read by Volume objects only.
  c[1].emission_strength_grid = "flame";
  ScenePtr g = new_scene();
  EXPECT_EQ(lt_scene_set_world_volume(g.get(), c, 2), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_scene_set_material_volume(g.get(), add_diffuse(g.get(), {0, 0, 0}), c, 2, 1), LT_ERROR_INVALID_ARGUMENT);
}
