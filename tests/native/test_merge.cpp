// Sample-split rendering (sample_offset) and lt_merge_exr: parts of samples [0, 64) and [64, 128)
// merged equal one render of [0, 128) for every integrator, BDPT's light-tracing splats included,
// up to float rounding; parts that do not belong together are refused and nothing is written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io/exr.h"
#include "scene_builders.h"

using namespace lt_test;

namespace {

constexpr int kW = 24, kH = 18;

// A floor, a diffuse sphere, a glossy box, a small area light and a dim world (every BDPT
// strategy has something to do); with `media`, a scattering ball too.
ScenePtr merge_scene(bool media, bool catcher = false) {
  ScenePtr s = new_scene();
  if (catcher) {  // the floor a shadow catcher
    const int floor = add_diffuse(s.get(), {0.7f, 0.6f, 0.5f});
    lt_instance_desc d{};
    d.mesh = add_mesh(s.get(), plane(8, 8));
    const Xform id = translate({0, 0, 0});
    std::copy(id.begin(), id.end(), d.transform);
    d.materials = &floor;
    d.material_count = 1;
    d.visibility = LT_VISIBLE_ALL;
    d.shadow_catcher = 1;
    int out = -1;
    check(lt_scene_add_instance(s.get(), &d, &out), "lt_scene_add_instance");
  } else {
    add_object(s.get(), plane(8, 8), add_diffuse(s.get(), {0.7f, 0.6f, 0.5f}));
  }
  // The sphere moves between frames (the Vector pass; settings_for takes the steps as frames).
  const int sphere_material = add_diffuse(s.get(), {0.2f, 0.5f, 0.8f});
  lt_instance_desc sphere{};
  sphere.mesh = add_mesh(s.get(), icosphere(0.5f, 2));
  sphere.materials = &sphere_material;
  sphere.material_count = 1;
  sphere.visibility = LT_VISIBLE_ALL;
  std::vector<float> steps;
  for (float dx : {-0.3f, 0.0f, 0.2f})
    for (float v : translate({-0.6f + dx, 0, 0.5f})) steps.push_back(v);
  std::copy(steps.begin() + 12, steps.begin() + 24, sphere.transform);
  sphere.motion_transforms = steps.data();
  sphere.motion_step_count = 3;
  int id;
  check(lt_scene_add_instance(s.get(), &sphere, &id), "sphere");
  const int gm = add_glossy(s.get(), {0.8f, 0.8f, 0.8f}, 0.3f);
  add_object(s.get(), box({0.2f, -0.3f, 0}, {0.9f, 0.4f, 0.7f}), gm);
  if (media) {
    ShaderCode p;
    p.transparent(p.one(), {1, 1, 1});
    const int vm = add_material(s.get(), p);
    lt_volume_desc d{};
    d.node = LT_VOLUME_SCATTER;
    d.color[0] = d.color[1] = d.color[2] = 0.9f;
    d.density = 2;
    check(lt_scene_set_material_volume(s.get(), vm, &d, 1, 1), "set_material_volume");
    add_object(s.get(), icosphere(0.4f, 2), vm, translate({0.1f, -0.9f, 0.6f}));
  }
  lt_light_desc light = area_light(LT_AREA_SQUARE, 0.5f, 0.5f, look_at({0, -1, 2.5f}, {0, 0, 0}), 200);
  light.lightgroup = 1;  // light groups (settings_for): the lamp's and the world's
  add_light(s.get(), light);
  set_world(s.get(), {0.05f, 0.06f, 0.08f}, 1);
  check(lt_scene_set_world_lightgroup(s.get(), 2), "set_world_lightgroup");
  // The camera moves too: the floor's vectors vary within a pixel, where the world's edge leaves
  // parts different coverages.
  lt_camera_desc camera = perspective_camera(look_at({0, -4, 2}, {0, 0, 0.4f}), 35);
  std::vector<float> camera_steps;
  for (float dx : {-0.1f, 0.0f, 0.15f})
    for (float v : look_at({dx, -4, 2}, {0, 0, 0.4f})) camera_steps.push_back(v);
  camera.motion_transforms = camera_steps.data();
  camera.motion_step_count = 3;
  set_camera(s.get(), camera);
  check(lt_scene_commit(s.get()), "commit");
  return s;
}

lt_render_settings settings_for(int integrator, int offset, int samples) {
  lt_render_settings rs = render_settings(kW, kH, samples, 7);
  rs.integrator = integrator;
  rs.sample_offset = offset;
  rs.volume_bounces = 2;
  static const char* const kGroups[] = {"lamp", "world"};
  rs.lightgroup_count = 2;
  rs.lightgroup_names = kGroups;
  rs.passes |= (1u << LT_PASS_AO) | (1u << LT_PASS_VECTOR);  // AO: a mean; Vector: by its coverage
  rs.motion_pass = 1;
  return rs;
}

// Renders and writes an EXR part; attributes as lt_render_write_exr_attributes takes them.
void render_part(lt_scene* s, const lt_render_settings& rs, const std::string& path,
                 std::vector<const char*> attributes = {}) {
  lt_render* raw = nullptr;
  check(lt_render_start(s, &rs, &raw), "render_start");
  RenderPtr r(raw);
  check(lt_render_wait(r.get()), "render_wait");
  attributes.push_back(nullptr);
  check(lt_render_write_exr_attributes(r.get(), path.c_str(), attributes.data()), "write_exr");
}

int merge(const std::string& out, const std::vector<std::string>& parts) {
  std::vector<const char*> p;
  for (const std::string& s : parts) p.push_back(s.c_str());
  return lt_merge_exr(out.c_str(), p.data(), int(p.size()));
}

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// Float-order bound: every merged value is a count-weighted mean in double of float parts, each
// the float of a double mean; both sides are within a few float ulps (2^-24 relative) of the
// exact mean, so 1e-5 relative is ample. Normals and the Variance pass can cancel (signed
// components; the pooled variance's between-part term), so they get the same bound relative to
// the pixel's scale: |normal| <= 1, and for the variance the squared mean over the sample count.
void expect_merged_equals_full(const lt::ExrImage& merged, const lt::ExrImage& full, const char* what) {
  ASSERT_EQ(merged.width, full.width);
  ASSERT_EQ(merged.height, full.height);
  ASSERT_EQ(merged.channels.size(), full.channels.size());
  const lt::ExrChannel* counts = full.find("SampleCount.X");
  double worst_all = 0;
  for (const lt::ExrChannel& fc : full.channels) {
    const lt::ExrChannel* mc = merged.find(fc.name);
    ASSERT_NE(mc, nullptr) << what << ": merged lacks " << fc.name;
    int bad = 0;
    double worst = 0;
    for (size_t i = 0; i < fc.pixels.size(); ++i) {
      const double a = mc->pixels[i], b = fc.pixels[i];
      double scale = std::abs(b);
      if (fc.name.rfind("Normal.", 0) == 0 || fc.name.rfind("Mist.", 0) == 0) scale = 1;  // signed; 1 - a mean
      // The Shadow Catcher pass (and the approximate Combined made from it) divides a difference of
      // float means (Combined less the matte) by the catcher's: rounding grows by their ratio, a few.
      if (fc.name.rfind("ShadowCatcher.", 0) == 0 || (full.find("CatcherCombined.R") && fc.name.size() == 1))
        scale = std::max(scale, 10.0);
      if (fc.name.rfind("Variance.", 0) == 0) {
        const std::string c = fc.name.substr(9);
        const double mean = full.find(c)->pixels[i];
        scale = std::max(scale, mean * mean / std::max(1.0f, counts->pixels[i]));
      }
      const double err = std::abs(a - b);
      if (err > 0) worst = std::max(worst, err / std::max(scale, 1e-30));
      if (!(err <= 1e-5 * scale) && bad++ < 3)
        ADD_FAILURE() << what << " " << fc.name << " pixel " << i << ": merged " << a << ", full render " << b;
    }
    EXPECT_EQ(bad, 0) << what << " " << fc.name << " (worst relative error " << worst << ")";
    worst_all = std::max(worst_all, worst);
  }
  std::printf("%s: largest relative difference over every pass and pixel: %.3g\n", what, worst_all);
}

class MergeExactness : public ::testing::TestWithParam<int> {};

TEST_P(MergeExactness, SplitPartsMergeIntoTheFullRender) {
  const int integrator = GetParam();
  ScenePtr s = merge_scene(integrator == LT_INTEGRATOR_VOLPATH);
  TempDir dir;
  const std::string full = dir.path + "/full.exr", a = dir.path + "/a.exr", b = dir.path + "/b.exr",
                    c = dir.path + "/c.exr", out = dir.path + "/merged.exr", out3 = dir.path + "/merged3.exr";
  render_part(s.get(), settings_for(integrator, 0, 128), full);
  render_part(s.get(), settings_for(integrator, 0, 64), a);
  render_part(s.get(), settings_for(integrator, 64, 64), b);
  ASSERT_EQ(merge(out, {b, a}), LT_OK) << lt_last_error();
  const lt::ExrImage f = lt::read_exr(full), m = lt::read_exr(out), pa = lt::read_exr(a);
  expect_merged_equals_full(m, f, "2 parts");
  EXPECT_EQ(m.attributes.at("lantern/samples"), "128");
  EXPECT_EQ(m.attributes.at("lantern/sample_ranges"), "0-128");
  for (float v : m.find("SampleCount.X")->pixels) ASSERT_EQ(v, 128.0f);
  if (integrator == LT_INTEGRATOR_BIDIRECTIONAL) EXPECT_NE(f.find("LightTracing.R"), nullptr);
  EXPECT_NE(f.find("Combined_lamp.R"), nullptr);  // light groups, their splats apart with BDPT
  EXPECT_NE(f.find("AO.G"), nullptr);
  ASSERT_NE(f.find("VectorCoverage.X"), nullptr);
  // Pixels at the floor's edge against the world: a part of their samples wrote a Vector (the
  // merge weights it).
  int partial = 0;
  for (float c : f.find("VectorCoverage.X")->pixels) partial += c > 0 && c < 1;
  EXPECT_GT(partial, 0);
  EXPECT_EQ(f.find("LightTracing.Combined_world.B") != nullptr, integrator == LT_INTEGRATOR_BIDIRECTIONAL);

  // The part is a different estimate (so the equality above says something), and the offset
  // matters: [64, 128) is not [0, 64) again.
  int differing = 0;
  for (size_t i = 0; i < f.find("R")->pixels.size(); ++i)
    differing += pa.find("R")->pixels[i] != f.find("R")->pixels[i];
  EXPECT_GT(differing, kW * kH / 2);
  EXPECT_NE(slurp(a).substr(2000), slurp(b).substr(2000));

  // Uneven split, merged in two steps: a merge is itself a part.
  render_part(s.get(), settings_for(integrator, 64, 40), a);
  render_part(s.get(), settings_for(integrator, 104, 24), c);
  render_part(s.get(), settings_for(integrator, 0, 64), b);
  ASSERT_EQ(merge(out3, {a, c}), LT_OK) << lt_last_error();
  const std::string out4 = out3 + ".all.exr";  // a merge never writes over one of its parts
  ASSERT_EQ(merge(out4, {out3, b}), LT_OK) << lt_last_error();
  expect_merged_equals_full(lt::read_exr(out4), f, "3 parts in 2 merges");
}

std::string integrator_name(const ::testing::TestParamInfo<int>& i) {
  return i.param == LT_INTEGRATOR_PATH ? "Path" : i.param == LT_INTEGRATOR_BIDIRECTIONAL ? "Bidirectional" : "VolPath";
}
INSTANTIATE_TEST_SUITE_P(Integrators, MergeExactness,
                         ::testing::Values(LT_INTEGRATOR_PATH, LT_INTEGRATOR_BIDIRECTIONAL, LT_INTEGRATOR_VOLPATH),
                         integrator_name);

// Each kind of mismatch is refused with a message naming it; an existing output stays as it was.
// Shadow catchers: Combined (the matte, approximate or not, over a transparent film or the world)
// and the Shadow Catcher pass are recomputed from the parts' merged catcher means.
TEST(MergeShadowCatcher, CombinedAndThePassMergeIntoTheFullRender) {
  ScenePtr s = merge_scene(false, true);
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_BIDIRECTIONAL})
    for (int approximate : {0, 1})
      for (int transparent : {0, 1}) {
        SCOPED_TRACE("integrator " + std::to_string(integrator));
        TempDir dir;
        const std::string full = dir.path + "/full.exr", a = dir.path + "/a.exr", b = dir.path + "/b.exr",
                          out = dir.path + "/merged.exr";
        auto settings = [&](int offset, int samples) {
          lt_render_settings rs = settings_for(integrator, offset, samples);
          rs.passes |= 1u << LT_PASS_SHADOW_CATCHER;
          rs.shadow_catcher_approximate = approximate;
          rs.transparent_background = transparent;
          return rs;
        };
        render_part(s.get(), settings(0, 32), full);
        render_part(s.get(), settings(0, 16), a);
        render_part(s.get(), settings(16, 16), b);
        ASSERT_EQ(merge(out, {a, b}), LT_OK) << lt_last_error();
        const lt::ExrImage f = lt::read_exr(full);
        ASSERT_NE(f.find("ShadowCatcher.R"), nullptr);
        ASSERT_NE(f.find("CatcherMatte.A"), nullptr);
        expect_merged_equals_full(lt::read_exr(out), f, approximate ? "approximate" : "matte");
      }
}

