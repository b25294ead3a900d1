#include "core/render.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstdio>

#include "core/label_font.h"

namespace lt {

namespace {
constexpr int kTile = 16;
// Readers see a new image at most this often while rendering (publishing copies the film).
constexpr double kPublishInterval = 0.25;

// The volume debug view's panel names, stamped at each panel's top-left corner (in the region's
// pixels): 2x for panels 200 px wide or more, skipped for panels too small to hold them.
std::vector<uint8_t> volume_debug_labels(const RenderSettings& s, int region_w, int region_h) {
  static const char* const kNames[4] = {"T MARCH", "T RATIO", "D MARCH", "D DELTA"};
  const int hw = std::max(1, s.width / 2), hh = std::max(1, s.height / 2);
  const int pw = std::min(hw, s.width - hw), ph = std::min(hh, s.height - hh);
  constexpr int kMargin = 1;
  int scale = pw >= 200 ? 2 : 1;
  while (scale > 0 && (label_width("T MARCH", scale) + 2 * kMargin > pw || label_height(scale) + 2 * kMargin > ph))
    --scale;
  if (!scale) return {};
  std::vector<uint8_t> mask(size_t(region_w) * region_h, kLabelNone);
  for (int panel = 0; panel < 4; ++panel) {
    const int x = (panel % 2) * hw + kMargin, y_top = (panel < 2 ? s.height : hh) - 1 - kMargin;
    stamp_label(mask, region_w, region_h, x - s.x0, y_top - s.y0, kNames[panel], scale);
  }
  return mask;
}
}  // namespace

RenderJob::RenderJob(const Scene& scene, const RenderSettings& s)
    : scene_(scene),
      settings_(s),
      camera_(scene.camera, s.width, s.height),
      filter_(s.filter, s.filter_width),
      film_(s.x1 - s.x0, s.y1 - s.y0) {
  const int depth = s.integrator_settings.strategy_depth;
  if (s.integrator == IntegratorType::Bidirectional && depth > 0) film_.enable_strategies(depth * strategy_columns(depth));
  if (s.integrator == IntegratorType::VolumeDebug) film_.set_labels(volume_debug_labels(s, film_.width(), film_.height()));
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
  if (settings_.integrator == IntegratorType::Bidirectional) {
    RenderContext ctx{scene_, camera_, filter_, settings_.integrator_settings,
                      settings_.x0, settings_.y0, film_.width(), film_.height()};
    const int cells = film_.strategy_cells();
    render_pass_with(sample_index, [&](const CameraSample& cs, Sampler& sampler, SampleStats& stats, std::vector<Splat>& splats) {
      if (!cells) return trace_bdpt(ctx, cs, sampler, stats, splats);
      thread_local std::vector<Spectrum> strategies;
      strategies.assign(size_t(cells), Spectrum(0.0f));
      SampleValue v = trace_bdpt(ctx, cs, sampler, stats, splats, strategies.data());
      if (is_finite(v.radiance))
        film_.add_strategies(int(cs.pixel_center.x) - settings_.x0, int(cs.pixel_center.y) - settings_.y0, strategies.data());
      return v;
    });
    // Merge the splats tile by tile in a fixed order (deterministic for any thread count).
    for (auto& list : tile_splats_) {
      for (const Splat& sp : list) {
        film_.add_splat(sp.pixel, sp.value);
        if (sp.strategy >= 0) film_.add_strategy_splat(sp.pixel, sp.strategy, sp.value);
      }
      list.clear();
    }
    film_.add_light_paths(uint64_t(film_.width()) * film_.height());
  } else if (settings_.integrator == IntegratorType::VolumeDebug) {
    // Panels: top row transmittance (marching | ratio tracking), bottom row sampled distance
    // (marching | delta tracking); each panel is the whole view at half the resolution.
    const int hw = std::max(1, settings_.width / 2), hh = std::max(1, settings_.height / 2);
    render_pass_with(sample_index, [&](const CameraSample& cs, Sampler& sampler, SampleStats& stats, std::vector<Splat>&) {
      const int col = cs.film.x >= hw ? 1 : 0, top = cs.film.y >= hh ? 1 : 0;
      float fx = std::min(cs.film.x - col * hw, float(hw)) * settings_.width / float(hw);
      float fy = std::min(cs.film.y - top * hh, float(hh)) * settings_.height / float(hh);
      return trace_volume_debug(scene_, settings_.integrator_settings, camera_.generate(fx, fy), (1 - top) * 2 + col,
                                sampler, stats);
    });
  } else if (settings_.integrator == IntegratorType::VolPath && scene_.has_media()) {
    render_pass_with(sample_index, [&](const CameraSample& cs, Sampler& sampler, SampleStats& stats, std::vector<Splat>&) {
      return trace_volpath(scene_, settings_.integrator_settings, cs.ray, sampler, stats);
    });
  } else {
    // Path tracing; also "Volumetric Path" on a scene without media (the same estimator, no cost).
    render_pass_with(sample_index, [&](const CameraSample& cs, Sampler& sampler, SampleStats& stats, std::vector<Splat>&) {
      return trace_path(scene_, settings_.integrator_settings, cs.ray, sampler, stats);
    });
  }
}

template <class Trace>
void RenderJob::render_pass_with(int sample_index, Trace trace) {
  const int w = film_.width(), h = film_.height();
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  tile_splats_.resize(size_t(tiles_x) * tiles_y);
  tbb::parallel_for(tbb::blocked_range2d<int>(0, tiles_y, 1, 0, tiles_x, 1), [&](const tbb::blocked_range2d<int>& r) {
    SampleStats stats;
    uint64_t nans = 0;
    for (int ty = r.rows().begin(); ty < r.rows().end(); ++ty)
      for (int tx = r.cols().begin(); tx < r.cols().end(); ++tx) {
        if (cancel_.load(std::memory_order_relaxed)) break;
        std::vector<Splat>& splats = tile_splats_[size_t(ty) * tiles_x + tx];
        for (int y = ty * kTile; y < std::min(h, (ty + 1) * kTile); ++y)
          for (int x = tx * kTile; x < std::min(w, (tx + 1) * kTile); ++x) {
            const int fx = x + settings_.x0, fy = y + settings_.y0;
            // Random numbers depend only on (seed, pixel of the full frame, sample index).
            Sampler sampler(settings_.seed, uint32_t(fy) * uint32_t(settings_.width) + uint32_t(fx), uint32_t(sample_index));
            float ox = filter_.sample(sampler.next_1d()), oy = filter_.sample(sampler.next_1d());
            CameraSample cs;
            cs.pixel_center = {fx + 0.5f, fy + 0.5f};
            cs.film = {fx + 0.5f + ox, fy + 0.5f + oy};
            cs.ray = camera_.generate(cs.film.x, cs.film.y);
            size_t splat_mark = splats.size();
            SampleValue v = trace(cs, sampler, stats, splats);
            if (!is_finite(v.radiance) || !std::isfinite(v.alpha) || !is_finite(v.albedo) || !is_finite(v.normal)) {
              ++nans;  // never written into the film; counted in the render statistics
              splats.resize(splat_mark);
              continue;
            }
            if (v.depth < 1e10f) v.depth = camera_.depth(cs.ray.o + cs.ray.d * v.depth);
            film_.add(x, y, v);
          }
      }
    rays_.fetch_add(stats.rays, std::memory_order_relaxed);
    if (nans) nan_samples_.fetch_add(nans, std::memory_order_relaxed);
  });
}

void RenderJob::run() {
  if (start_ == std::chrono::steady_clock::time_point()) start_ = std::chrono::steady_clock::now();
  try {
    tbb::task_arena arena(settings_.threads > 0 ? settings_.threads : tbb::task_arena::automatic);
    auto last_publish = std::chrono::steady_clock::now();
    arena.execute([&] {
      for (int s = 0; s < settings_.samples; ++s) {
        if (cancel_.load()) break;
        render_pass(settings_.sample_offset + s);
        if (cancel_.load()) break;
        samples_done_.store(s + 1);
        auto now = std::chrono::steady_clock::now();
        if (std::chrono::duration<double>(now - last_publish).count() >= kPublishInterval) {
          film_.publish();
          last_publish = now;
        }
      }
    });
    film_.publish();
    finished_elapsed_.store(std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
    state_.store(cancel_.load() ? int(RenderState::Cancelled) : int(RenderState::Done));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lantern: render failed: %s\n", e.what());
    error_ = e.what();
    film_.publish();
    finished_elapsed_.store(std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
    state_.store(int(RenderState::Failed));
  }
}

RenderStatus RenderJob::status() const {
  RenderStatus st;
  st.state = RenderState(state_.load());
  st.samples_done = samples_done_.load();
  st.samples_total = settings_.samples;
  double fin = finished_elapsed_.load();
  st.elapsed = fin >= 0 ? fin : std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (st.state != RenderState::Running) st.remaining = 0;
  else if (st.samples_done > 0) st.remaining = st.elapsed / st.samples_done * (st.samples_total - st.samples_done);
  st.nan_samples = nan_samples_.load();
  st.rays = rays_.load();
  return st;
}

}  // namespace lt
