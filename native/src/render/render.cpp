#include "render/render.h"

#include <sys/resource.h>
#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <new>

#include "denoise/nfor.h"

namespace lt {

namespace {
constexpr int kTile = 16;
// With adaptive sampling the active pixels cluster in a few places: smaller tiles spread them over
// the threads.
constexpr int kAdaptiveTile = 4;
// Readers see a new image at most this often while rendering (publishing copies the film).
constexpr double kPublishInterval = 0.25;
// Denoising the published image (settings.denoise_start_sample): after a denoise of d seconds, the
// next waits for at least kDenoisePace d seconds of rendering, so that denoising takes at most
// 1 / (1 + kDenoisePace) of the wall time (a quarter).
constexpr double kDenoisePace = 3.0;

// The integrator's settings with what the kept passes ask it to fill.
IntegratorSettings with_passes(const RenderSettings& s) {
  IntegratorSettings is = s.integrator_settings;
  unsigned light = 0, data = 0;
  for (int p = int(Pass::DiffuseDirect); p <= int(Pass::Environment); ++p) light |= pass_bit(Pass(p));
  for (int p = int(Pass::Position); p <= int(Pass::MaterialIndex); ++p) data |= pass_bit(Pass(p));
  is.light_passes = (s.passes & light) != 0;
  is.data_passes = (s.passes & data) != 0 || s.cryptomatte != 0;
  is.ao_pass = (s.passes & pass_bit(Pass::AO)) != 0;
  // Cycles writes no motion with motion blur on: the pass stays zero.
  is.vector_pass = (s.passes & pass_bit(Pass::Vector)) != 0 && s.motion_pass;
  return is;
}
}  // namespace

RenderJob::RenderJob(const Scene& scene, const RenderSettings& s)
    : settings_(s),
      camera_(scene.camera, s.width, s.height),
      filter_(s.filter, s.filter_width),
      integrator_(make_integrator(
          s.integrator, RenderContext{scene, camera_, filter_, with_passes(s), s.x0, s.y0, s.x1 - s.x0, s.y1 - s.y0})),
      film_(s.x1 - s.x0, s.y1 - s.y0, film_layout(s)),
      active_(size_t(film_.width()) * film_.height(), 1),
      motion_(!s.motion_pass &&
              (scene.geometry.has_motion() || camera_.has_motion() ||
               std::any_of(scene.media.begin(), scene.media.end(), [](const Medium& m) { return m.moves(); }))),
      differentials_(std::any_of(scene.materials.begin(), scene.materials.end(),
                                 [](const Material& m) { return m.needs_differentials(); })) {
  active_pixels_.store(active_.size());
  film_.set_labels(integrator_->film_labels());
  camera_x_ = normalize(scene.camera.xf.column(0));
  camera_y_ = normalize(scene.camera.xf.column(1));
  camera_z_ = -normalize(scene.camera.xf.column(2));
}

FilmLayout RenderJob::film_layout(const RenderSettings& s) {
  FilmLayout l;
  l.passes = s.passes;
  if (s.denoise) l.passes |= kDenoisingFeatures | pass_bit(Pass::NoisyImage);
  l.squares = (s.passes & pass_bit(Pass::Variance)) || s.adaptive;
  const IntegratorNeeds needs = integrator_needs(s.integrator, s.integrator_settings);
  l.splats = needs.splats;
  l.strategy_cells = needs.strategy_cells;
  l.cryptomatte = s.cryptomatte;
  l.cryptomatte_levels = s.cryptomatte_levels;
  l.lightgroups = s.integrator_settings.lightgroups;
  l.aovs = s.integrator_settings.aovs;
  l.shadow_catcher = s.integrator_settings.shadow_catcher;
  l.catcher_approximate = s.integrator_settings.shadow_catcher_approximate;
  l.transparent = s.integrator_settings.transparent_background;
  return l;
}

MemoryEstimate RenderJob::estimate_bytes(const RenderSettings& s) {
  const size_t pixels = size_t(s.x1 - s.x0) * size_t(s.y1 - s.y0);
  MemoryEstimate m;
  m.film = pixels * film_layout(s).bytes_per_pixel();
  m.other = pixels;                       // active_
  if (s.adaptive) m.other += pixels * 8;  // update_active's per-pixel variances
  m.other += pixels * integrator_needs(s.integrator, s.integrator_settings).bytes_per_pixel;
  // Denoising: the half images, the denoiser's planes, its reconstruction sums (2 x RGB + weight)
  // and its output (denoise/nfor.cpp).
  if (s.denoise) m.other += pixels * (2 * (3 + 3 + kFeatureChannels) + 1 + 12 + kFeatureChannels + 1 + 8 + 6) * 4;
  if (s.denoise && s.denoise_start_sample > 0) m.other += pixels * 3 * 4;  // the published image's RGB
  return m;
}

size_t available_memory() {
  size_t avail = SIZE_MAX;
  if (FILE* f = std::fopen("/proc/meminfo", "r")) {
    char line[256];
    unsigned long long kb = 0;
    while (std::fgets(line, sizeof line, f))
      if (std::sscanf(line, "MemAvailable: %llu kB", &kb) == 1) {
        avail = size_t(kb) * 1024;
        break;
      }
    std::fclose(f);
  }
  struct rlimit rl;
  if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
    size_t used = 0;
    if (FILE* f = std::fopen("/proc/self/statm", "r")) {
      unsigned long long pages = 0;
      if (std::fscanf(f, "%llu", &pages) == 1) used = size_t(pages) * size_t(sysconf(_SC_PAGESIZE));
      std::fclose(f);
    }
    const size_t limit = size_t(rl.rlim_cur);
    avail = std::min(avail, limit > used ? limit - used : size_t(0));
  }
  return avail;
}

