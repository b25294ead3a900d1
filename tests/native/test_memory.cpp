// Bounded memory (issue 18): the film keeps only the passes a render asks for, a render that would
// not fit is refused before it allocates, an allocation failure on the render thread ends the render
// as Failed without aborting the process, and images are stored once at the source's precision.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "core/film.h"
#include "integrators/integrator.h"
#include "io/image_file.h"
#include "render/render.h"
#include "scene_builders.h"
#include "shading/image.h"

extern char** environ;

using namespace lt_test;

namespace {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kSanitized = true;  // shadow memory takes terabytes of address space: no RLIMIT_AS
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

ScenePtr lit_scene() {
  ScenePtr s = new_scene();
  add_object(s.get(), plane(10, 10), add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}));
  add_object(s.get(), icosphere(1, 2), add_diffuse(s.get(), {0.5f, 0.6f, 0.7f}), translate({0, 0, 1}));  // noise
  add_light(s.get(), sun_light({0.2f, 0.1f, -1}, 3));
  set_world(s.get(), {0.1f, 0.1f, 0.1f}, 1);
  set_camera(s.get(), perspective_camera(look_at({0, -4, 3}, {0, 0, 0}), 35));
  check(lt_scene_commit(s.get()), "commit");
  return s;
}

size_t address_space_in_use() {
  unsigned long long pages = 0;
  FILE* f = std::fopen("/proc/self/statm", "r");
  if (f) {
    if (std::fscanf(f, "%llu", &pages) != 1) pages = 0;
    std::fclose(f);
  }
  return size_t(pages) * size_t(sysconf(_SC_PAGESIZE));
}

void limit_address_space(size_t bytes) {
  struct rlimit rl;
  ASSERT_EQ(getrlimit(RLIMIT_AS, &rl), 0);
  rl.rlim_cur = bytes;
  ASSERT_EQ(setrlimit(RLIMIT_AS, &rl), 0);
}

// The child's malloc: one arena, and blocks of 1 MiB and more mapped and unmapped on their own (no
// dynamic threshold), so that no freed or reserved space can serve an allocation past the limit.
// Set before the process starts: set by mallopt in the test, a second arena (64 MiB reserved)
// existed in 5 of 40 runs, and glibc retries a failed allocation in another arena.
constexpr char kChildMalloc[] = "glibc.malloc.arena_max=1:glibc.malloc.mmap_threshold=1048576";

// Runs one DISABLED_ test of this binary in a fresh process (a fork would inherit TBB's state),
// returns its wait status.
int run_child_test(const char* name) {
  char self[4096];
  const ssize_t len = readlink("/proc/self/exe", self, sizeof self - 1);
  if (len <= 0) return -1;
  self[len] = 0;
  std::string filter = std::string("--gtest_filter=") + name;
  char also[] = "--gtest_also_run_disabled_tests";
  char* argv[] = {self, filter.data(), also, nullptr};
  std::vector<std::string> env_strings;
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "GLIBC_TUNABLES=", 15) != 0) env_strings.emplace_back(*e);
  env_strings.push_back(std::string("GLIBC_TUNABLES=") + kChildMalloc);
  std::vector<char*> envp;
  for (std::string& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);
  pid_t pid;
  if (posix_spawn(&pid, self, nullptr, nullptr, argv, envp.data()) != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return status;
}

void expect_clean_exit(int status, const char* what) {
  EXPECT_TRUE(WIFEXITED(status)) << what << ": the child died of signal "
                                 << (WIFSIGNALED(status) ? WTERMSIG(status) : 0)
                                 << " (an abort is what this test guards against)";
  if (WIFEXITED(status))
    EXPECT_EQ(WEXITSTATUS(status), 0) << what << ": the child's assertions failed (see its output)";
}

}  // namespace