TEST(MergeRefusals, EveryMismatchIsRefusedAndNothingIsOverwritten) {
  ScenePtr s = merge_scene(false);
  TempDir dir;
  auto p = [&](const char* name) { return dir.path + "/" + name; };
  const std::vector<const char*> scene_a = {"lantern/scene", "A"};
  render_part(s.get(), settings_for(LT_INTEGRATOR_PATH, 0, 4), p("a.exr"), scene_a);
  render_part(s.get(), settings_for(LT_INTEGRATOR_PATH, 4, 4), p("b.exr"), scene_a);
  render_part(s.get(), settings_for(LT_INTEGRATOR_PATH, 2, 4), p("overlap.exr"), scene_a);
  render_part(s.get(), settings_for(LT_INTEGRATOR_PATH, 4, 4), p("scene.exr"), {"lantern/scene", "B"});
  render_part(s.get(), settings_for(LT_INTEGRATOR_PATH, 4, 4), p("noscene.exr"));
  lt_render_settings seed = settings_for(LT_INTEGRATOR_PATH, 4, 4);
  seed.seed = 8;
  render_part(s.get(), seed, p("seed.exr"), scene_a);
  render_part(s.get(), settings_for(LT_INTEGRATOR_BIDIRECTIONAL, 4, 4), p("integrator.exr"), scene_a);
  lt_render_settings res = settings_for(LT_INTEGRATOR_PATH, 4, 4);
  res.width = kW + 2;
  render_part(s.get(), res, p("resolution.exr"), scene_a);
  lt_render_settings border = settings_for(LT_INTEGRATOR_PATH, 4, 4);
  border.width = 2 * kW;
  border.border[0] = 0, border.border[1] = kW, border.border[2] = 0, border.border[3] = kH;
  render_part(s.get(), border, p("region.exr"), scene_a);
  // Made by hand from a part: one channel fewer; no SampleCount channel; no sample attributes.
  lt::ExrImage img = lt::read_exr(p("b.exr"));
  auto without = [&](const std::string& name) {
    std::vector<lt::ExrChannel> ch;
    for (const lt::ExrChannel& c : img.channels)
      if (c.name != name) ch.push_back(c);
    return ch;
  };
  lt::write_exr(p("passes.exr"), img.width, img.height, without("Albedo.G"), img.attributes);
  lt::write_exr(p("nocount.exr"), img.width, img.height, without("SampleCount.X"), img.attributes);
  auto attrs = img.attributes;
  attrs.erase("lantern/sample_ranges");
  lt::write_exr(p("noranges.exr"), img.width, img.height, img.channels, attrs);
  std::ofstream(p("garbage.exr")) << "not an EXR";

  const std::string out = p("out.exr");
  std::ofstream(out) << "previous result";
  struct Case {
    const char* part;
    int status;
    const char* message;
  };
  const Case cases[] = {
      {"resolution.exr", LT_ERROR_INVALID_ARGUMENT, "resolution differs"},
      {"region.exr", LT_ERROR_INVALID_ARGUMENT, "differs"},
      {"passes.exr", LT_ERROR_INVALID_ARGUMENT, "passes differ"},
      {"scene.exr", LT_ERROR_INVALID_ARGUMENT, "scene differs"},
      {"noscene.exr", LT_ERROR_INVALID_ARGUMENT, "scene differs"},
      {"seed.exr", LT_ERROR_INVALID_ARGUMENT, "seed differs"},
      {"integrator.exr", LT_ERROR_INVALID_ARGUMENT, "integrator differs"},
      {"overlap.exr", LT_ERROR_INVALID_ARGUMENT, "sample ranges overlap"},
      {"a.exr", LT_ERROR_INVALID_ARGUMENT, "sample ranges overlap"},  // the same part twice
      {"nocount.exr", LT_ERROR_INVALID_ARGUMENT, "no recorded sample counts"},
      {"noranges.exr", LT_ERROR_INVALID_ARGUMENT, "no recorded sample counts"},
      {"garbage.exr", LT_ERROR_IO, "could not read"},
      {"missing.exr", LT_ERROR_IO, "could not read"},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(merge(out, {p("a.exr"), p(c.part)}), c.status) << c.part;
    const std::string msg = lt_last_error();
    EXPECT_NE(msg.find(c.message), std::string::npos) << c.part << ": message \"" << msg << "\"";
    EXPECT_EQ(slurp(out), "previous result") << c.part << " overwrote the output";
  }
  EXPECT_EQ(merge(out, {}), LT_ERROR_INVALID_ARGUMENT);
  // The output among the parts, by the same path, another spelling or a link: refused, untouched.
  const std::string b_copy = slurp(p("b.exr"));
  std::filesystem::create_symlink(p("b.exr"), p("link.exr"));
  for (const std::string& o : {p("b.exr"), dir.path + "/./b.exr", p("link.exr")}) {
    EXPECT_EQ(merge(o, {p("a.exr"), p("b.exr")}), LT_ERROR_INVALID_ARGUMENT) << o;
    EXPECT_NE(std::string(lt_last_error()).find("is also a part"), std::string::npos) << lt_last_error();
    EXPECT_EQ(slurp(p("b.exr")), b_copy) << o << " overwrote a part";
  }
  std::filesystem::remove(p("link.exr"));
  // No temporary files left behind, and the good pair merges.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path))
    files += e.path().filename().string().find(".tmp") != std::string::npos;
  EXPECT_EQ(files, 0);
  ASSERT_EQ(merge(out, {p("a.exr"), p("b.exr")}), LT_OK) << lt_last_error();
  EXPECT_EQ(lt::read_exr(out).attributes.at("lantern/sample_ranges"), "0-8");
}