RenderJob::~RenderJob() {
  cancel();
  wait();
}

void RenderJob::start() {
  start_ = std::chrono::steady_clock::now();
  thread_ = std::thread([this] { run(); });
}

void RenderJob::wait() {
  if (thread_.joinable()) thread_.join();
}

void RenderJob::render_pass(int sample_index) {
  const int w = film_.width(), h = film_.height();
  const int tile_size = settings_.adaptive ? kAdaptiveTile : kTile;
  const int tiles_x = (w + tile_size - 1) / tile_size, tiles_y = (h + tile_size - 1) / tile_size;
  tile_splats_.resize(2 * size_t(tiles_x) * tiles_y);
  pass_samples_.store(0);
  pass_samples_half_.store(0);
  // The time limit may cut any pass but the first, so that every pixel has a sample.
  const bool may_cut = sample_index > 0 && settings_.time_limit > 0;
  integrator_->begin_pass(film_);
  tbb::parallel_for(tbb::blocked_range2d<int>(0, tiles_y, 1, 0, tiles_x, 1), [&](const tbb::blocked_range2d<int>& r) {
    SampleStats stats;
    uint64_t nans = 0, traced = 0, traced_half = 0;
    const int groups = film_.lightgroups(), aov_floats = 4 * film_.aovs();
    std::vector<Spectrum> lightgroups;
    std::vector<float> aovs;
    for (int ty = r.rows().begin(); ty < r.rows().end(); ++ty)
      for (int tx = r.cols().begin(); tx < r.cols().end(); ++tx) {
        if (cancel_.load(std::memory_order_relaxed) || (may_cut && past_deadline())) break;
        const size_t tile = size_t(ty) * tiles_x + tx;
        for (int y = ty * tile_size; y < std::min(h, (ty + 1) * tile_size); ++y)
          for (int x = tx * tile_size; x < std::min(w, (tx + 1) * tile_size); ++x) {
            if (!active_[size_t(y) * w + x]) continue;
            const int half = film_.next_half(x, y);
            ++traced;
            traced_half += uint64_t(half);
            std::vector<Splat>& splats = tile_splats_[2 * tile + size_t(half)];
            const int fx = x + settings_.x0, fy = y + settings_.y0;
            // Random numbers depend only on (seed, pixel of the full frame, sample index).
            Sampler sampler(settings_.seed, uint32_t(fy) * uint32_t(settings_.width) + uint32_t(fx),
                            uint32_t(sample_index), settings_.pattern);
            const Vec2 uf = sampler.next_2d();
            const float ox = filter_.sample(uf.x), oy = filter_.sample(uf.y);
            CameraSample cs;
            cs.pixel_center = {fx + 0.5f, fy + 0.5f};
            cs.film = {fx + 0.5f + ox, fy + 0.5f + oy};
            // A lens sample only for a camera with an aperture: a pinhole's renders stay as they were.
            if (camera_.has_lens()) cs.lens = sampler.next_2d();
            // Motion blur: one shutter time per camera sample (Cycles' PRNG_TIME, uniform over the
            // shutter as its default shutter curve), drawn only when something moves so that
            // other scenes keep their numbers; the whole path, shadow rays and BDPT's light
            // subpath of this sample happen at it.
            const float time = motion_ ? sampler.next_1d() : 0.5f;
            if (!camera_.generate(cs.film.x, cs.film.y, cs.lens, &cs.ray, time)) {
              // The film sees nothing there (outside a fisheye's circle): black and opaque, as Cycles.
              // It still counts as a light path, which BDPT traces (its splats reach the circle).
              integrator_->trace_unseen(cs, sampler, stats, splats);
              SampleValue none;
              none.alpha = 1;
              film_.add(x, y, none);
              continue;
            }
            // Only Bump and Wireframe read the footprint (add_differentials); others skip the cost.
            if (differentials_) camera_.differentials(cs.film.x, cs.film.y, &cs.dP, &cs.dD);
            if (groups > 0) {  // light groups: a zeroed buffer per sample (nothing when there are none)
              lightgroups.assign(size_t(groups), Spectrum(0.0f));
              cs.lightgroups = lightgroups.data();
            }
            if (aov_floats > 0) {
              aovs.assign(size_t(aov_floats), 0.0f);
              cs.aovs = aovs.data();
            }
            size_t splat_mark = splats.size();
            SampleValue v = integrator_->trace(cs, sampler, stats, splats);
            if (!film_.accepts(v)) {
              ++nans;  // never written into the film; counted in the render statistics
              splats.resize(splat_mark);
              continue;
            }
            if (v.depth < 1e10f) {
              if (film_.has_features()) {
                v.feature_distance = v.depth * length(cs.ray.d);
                v.feature_normal = {dot(v.normal, camera_x_), dot(v.normal, camera_y_), dot(v.normal, camera_z_)};
              }
              v.depth = camera_.depth(cs.ray.o + cs.ray.d * v.depth);
            }
            film_.add(x, y, v);
          }
      }
    rays_.fetch_add(stats.rays, std::memory_order_relaxed);
    pass_samples_.fetch_add(traced, std::memory_order_relaxed);
    pass_samples_half_.fetch_add(traced_half, std::memory_order_relaxed);
    if (nans) nan_samples_.fetch_add(nans, std::memory_order_relaxed);
  });
  integrator_->end_pass(film_, PassSplats{tile_splats_, pass_samples_.load(), pass_samples_half_.load()});
  for (std::vector<Splat>& splats : tile_splats_) splats.clear();
}