TEST(Memory, FilmKeepsOnlyThePassesAskedFor) {
  lt::FilmLayout lean;
  lean.passes = lt::pass_bit(lt::Pass::Combined) | lt::pass_bit(lt::Pass::Depth);
  lean.squares = false;
  // mean RGB, alpha, half RGB, count, depth and the published RGBA in half floats: 11 floats.
  // Cycles' render buffer for Combined + Depth with adaptive sampling (its default) is 10
  // floats; Blender's RenderResult adds 5 more for either engine (bench/memory.py measures it).
  EXPECT_EQ(lean.bytes_per_pixel(), 11u * 4u);
  lt::FilmLayout all;
  // Every pass: Normal, Albedo, Variance's squares and the denoising features (both halves' sums,
  // and half B's squares for the half images' variances).
  // The light passes: 13 RGB (Colours included); Position, UV (3 each), Mist and two indices;
  // AO (RGB) and Vector (4 and the count of samples that wrote one).
  EXPECT_EQ(all.bytes_per_pixel(), (11u + 3 + 3 + 3 + 2 * lt::kFeatureChannels + 3 + 13 * 3 + 3 + 3 + 3 + 3 + 5) * 4u);
  // Reading a pass the film does not keep is an error, never zeros that look like data.
  lt::Film film(4, 3, lean);
  film.finish();
  std::vector<float> out(4 * 3 * 3);
  EXPECT_THROW(film.read(lt::Pass::Albedo, out.data()), std::runtime_error);
  EXPECT_NO_THROW(film.read(lt::Pass::Depth, out.data()));

  // Through the ABI: the pass mask, and the same Combined either way.
  ScenePtr s = lit_scene();
  lt_render_settings rs = render_settings(24, 16, 4, 7);
  Passes full = render(s.get(), rs);
  rs.passes = (1u << LT_PASS_COMBINED) | (1u << LT_PASS_DEPTH);
  lt_render* r = nullptr;
  ASSERT_EQ(lt_render_start(s.get(), &rs, &r), LT_OK) << lt_last_error();
  RenderPtr rp(r);
  ASSERT_EQ(lt_render_wait(r), LT_OK) << lt_last_error();
  std::vector<float> combined(24 * 16 * 4), normal(24 * 16 * 3);
  ASSERT_EQ(lt_render_read_pass(r, LT_PASS_COMBINED, combined.data(), combined.size()), LT_OK);
  EXPECT_EQ(std::memcmp(combined.data(), full.combined.data(), combined.size() * sizeof(float)), 0);
  EXPECT_EQ(lt_render_read_pass(r, LT_PASS_NORMAL, normal.data(), normal.size()), LT_ERROR_STATE);
  EXPECT_NE(std::string(lt_last_error()).find("Normal"), std::string::npos) << lt_last_error();
}

// The render job sizes the film and estimates its memory from what the integrator type asks
// (integrator_needs, known before the integrator exists), never from the type's name: BDPT's splat
// buffers and strategy view in the film, a pass's splat lists in the estimate, nothing for the rest.
TEST(Memory, FilmAndEstimateFollowTheIntegratorsNeeds) {
  lt::RenderSettings rs;
  rs.width = rs.x1 = 64;
  rs.height = rs.y1 = 32;
  rs.integrator_settings.strategy_depth = 3;
  const size_t other_path = lt::RenderJob::estimate_bytes(rs).other;
  for (lt::IntegratorType type : {lt::IntegratorType::Path, lt::IntegratorType::VolPath,
                                  lt::IntegratorType::VolumeDebug, lt::IntegratorType::Bidirectional}) {
    rs.integrator = type;
    const lt::IntegratorNeeds needs = lt::integrator_needs(type, rs.integrator_settings);
    const bool bdpt = type == lt::IntegratorType::Bidirectional;
    EXPECT_EQ(needs.splats, bdpt);
    EXPECT_EQ(needs.strategy_cells, bdpt ? 3 * lt::strategy_columns(3) : 0);
    const lt::FilmLayout layout = lt::RenderJob::film_layout(rs);
    EXPECT_EQ(layout.splats, needs.splats) << int(type);
    EXPECT_EQ(layout.strategy_cells, needs.strategy_cells) << int(type);
    EXPECT_EQ(lt::RenderJob::estimate_bytes(rs).other - other_path, size_t(64 * 32) * needs.bytes_per_pixel)
        << int(type);
    EXPECT_EQ(needs.bytes_per_pixel, bdpt ? sizeof(lt::Splat) : 0u);
  }
}

