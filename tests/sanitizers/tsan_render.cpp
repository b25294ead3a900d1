// The ThreadSanitizer run (scripts/run_sanitizers.sh): small renders on four TBB threads through
// the C ABI, with the caller polling, reading passes and cancelling while the render threads
// write: bidirectional (camera samples in parallel, splats merged after each pass, the strategy
// view), adaptive sampling (its per-row passes over the film), path tracing and volumetric path
// tracing in fog, a cancelled render, the EXR writer and a merge. TSan (halt_on_error) ends the
// process at the first race; the checks here make sure the renders did what was asked, and that
// four threads give the same bits as one.
#include <tbb/global_control.h>

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "scene_builders.h"

using namespace lt_test;

namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::runtime_error(what);
}

// Starts a render and, until it stops, polls it and reads its Combined pass (the published copy
// the render thread replaces between passes); then reads every pass.
Passes render_while_reading(lt_scene* s, const lt_render_settings& rs, lt_render** keep = nullptr) {
  lt_render* raw = nullptr;
  check(lt_render_start(s, &rs, &raw), "lt_render_start");
  RenderPtr r(raw);
  std::vector<float> combined(size_t(rs.width) * rs.height * 4);
  lt_render_status st{};
  int reads = 0;
  do {
    check(lt_render_poll(r.get(), &st), "poll");
    check(lt_render_read_pass(r.get(), LT_PASS_COMBINED, combined.data(), combined.size()), "read while rendering");
    ++reads;
  } while (st.state == LT_STATE_RUNNING);
  check(lt_render_wait(r.get()), "wait");
  Passes p = read_passes(r.get(), rs.width, rs.height);
  require(p.first_non_finite().empty(), "non-finite pass " + p.first_non_finite());
  std::printf("  %d passes, %d reads while rendering\n", p.status.samples_done, reads);
  if (keep) *keep = r.release();
  return p;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

int main() {
  // Four render threads whatever the machine has (CI has two cores).
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 4);
  try {
    ScenePtr s = varied_scene(/*fog=*/true);
    TempDir dir;

    std::printf("bidirectional, strategy view, 4 threads\n");
    lt_render_settings rs = render_settings(24, 16, 4, 7);
    rs.integrator = LT_INTEGRATOR_BIDIRECTIONAL;
    rs.max_bounces = 6;
    rs.max_camera_length = rs.max_light_length = 6;
    rs.strategy_view_depth = 2;
    rs.threads = 4;
    lt_render* bd_raw = nullptr;
    Passes bd4 = render_while_reading(s.get(), rs, &bd_raw);
    RenderPtr bd(bd_raw);
    require(bd4.status.state == LT_STATE_DONE && bd4.status.samples_done == 4,
            "the bidirectional render did not finish");
    int gw = 0, gh = 0;
    check(lt_render_read_strategy_grid(bd.get(), nullptr, 0, &gw, &gh), "strategy grid size");
    std::vector<float> grid(size_t(gw) * gh * 3);
    check(lt_render_read_strategy_grid(bd.get(), grid.data(), grid.size(), &gw, &gh), "strategy grid");
    const std::string part_a = dir.path + "/a.exr", part_b = dir.path + "/b.exr", merged = dir.path + "/m.exr";
    check(lt_render_write_exr(bd.get(), part_a.c_str()), "write part a");

    std::printf("bidirectional, 1 thread (the same bits)\n");
    rs.threads = 1;
    Passes bd1 = render(s.get(), rs);
    require(same_bits(bd4.combined, bd1.combined) && same_bits(bd4.variance, bd1.variance),
            "4 threads and 1 thread give different bidirectional images");

    std::printf("bidirectional, samples 4-7 (the second part of a merge)\n");
    rs.threads = 4;
    rs.sample_offset = 4;
    rs.strategy_view_depth = 0;
    {
      lt_render* raw = nullptr;
      render_while_reading(s.get(), rs, &raw);
      RenderPtr r(raw);
      check(lt_render_write_exr(r.get(), part_b.c_str()), "write part b");
    }
    const char* parts[] = {part_a.c_str(), part_b.c_str()};
    check(lt_merge_exr(merged.c_str(), parts, 2), "merge");

    std::printf("bidirectional, adaptive sampling to a noise target\n");
    rs.sample_offset = 0;
    rs.samples = 12;
    rs.noise_target = 0.05f;
    rs.adaptive = 1;
    rs.min_samples = 4;
    render_while_reading(s.get(), rs);

    std::printf("volumetric path tracing, 4 threads\n");
    rs = render_settings(24, 16, 4, 3);
    rs.integrator = LT_INTEGRATOR_VOLPATH;
    rs.volume_bounces = 2;
    rs.threads = 4;
    render_while_reading(s.get(), rs);

    std::printf("path tracing, cancelled after its first pass\n");
    rs.integrator = LT_INTEGRATOR_PATH;
    rs.samples = 100000;
    {
      lt_render* raw = nullptr;
      check(lt_render_start(s.get(), &rs, &raw), "start");
      RenderPtr r(raw);
      lt_render_status st{};
      do check(lt_render_poll(r.get(), &st), "poll");
      while (st.samples_done < 1 && st.state == LT_STATE_RUNNING);
      check(lt_render_cancel(r.get()), "cancel");
      check(lt_render_wait(r.get()), "wait");
      check(lt_render_poll(r.get(), &st), "poll");
      require(st.state == LT_STATE_CANCELLED, "the render was not cancelled");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tsan_render: %s\n", e.what());
    return 1;
  }
  std::printf("tsan_render: no race reported\n");
  return 0;
}