bool RenderJob::past_deadline() const {
  return settings_.time_limit > 0 &&
         std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count() >= settings_.time_limit;
}

// Per-pixel adaptive sampling (in the spirit of Cycles' adaptive sampling): the image error is
// E^2 = sum_p v_p / sum_pc R_pc^2 (ErrorEstimate), so if every pixel's variance v_p is at most
// target^2 * sum_pc R_pc^2 / pixels, E meets the target. A pixel stops sampling once the largest
// variance among its 8 neighbours (each from its own samples' sample variance) meets that share;
// its mean stays the average of its own samples. Reading the neighbours and never the pixel
// itself keeps its stopping time independent of its own samples (up to the neighbours' counts),
// so the mean stays unbiased: deciding on its own variance would stop a pixel that has not yet
// met a rare bright path and bias it low (measured: tile means off by 2 standard errors on the
// Cornell box). Taking the maximum keeps pixels next to noisy ones sampling, as Cycles' dilation.
// BDPT: the per-pixel variance sees camera samples only; splats keep arriving in stopped pixels
// from the light paths of active ones, normalised by the light paths actually traced (unbiased),
// and the image estimate includes their noise. The share is therefore scaled by (sum of the
// per-pixel variances) / (the halves' sum_p v_p) when that is below 1, and should every pixel
// meet its share while the image misses the target, all pixels sample again.
void RenderJob::update_active(const ErrorEstimate& e) {
  const int w = film_.width(), h = film_.height();
  // Rows in parallel; per-row sums added in row order (the same bits for any thread count).
  std::vector<double> v(active_.size()), row_sum(h, 0.0);
  tbb::parallel_for(0, h, [&](int y) {
    double sum = 0;
    for (int x = 0; x < w; ++x) sum += v[size_t(y) * w + x] = film_.pixel_variance(x, y);
    row_sum[y] = sum;
  });
  double pixel_sum = 0;
  for (double r : row_sum) pixel_sum += r;
  const double seen = e.variance > 0 ? std::min(1.0, pixel_sum / e.variance) : 1.0;
  const double share = settings_.noise_target * settings_.noise_target * e.mean_square * seen;
  std::vector<uint32_t> row_active(h, 0);
  tbb::parallel_for(0, h, [&](int y) {
    uint32_t active = 0;
    for (int x = 0; x < w; ++x) {
      uint8_t& a = active_[size_t(y) * w + x];
      if (a) {
        double nb = -1;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int qx = x + dx, qy = y + dy;
            if ((dx || dy) && qx >= 0 && qx < w && qy >= 0 && qy < h) nb = std::max(nb, v[size_t(qy) * w + qx]);
          }
        if ((nb >= 0 ? nb : v[size_t(y) * w + x]) <= share) a = 0;  // a 1x1 region reads itself
      }
      active += a;
    }
    row_active[y] = active;
  });
  uint64_t active = 0;
  for (uint32_t r : row_active) active += r;
  if (!active) {
    std::fill(active_.begin(), active_.end(), uint8_t(1));
    active = active_.size();
  }
  active_pixels_.store(active);
}