TEST(Memory, PassesReadInRowBandsAreTheFullPassesRows) {
  // The add-on hands Blender its passes through a band-sized buffer (lt_render_read_pass_rows):
  // every band must be exactly those rows of the full read, labels included.
  ScenePtr s = lit_scene();
  lt_render_settings rs = render_settings(24, 16, 4, 7);
  rs.passes = (1u << LT_PASS_COUNT) - 1;  // every pass, AO and Vector too
  lt_render* r = nullptr;
  ASSERT_EQ(lt_render_start(s.get(), &rs, &r), LT_OK) << lt_last_error();
  RenderPtr rp(r);
  ASSERT_EQ(lt_render_wait(r), LT_OK) << lt_last_error();
  for (int pass = 0; pass < LT_PASS_COUNT; ++pass) {
    const size_t c = size_t(lt_pass_channels(pass)), row = 24 * c;
    std::vector<float> full(16 * row), band;
    ASSERT_EQ(lt_render_read_pass(r, pass, full.data(), full.size()), LT_OK) << lt_last_error();
    for (int y0 = 0; y0 < 16; y0 += 5) {
      const int rows = std::min(5, 16 - y0);
      band.assign(rows * row, -1.0f);
      ASSERT_EQ(lt_render_read_pass_rows(r, pass, y0, rows, band.data(), band.size()), LT_OK) << lt_last_error();
      EXPECT_EQ(std::memcmp(band.data(), full.data() + y0 * row, band.size() * sizeof(float)), 0)
          << "pass " << pass << " rows " << y0;
    }
  }
  std::vector<float> buf(24 * 4 * 4);
  EXPECT_EQ(lt_render_read_pass_rows(r, LT_PASS_COMBINED, 13, 4, buf.data(), buf.size()), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_render_read_pass_rows(r, LT_PASS_COMBINED, -1, 4, buf.data(), buf.size()), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_render_read_pass_rows(r, LT_PASS_COMBINED, 0, 3, buf.data(), buf.size()), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_render_read_pass_rows(r, LT_PASS_COMBINED, 0, -4, buf.data(), buf.size()), LT_ERROR_INVALID_ARGUMENT);
}

TEST(Memory, ConstantPixelsKeepTheirValueAndZeroVariance) {
  // Float accumulators as running means: n equal samples give exactly that value and variance 0
  // (float sums would give n * v rounded, and a sum of squares a spurious variance).
  lt::Film film(1, 1);
  lt::SampleValue v;
  v.radiance = lt::Spectrum(0.2f, 0.35f, 1e-3f);
  v.alpha = 1;
  for (int i = 0; i < 1001; ++i) film.add(0, 0, v);
  EXPECT_EQ(film.pixel_variance(0, 0), 0.0);
  EXPECT_EQ(film.error_estimate(1001).rel_error, 0.0);
  film.finish();
  float rgba[4], var[3];
  film.read(lt::Pass::Combined, rgba);
  film.read(lt::Pass::Variance, var);
  EXPECT_EQ(rgba[0], 0.2f);
  EXPECT_EQ(rgba[1], 0.35f);
  EXPECT_EQ(rgba[2], 1e-3f);
  EXPECT_EQ(rgba[3], 1.0f);
  EXPECT_EQ(var[0] + var[1] + var[2], 0.0f);
}

TEST(Memory, PublishedImageIsHalfFloatAndFinalReadsAreExact) {
  // Readers see Combined in half floats while the render runs (a display's precision, 8 bytes a
  // pixel); once it has stopped they read the float accumulators.
  const float values[] = {0.5f, 0.2f, 1e-6f, 3e-8f, 1234.567f, 1e6f, 0.0f};
  const int n = int(sizeof values / sizeof values[0]);
  lt::Film film(n, 1);
  float rgba[4 * n];
  film.read(lt::Pass::Combined, rgba);  // before the first publish: zeros
  for (float v : rgba) EXPECT_EQ(v, 0.0f);
  for (int x = 0; x < n; ++x) {
    lt::SampleValue s;
    s.radiance = lt::Spectrum(values[x], -values[x], values[x] * 0.75f);
    s.alpha = 1;
    film.add(x, 0, s);
  }
  film.publish();
  film.read(lt::Pass::Combined, rgba);
  for (int x = 0; x < n; ++x) {
    const float v = values[x];
    // Half: 11 significant bits above 2^-14, steps of 2^-24 below it, at most 65504.
    const float tol = std::max(std::abs(v) * 0x1p-11f, 0x1p-25f);
    EXPECT_NEAR(rgba[4 * x], std::min(v, 65504.0f), v > 65504 ? 0 : tol) << v;
    EXPECT_NEAR(rgba[4 * x + 1], -std::min(v, 65504.0f), v > 65504 ? 0 : tol) << v;
    EXPECT_EQ(rgba[4 * x + 3], 1.0f);
  }
  EXPECT_EQ(rgba[0], 0.5f);
  film.finish();
  film.read(lt::Pass::Combined, rgba);
  for (int x = 0; x < n; ++x) EXPECT_EQ(rgba[4 * x], values[x]);
}