TEST(SampleOffset, OutOfRangeIsRefused) {
  ScenePtr s = merge_scene(false);
  lt_render* r = nullptr;
  lt_render_settings rs = settings_for(LT_INTEGRATOR_PATH, -1, 4);
  EXPECT_EQ(lt_render_start(s.get(), &rs, &r), LT_ERROR_INVALID_ARGUMENT);
  rs.sample_offset = (1 << 30) - 3;
  EXPECT_EQ(lt_render_start(s.get(), &rs, &r), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(lt_last_error()).find("sample offset"), std::string::npos);
}

}  // namespace

// Parts with fewer light paths than pixels x samples (adaptive sampling stops pixels; so does a
// pass cut by the time limit): each part's light-tracing image is weighted by the light paths it
// traced, one per camera sample, which SampleCount counts independently of the header.
TEST(MergeLightPaths, AdaptivePartsAreWeightedByTheLightPathsTraced) {
  ScenePtr s = merge_scene(false);
  TempDir dir;
  const std::string a = dir.path + "/a.exr", b = dir.path + "/b.exr", out = dir.path + "/m.exr";
  lt_render_settings ra = settings_for(LT_INTEGRATOR_BIDIRECTIONAL, 0, 48);
  ra.noise_target = 0.001f;  // never met: adaptive sampling runs to the last sample
  ra.adaptive = 1;
  ra.min_samples = 8;
  render_part(s.get(), ra, a);
  render_part(s.get(), settings_for(LT_INTEGRATOR_BIDIRECTIONAL, 48, 16), b);
  ASSERT_EQ(merge(out, {a, b}), LT_OK) << lt_last_error();
  const lt::ExrImage pa = lt::read_exr(a), pb = lt::read_exr(b), m = lt::read_exr(out);
  double la = 0, lb = 0;
  for (float c : pa.find("SampleCount.X")->pixels) la += c;
  for (float c : pb.find("SampleCount.X")->pixels) lb += c;
  ASSERT_LT(la, 48.0 * kW * kH) << "adaptive sampling stopped no pixel: the test would not test anything";
  EXPECT_EQ(pa.attributes.at("lantern/light_paths"), std::to_string((long long)la));
  EXPECT_EQ(m.attributes.at("lantern/light_paths"), std::to_string((long long)(la + lb)));
  for (const char* ch : {"LightTracing.R", "LightTracing.G", "LightTracing.B"}) {
    const auto &xa = pa.find(ch)->pixels, &xb = pb.find(ch)->pixels, &xm = m.find(ch)->pixels;
    for (size_t i = 0; i < xm.size(); ++i) {
      const double want = (la * xa[i] + lb * xb[i]) / (la + lb);
      ASSERT_NEAR(xm[i], want, 1e-5 * std::abs(want) + 1e-30) << ch << " pixel " << i;
    }
  }
  // A light group likewise: its camera part by the pixel's samples, its splat part by light paths.
  const auto &ca = pa.find("SampleCount.X")->pixels, &cb = pb.find("SampleCount.X")->pixels;
  const auto &ga = pa.find("Combined_lamp.R")->pixels, &gb = pb.find("Combined_lamp.R")->pixels;
  const auto &sa = pa.find("LightTracing.Combined_lamp.R")->pixels,
             &sb = pb.find("LightTracing.Combined_lamp.R")->pixels;
  const auto& gm = m.find("Combined_lamp.R")->pixels;
  for (size_t i = 0; i < gm.size(); ++i) {
    const double want = (ca[i] * (double(ga[i]) - sa[i]) + cb[i] * (double(gb[i]) - sb[i])) / (ca[i] + cb[i]) +
                        (la * sa[i] + lb * sb[i]) / (la + lb);
    ASSERT_NEAR(gm[i], want, 1e-5 * std::abs(want) + 1e-7) << "Combined_lamp.R pixel " << i;
  }
}