void RenderJob::run() noexcept {
  if (start_ == std::chrono::steady_clock::time_point()) start_ = std::chrono::steady_clock::now();
  try {
    tbb::task_arena arena(settings_.threads > 0 ? settings_.threads : tbb::task_arena::automatic);
    auto last_publish = std::chrono::steady_clock::now();
    HaltReason halt = HaltReason::Samples;
    // The published image is denoised from this many samples on (never: INT_MAX).
    const int denoise_from = settings_.denoise && settings_.denoise_start_sample > 0
                                 ? std::max(2, settings_.denoise_start_sample)
                                 : std::numeric_limits<int>::max();
    std::vector<float> preview;  // the last denoised published image, of preview_samples samples
    int preview_samples = 0;
    arena.execute([&] {
      for (int s = 0; s < settings_.samples; ++s) {
        if (cancel_.load()) break;
        if (s > 0 && past_deadline()) {
          halt = HaltReason::TimeLimit;
          break;
        }
        passes_started_.store(s + 1);
        {
          struct Writing {  // ends the pass's writing also when it throws
            Film& f;
            explicit Writing(Film& film) : f(film) { f.begin_writing(); }
            ~Writing() { f.end_writing(); }
          } writing(film_);
          render_pass(settings_.sample_offset + s);
        }
        if (cancel_.load()) break;
        // A pass cut by the time limit leaves some pixels one sample short: samples_done counts
        // complete passes.
        if (s > 0 && past_deadline()) {
          halt = HaltReason::TimeLimit;
          if (pass_samples_.load() == active_pixels_.load()) samples_done_.store(s + 1);
          break;
        }
        const ErrorEstimate e = film_.error_estimate(s + 1);
        rel_error_.store(e.rel_error);
        unestimated_pixels_.store(e.unestimated_pixels);
        bool reached = false;
        if (settings_.noise_target > 0 && s + 1 >= settings_.min_samples && e.rel_error >= 0) {
          reached = e.rel_error <= settings_.noise_target;
          if (reached)
            halt = HaltReason::NoiseTarget;
          else if (settings_.adaptive)
            update_active(e);
        }
        auto now = std::chrono::steady_clock::now();
        const double since_publish = std::chrono::duration<double>(now - last_publish).count();
        if (s + 1 >= denoise_from) {
          // Once the published image is denoised, every later one is (no flicker back to noise):
          // the first at the start sample, then paced by the denoiser's cost.
          if (s + 1 == denoise_from ||
              since_publish >= std::max(kPublishInterval, kDenoisePace * denoise_seconds_.load())) {
            preview = denoise_film();
            preview_samples = s + 1;
            film_.publish(&preview);
            last_publish = std::chrono::steady_clock::now();
          }
        } else if (((s + 1) & s) == 0 || since_publish >= kPublishInterval) {
          // Also after passes 1, 2, 4, 8, ...: early passes change the image most, and the
          // viewport shows the first one as soon as it exists.
          film_.publish();
          last_publish = now;
        }
        samples_done_.store(s + 1);  // after publishing: a reader that sees pass 1 done can read it
        if (reached) break;
      }
    });
    arena.execute([&] {  // also after a cut pass
      const ErrorEstimate e = film_.error_estimate(samples_done_.load());
      rel_error_.store(e.rel_error);
      unestimated_pixels_.store(e.unestimated_pixels);
      // The denoiser needs both half images; a cancel asks to stop now, so it is not run then.
      // With a start sample, not before it; the last published image is reused when no pass
      // (not even a cut one) came after it.
      const int done = samples_done_.load();
      if (settings_.denoise && !cancel_.load() && done >= 2 && done >= settings_.denoise_start_sample)
        film_.set_denoised(preview_samples == passes_started_.load() ? std::move(preview) : denoise_film());
    });
    film_.finish();
    finished_elapsed_.store(std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
    halt_reason_.store(int(cancel_.load() ? HaltReason::Cancelled : halt));
    state_.store(cancel_.load() ? int(RenderState::Cancelled) : int(RenderState::Done));
  } catch (const std::bad_alloc&) {
    fail("out of memory while rendering", true);
  } catch (const std::exception& e) {
    fail(e.what(), false);
  } catch (...) {
    fail("unknown error", false);
  }
}

std::vector<float> RenderJob::denoise_film() {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<float> rgb = denoise(film_.half_images());
  denoise_seconds_.store(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return rgb;
}

// Ends the render as Failed. Allocates nothing (the failure may be an allocation's): the film
// already holds every pass, and readers read it as it is.
void RenderJob::fail(const char* what, bool out_of_memory) noexcept {
  std::snprintf(error_, sizeof error_, "%s", what);
  std::fprintf(stderr, "lantern: render failed: %s\n", error_);
  out_of_memory_.store(out_of_memory);
  try {
    film_.finish();
  } catch (...) {  // std::mutex::lock may throw std::system_error; the film stays unpublished
  }
  finished_elapsed_.store(std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
  halt_reason_.store(int(HaltReason::Failed));
  state_.store(int(RenderState::Failed));
}

RenderStatus RenderJob::status() const {
  RenderStatus st;
  st.state = RenderState(state_.load());
  st.samples_done = samples_done_.load();
  st.passes_started = passes_started_.load();
  st.samples_total = settings_.samples;
  double fin = finished_elapsed_.load();
  st.elapsed = fin >= 0 ? fin : std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  st.rel_error = rel_error_.load();
  st.halt_reason = HaltReason(halt_reason_.load());
  st.active_pixels = active_pixels_.load();
  st.unestimated_pixels = unestimated_pixels_.load();
  st.denoised = st.state != RenderState::Running ? film_.denoised() : film_.published_denoised();
  st.denoise_seconds = denoise_seconds_.load();
  if (st.state != RenderState::Running) {
    st.remaining = 0;
  } else if (st.samples_done > 0) {
    // The first halting criterion to be met: samples, the time limit, or the noise target with
    // the error falling as 1/sqrt(samples) (an overestimate with adaptive sampling).
    const double per_sample = st.elapsed / st.samples_done;
    double left = per_sample * (st.samples_total - st.samples_done);
    if (settings_.time_limit > 0) left = std::min(left, std::max(0.0, settings_.time_limit - st.elapsed));
    if (settings_.noise_target > 0 && st.rel_error > 0 && std::isfinite(st.rel_error)) {
      const double r = st.rel_error / settings_.noise_target;
      const double needed = std::max(double(settings_.min_samples), st.samples_done * r * r);
      left = std::min(left, per_sample * std::max(0.0, needed - st.samples_done));
    }
    st.remaining = left;
  }
  st.nan_samples = nan_samples_.load();
  st.rays = rays_.load();
  return st;
}

}  // namespace lt