TEST(Memory, RenderThatDoesNotFitIsRefusedBeforeAllocating) {
  if (kSanitized) GTEST_SKIP() << "sanitizers reserve address space: RLIMIT_AS cannot be used";
  expect_clean_exit(run_child_test("Memory.DISABLED_ChildRefusedUnderAddressSpaceLimit"), "refusal");
}

TEST(Memory, DISABLED_ChildRefusedUnderAddressSpaceLimit) {
  ScenePtr s = lit_scene();
  limit_address_space(address_space_in_use() + (size_t(1) << 30));
  lt_render_settings rs = render_settings(8000, 8000, 4, 1);  // about 3.3 GiB of film
  lt_render* r = nullptr;
  const int started = lt_render_start(s.get(), &rs, &r);
  RenderPtr(r).reset();  // stopped before the scene goes, should the refusal have failed
  ASSERT_EQ(started, LT_ERROR_OUT_OF_MEMORY);
  const std::string msg = lt_last_error();
  EXPECT_NE(msg.find("8000x8000 render needs about"), std::string::npos) << msg;
  EXPECT_NE(msg.find("is available"), std::string::npos) << msg;
  // What the caller adds is counted too: a small render with a huge caller share is refused.
  rs = render_settings(64, 64, 1, 1);
  rs.caller_bytes = 4ull << 30;
  r = nullptr;
  ASSERT_EQ(lt_render_start(s.get(), &rs, &r), LT_ERROR_OUT_OF_MEMORY);
  EXPECT_NE(std::string(lt_last_error()).find("caller 4.00 GiB"), std::string::npos) << lt_last_error();
  rs.caller_bytes = 0;
  ASSERT_EQ(lt_render_start(s.get(), &rs, &r), LT_OK) << lt_last_error();
  RenderPtr rp(r);
  EXPECT_EQ(lt_render_wait(r), LT_OK) << lt_last_error();
}

TEST(Memory, AllocationFailureOnTheRenderThreadEndsTheRenderWithoutAborting) {
  if (kSanitized) GTEST_SKIP() << "sanitizers reserve address space: RLIMIT_AS cannot be used";
  expect_clean_exit(run_child_test("Memory.DISABLED_ChildRenderThreadRunsOutOfMemory"), "render thread");
}

