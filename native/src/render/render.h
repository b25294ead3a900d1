// A render job: passes over the image on the core's own TBB threads, each camera sample traced by
// the integrator the settings pick (integrators/integrator.h), progress, cancellation and the film
// readers poll. Nothing here calls back into the caller.
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "core/film.h"
#include "integrators/integrator.h"
#include "scene/scene.h"

namespace lt {

struct RenderSettings {
  int width = 640, height = 480;
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // region of the full frame; x1 == 0: all
  int samples = 16;
  uint32_t seed = 0;
  int sample_offset = 0;  // first sample index: the pass s uses sample_offset + s
  SamplePattern pattern = SamplePattern::SobolOwen;
  IntegratorType integrator = IntegratorType::Path;
  IntegratorSettings integrator_settings;
  int threads = 0;
  FilterType filter = FilterType::BlackmanHarris;
  float filter_width = 1.5f;
  // Halting: the render stops at the first of `samples`, `time_limit` seconds (0: none; the first
  // pass always completes) and the image's estimated relative error (ErrorEstimate) reaching
  // `noise_target` (0: none), checked from `min_samples` on. `adaptive`: pixels whose own
  // variance is below their share of the target stop sampling (see RenderJob::update_active).
  double time_limit = 0;
  double noise_target = 0;
  bool adaptive = false;
  int min_samples = 16;
  unsigned passes = kDefaultPasses;  // what the film keeps (FilmLayout::passes)
  // Light groups' names (integrator_settings.lightgroups of them): EXR channels Combined_<name>.
  std::vector<std::string> lightgroup_names;
  // Shader AOVs (integrator_settings.aovs of them): names and whether each is a colour (RGBA) or a
  // value; EXR channels <name>.R/G/B/A or <name>.X.
  std::vector<std::string> aov_names;
  std::vector<bool> aov_colors;
  // Denoise Combined once rendering stops (denoise/nfor.h; not after a cancel, nor with fewer
  // than 2 passes); the film then keeps the features and Noisy Image.
  bool denoise = false;
  // With denoise, > 0: also the published image from max(denoise_start_sample, 2) samples on
  // (lt_render_settings.denoise_start_sample: the viewport's), and the final image only from there.
  int denoise_start_sample = 0;
  // Cryptomatte types kept (bits 1 << CryptomatteType) and Blender's Levels (FilmLayout).
  unsigned cryptomatte = 0;
  int cryptomatte_levels = 6;
  // The scene's motion steps are the previous, this and the next frame for the Vector pass
  // (lt_render_settings.motion_pass): samples are taken at the centre step, nothing blurs.
  bool motion_pass = false;
};

// The film and per-pixel buffers a render allocates, in bytes (RenderJob::estimate_bytes).
struct MemoryEstimate {
  size_t film = 0, other = 0;
  size_t total() const { return film + other; }
};
// What this process can still allocate: the smaller of MemAvailable (/proc/meminfo) and the
// address-space limit (RLIMIT_AS) minus the address space in use; SIZE_MAX when neither is known.
size_t available_memory();

enum class RenderState { Running = 0, Done = 1, Cancelled = 2, Failed = 3 };
// Why a render stopped (None while it runs).
enum class HaltReason { None = 0, Samples = 1, TimeLimit = 2, NoiseTarget = 3, Cancelled = 4, Failed = 5 };

struct RenderStatus {
  RenderState state = RenderState::Running;
  int samples_done = 0, samples_total = 0;
  // Passes begun: a pass cut by the time limit or a cancel has used its sample index in some
  // pixels, so a part's sample range must include it.
  int passes_started = 0;
  double elapsed = 0, remaining = -1;
  uint64_t nan_samples = 0, rays = 0;
  double rel_error = -1;  // ErrorEstimate::rel_error after the last complete pass
  HaltReason halt_reason = HaltReason::None;
  uint64_t active_pixels = 0;       // pixels still sampling (all of them without adaptive sampling)
  uint64_t unestimated_pixels = 0;  // ErrorEstimate::unestimated_pixels of the last estimate
  // Combined holds the denoised image (Noisy Image the film's); while rendering, the published one is.
  bool denoised = false;
  double denoise_seconds = 0;  // the denoiser's time (its last run's while rendering)
};

class RenderJob {
 public:
  // Allocates the film; throws std::bad_alloc when it cannot (check estimate_bytes first).
  RenderJob(const Scene& scene, const RenderSettings& settings);
  static FilmLayout film_layout(const RenderSettings& settings);
  static MemoryEstimate estimate_bytes(const RenderSettings& settings);
  ~RenderJob();
  void start();
  void cancel() { cancel_.store(true); }
  void wait();
  RenderStatus status() const;
  const Film& film() const { return film_; }
  const RenderSettings& settings() const { return settings_; }
  int region_width() const { return film_.width(); }
  int region_height() const { return film_.height(); }
  // Renders synchronously on the calling thread's arena (tests, CLI). Never throws: a failure
  // (an allocation included) ends the render as Failed, keeping what was rendered.
  void run() noexcept;
  // Why the render failed (empty unless Failed), and whether it ran out of memory.
  const char* error() const { return error_; }
  bool out_of_memory() const { return out_of_memory_.load(); }

 private:
  void render_pass(int sample_index);
  bool past_deadline() const;
  void fail(const char* what, bool out_of_memory) noexcept;
  // Adaptive sampling: clears active_ for pixels whose variance meets their share of the target.
  void update_active(const ErrorEstimate& e);
  // The denoised RGB of the film as it is (between passes), its time in denoise_seconds_.
  std::vector<float> denoise_film();
  RenderSettings settings_;
  Camera camera_;
  FilterSampler filter_;
  std::unique_ptr<Integrator> integrator_;
  Film film_;
  std::thread thread_;
  std::atomic<bool> cancel_{false};
  std::atomic<int> state_{0};
  std::atomic<int> samples_done_{0};
  std::atomic<int> passes_started_{0};
  std::atomic<uint64_t> nan_samples_{0}, rays_{0};
  std::atomic<double> rel_error_{-1};
  std::atomic<int> halt_reason_{0};
  std::atomic<uint64_t> active_pixels_{0}, unestimated_pixels_{0};
  std::atomic<double> denoise_seconds_{0};
  // The camera's axes in world space (x right, y up, z forward): Denoising Normal's frame.
  Vec3 camera_x_, camera_y_, camera_z_;
  // Samples traced in the current pass, of them in half B (BDPT: one light path each).
  std::atomic<uint64_t> pass_samples_{0}, pass_samples_half_{0};
  std::vector<uint8_t> active_;  // per pixel of the region: still sampling
  bool motion_ = false;          // something moves: each camera sample draws a shutter time
  bool differentials_ = false;   // a material reads ray differentials (Bump, Wireframe): samples get them
  std::chrono::steady_clock::time_point start_;
  std::atomic<double> finished_elapsed_{-1};
  // Written without allocating (the failure may be an allocation's).
  char error_[512] = {0};
  std::atomic<bool> out_of_memory_{false};
  // Light-tracing splats of the current pass, two lists per tile (half A, half B), merged in tile
  // order so that the image does not depend on the thread count.
  std::vector<std::vector<Splat>> tile_splats_;
};

}  // namespace lt