TEST(Memory, DISABLED_ChildRenderThreadRunsOutOfMemory) {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  ASSERT_TRUE(tunables && std::strcmp(tunables, kChildMalloc) == 0)
      << "run through Memory.AllocationFailureOnTheRenderThreadEndsTheRenderWithoutAborting (kChildMalloc)";
  ScenePtr s = lit_scene();
  // Adaptive sampling allocates 8 bytes per pixel on the render thread after each pass from
  // min_samples on (RenderJob::update_active); the address space is capped after the first pass.
  const int w = 1200, h = 1000;
  lt_render_settings rs = render_settings(w, h, 4, 1);
  rs.noise_target = 1e-6f;
  rs.adaptive = 1;
  rs.min_samples = 2;
  rs.threads = 1;
  lt_render* r = nullptr;
  ASSERT_EQ(lt_render_start(s.get(), &rs, &r), LT_OK) << lt_last_error();
  RenderPtr rp(r);
  lt_render_status st{};
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ASSERT_EQ(lt_render_poll(r, &st), LT_OK);
  } while (st.samples_done < 1 && st.state == LT_STATE_RUNNING);
  ASSERT_EQ(st.samples_done, 1) << "the second pass ended before the limit was set; make it slower";
  limit_address_space(address_space_in_use() + (size_t(2) << 20));
  const int status = lt_render_wait(r);
  limit_address_space(RLIM_INFINITY);
  ASSERT_EQ(lt_render_poll(r, &st), LT_OK);
  ASSERT_NE(st.halt_reason, LT_HALT_NOISE_TARGET) << "the image must stay noisy for this test";
  EXPECT_EQ(status, LT_ERROR_OUT_OF_MEMORY) << lt_last_error();
  EXPECT_NE(std::string(lt_last_error()).find("render failed: out of memory"), std::string::npos) << lt_last_error();
  ASSERT_EQ(lt_render_poll(r, &st), LT_OK);
  EXPECT_EQ(st.state, LT_STATE_FAILED);
  EXPECT_EQ(st.halt_reason, LT_HALT_FAILED);
  // What was rendered stays readable: the first pass reached every pixel.
  Passes p = read_passes(r, w, h);
  EXPECT_EQ(p.first_non_finite(), "");
  int unsampled = 0;
  for (float c : p.sample_count) unsampled += c < 1;
  EXPECT_EQ(unsampled, 0);
}

TEST(Memory, ImagesAreStoredOnceAtTheirPrecision) {
  const int w = 37, h = 23;
  // Byte images as Blender gives them (b * (1/255)): stored as 8-bit RGB, every texel the same.
  std::vector<float> bytes(size_t(w) * h * 4), floats(bytes.size()), grey(size_t(w) * h);
  for (size_t i = 0; i < bytes.size(); ++i) {
    bytes[i] = float((i * 37 + 11) % 256) * (1.0f / 255.0f);
    floats[i] = bytes[i] * 1.5f + 0.01f;
  }
  floats[5] = std::numeric_limits<float>::quiet_NaN();
  for (size_t i = 0; i < grey.size(); ++i) grey[i] = float(i % 7) * 0.1f;
  lt::Image b(w, h, 4, bytes.data(), false, lt::Interpolation::Linear, lt::Extension::Repeat);
  lt::Image f(w, h, 4, floats.data(), false, lt::Interpolation::Linear, lt::Extension::Repeat);
  lt::Image g(w, h, 1, grey.data(), false, lt::Interpolation::Linear, lt::Extension::Repeat);
  EXPECT_TRUE(b.is_byte());
  EXPECT_EQ(b.bytes(), size_t(w) * h * 3);
  EXPECT_FALSE(f.is_byte());
  EXPECT_EQ(f.bytes(), size_t(w) * h * 3 * sizeof(float));  // alpha dropped
  EXPECT_FALSE(g.is_byte());
  EXPECT_EQ(g.bytes(), size_t(w) * h * sizeof(float));
  int differ = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const lt::Vec3 tb = b.texel(x, y), tf = f.texel(x, y), tg = g.texel(x, y);
      for (int k = 0; k < 3; ++k) {
        differ += tb[k] != bytes[4 * i + k];
        differ += tf[k] != (std::isfinite(floats[4 * i + k]) ? floats[4 * i + k] : 0.0f);
        differ += tg[k] != grey[i];
      }
    }
  EXPECT_EQ(differ, 0);

  // Through the ABI without a caller's copy, and the memory it reports.
  ScenePtr s = new_scene();
  lt_image_desc d{};
  d.width = w;
  d.height = h;
  d.channels = 4;
  d.interpolation = LT_INTERP_LINEAR;
  d.extension = LT_EXTENSION_REPEAT;
  float* px = nullptr;
  ASSERT_EQ(lt_scene_begin_image(s.get(), &d, &px), LT_OK) << lt_last_error();
  ASSERT_NE(px, nullptr);
  std::copy(bytes.begin(), bytes.end(), px);
  int id = -1;
  ASSERT_EQ(lt_scene_end_image(s.get(), &id), LT_OK) << lt_last_error();
  EXPECT_EQ(id, 0);
  EXPECT_EQ(lt_scene_end_image(s.get(), &id), LT_ERROR_STATE);  // nothing begun
  ASSERT_EQ(lt_scene_begin_image(s.get(), &d, &px), LT_OK);
  std::copy(floats.begin(), floats.end(), px);
  ASSERT_EQ(lt_scene_end_image(s.get(), &id), LT_OK);
  lt_scene_stats st{};
  ASSERT_EQ(lt_scene_get_stats(s.get(), &st), LT_OK);
  EXPECT_EQ(st.image_texels, 2u * w * h);
  EXPECT_EQ(st.byte_images, 1u);
  EXPECT_EQ(st.image_bytes, uint64_t(w) * h * (3 + 12));
}

TEST(Memory, ImageAlphaIsKeptAsCyclesReadsIt) {
  // 2 x 1 RGBA byte image: an opaque texel and a half-transparent one.
  const float b = 1.0f / 255.0f;
  const float px[8] = {200 * b, 100 * b, 50 * b, 1.0f, 200 * b, 100 * b, 50 * b, 128 * b};
  auto make = [&](lt::ImageAlpha a) {
    return lt::Image(2, 1, 4, px, false, lt::Interpolation::Closest, lt::Extension::Extend, a);
  };
  const lt::Vec2 opaque{0.25f, 0.5f}, half{0.75f, 0.5f};
  // Ignored: as before, no alpha plane, opaque.
  lt::Image ignored = make(lt::ImageAlpha::Ignore);
  EXPECT_FALSE(ignored.has_alpha());
  EXPECT_EQ(ignored.lookup_alpha(half), 1.0f);
  EXPECT_EQ(ignored.bytes(), 6u);
  // Straight bytes are associated in integers as Cycles does: 200 * 128 / 255 = 100 (truncated).
  lt::Image straight = make(lt::ImageAlpha::Straight);
  EXPECT_TRUE(straight.associated());
  EXPECT_EQ(straight.bytes(), 8u);
  EXPECT_EQ(straight.lookup_alpha(half), 128 * b);
  EXPECT_EQ(straight.lookup(half).x, 100 * b);
  EXPECT_EQ(straight.lookup(opaque).x, 200 * b);
  // Unassociated on request (the Alpha output is used): divided back, before any sRGB decoding.
  EXPECT_FLOAT_EQ(straight.lookup(half, true).x, 100 * b / (128 * b));
  // Channel-packed colours are never multiplied or divided.
  lt::Image packed = make(lt::ImageAlpha::ChannelPacked);
  EXPECT_FALSE(packed.associated());
  EXPECT_EQ(packed.lookup(half, true).x, 200 * b);
  EXPECT_EQ(packed.lookup_alpha(half), 128 * b);
  // An alpha of 1 everywhere keeps no plane.
  const float solid[8] = {0.5f, 0.5f, 0.5f, 1, 0.25f, 0.25f, 0.25f, 1};
  EXPECT_FALSE(
      lt::Image(2, 1, 4, solid, false, lt::Interpolation::Linear, lt::Extension::Repeat, lt::ImageAlpha::Straight)
          .has_alpha());
}

TEST(Memory, ImageFilesAreReadAsBlenderGivesThemAndKeptOnce) {
  // An 8-bit RGBA PNG (rows top first in the file) read by the core: the same texels and alpha as
  // the image Blender's Image.pixels gives (b / 255, rows bottom first) added as floats, 4 bytes a
  // texel (RGB and the alpha plane) with no float copy.
  const int w = 5, h = 3;
  std::vector<uint8_t> file(size_t(w) * h * 4);
  for (size_t i = 0; i < file.size(); ++i) file[i] = uint8_t((i * 53 + 7) % 256);
  const std::string path = ::testing::TempDir() + "lantern_image_file.png";
  {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, 4, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:UnassociatedAlpha", 1);  // these bytes as they are (PNG's straight alpha)
    ASSERT_TRUE(out->open(path, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, file.data()));
    out->close();
  }
  std::vector<float> blender(file.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < 4 * w; ++x)
      blender[size_t(h - 1 - y) * w * 4 + x] = file[size_t(y) * w * 4 + x] * (1.0f / 255.0f);
  lt::ImageFileRequest r;
  r.path = path;
  r.use_alpha = true;
  std::unique_ptr<lt::Image> read = lt::read_image_file(r);
  lt::Image ref(w, h, 4, blender.data(), true, lt::Interpolation::Linear, lt::Extension::Repeat,
                lt::ImageAlpha::Straight);
  EXPECT_TRUE(read->is_byte());
  EXPECT_EQ(read->bytes(), size_t(w) * h * 4);
  EXPECT_EQ(read->bytes(), ref.bytes());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const lt::Vec2 uv{(x + 0.5f) / w, (y + 0.5f) / h};
      const lt::Vec3 a = read->texel(x, y), b = ref.texel(x, y);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(a[k], b[k]) << x << "," << y;
      EXPECT_EQ(read->lookup_alpha(uv), ref.lookup_alpha(uv)) << x << "," << y;
    }
  // Through the ABI: what Blender would convert is left to it, a missing file is an I/O error.
  ScenePtr s = new_scene();
  lt_image_file_desc d{};
  d.path = path.c_str();
  d.color_space = LT_COLOR_SPACE_SRGB;
  d.alpha_mode = LT_ALPHA_MODE_STRAIGHT;
  int id = -1;
  EXPECT_EQ(lt_scene_add_image_file(s.get(), &d, &id), LT_OK) << lt_last_error();
  EXPECT_EQ(id, 0);
  d.alpha_mode = LT_ALPHA_MODE_PREMULTIPLIED;  // unpremultiplied as Blender does (below)
  d.interpolation = LT_INTERP_CUBIC;           // any interpolation filters the bytes in place
  EXPECT_EQ(lt_scene_add_image_file(s.get(), &d, &id), LT_OK) << lt_last_error();
  d.interpolation = 3;
  EXPECT_EQ(lt_scene_add_image_file(s.get(), &d, &id), LT_ERROR_INVALID_ARGUMENT);
  d.interpolation = LT_INTERP_LINEAR;
  d.alpha_mode = 7;
  EXPECT_EQ(lt_scene_add_image_file(s.get(), &d, &id), LT_ERROR_INVALID_ARGUMENT);
  d.alpha_mode = LT_ALPHA_MODE_STRAIGHT;
  const std::string missing = path + ".missing.png";
  d.path = missing.c_str();
  EXPECT_EQ(lt_scene_add_image_file(s.get(), &d, &id), LT_ERROR_IO);
  EXPECT_NE(std::string(lt_last_error()).find(missing), std::string::npos) << lt_last_error();
  EXPECT_EQ(lt_scene_add_image_file(s.get(), nullptr, &id), LT_ERROR_INVALID_ARGUMENT);
  std::remove(path.c_str());
}

TEST(Memory, PremultipliedByteFilesAreUnpremultipliedAsBlenderDoes) {
  // Straight (r, g, b, a) bytes in a PNG whose image is set to Premultiplied: Blender 3.4's
  // Image.pixels (measured) gives these colours back (IMB_unpremultiply_rect: b / a rounded in
  // floats, clamped; a = 0 divides by 1, so 40 becomes 255).
  const uint8_t file[][4] = {{150, 50, 250, 200}, {255, 128, 127, 130}, {40, 40, 40, 0}, {1, 2, 3, 4}};
  const uint8_t blender[][3] = {{191, 64, 255}, {255, 251, 249}, {255, 255, 255}, {64, 128, 191}};
  const std::string path = ::testing::TempDir() + "lantern_premultiplied.png";
  {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(4, 1, 4, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:UnassociatedAlpha", 1);
    ASSERT_TRUE(out->open(path, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, file));
    out->close();
  }
  lt::ImageFileRequest r;
  r.path = path;
  r.space = lt::FileColorSpace::Linear;  // byte values as they are
  r.alpha_mode = lt::FileAlphaMode::Premultiplied;
  std::unique_ptr<lt::Image> read = lt::read_image_file(r);
  ASSERT_TRUE(read->is_byte());
  for (int x = 0; x < 4; ++x)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(read->texel(x, 0)[k], blender[x][k] * (1.0f / 255.0f)) << x << "," << k;
  std::remove(path.c_str());
}
