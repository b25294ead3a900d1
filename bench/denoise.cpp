// The denoiser's trade, measured (issue 16): relMSE against a high-sample reference of the noisy
// and the denoised Cornell box over a range of sample counts, with each render's time (denoising
// included) so that equal-time rows can be compared; and the denoiser's time per megapixel on 2
// threads. Run: build/bench/denoise_bench [reference samples, default 2048 | time]
#include <malloc.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "../tests/native/scene_builders.h"
#include "api/handles.h"
#include "denoise/nfor.h"

using namespace lt_test;

namespace {

double rel_mse(const std::vector<float>& image, const std::vector<float>& ref) {
  double sum = 0;
  const size_t n = ref.size() / 4;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const double r = ref[4 * i + c], d = image[4 * i + c] - r;
      sum += d * d / (r * r + 0.01);
    }
  return sum / (3.0 * n);
}

}  // namespace

int main(int argc, char** argv) {
  // "time": the time per megapixel alone (for profiling).
  const bool time_only = argc > 1 && std::string(argv[1]) == "time";
  const int ref_samples = argc > 1 && !time_only ? std::atoi(argv[1]) : 2048, w = 96, h = 96;
  ScenePtr s = cornell_scene();
  if (!time_only) {
    lt_render_settings rs = render_settings(w, h, ref_samples, 1000);
    rs.threads = 2;
    const Passes ref = render(s.get(), rs);
    std::printf("Cornell box %dx%d, reference %d samples (%.1f s), 2 threads\n", w, h, ref_samples,
                ref.status.elapsed_seconds);
    std::printf("%8s %12s %14s %10s %10s %12s\n", "samples", "relMSE noisy", "relMSE denoised", "ratio", "time s",
                "denoise s");
    for (int spp : {4, 8, 16, 32, 64, 128, 256}) {
      lt_render_settings d = render_settings(w, h, spp, 7);
      d.threads = 2;
      d.denoise = 1;
      const Passes p = render(s.get(), d);
      const double noisy = rel_mse(p.noisy, ref.combined), denoised = rel_mse(p.combined, ref.combined);
      std::printf("%8d %12.5f %14.5f %10.2f %10.3f %12.3f\n", spp, noisy, denoised, noisy / denoised,
                  p.status.elapsed_seconds, p.status.denoise_seconds);
    }
    // The image mean's shift (the test Denoise.KeepsTheMeanWithinTheNoise, over six seeds): the
    // denoised minus the noisy image's mean, in units of the noisy mean's standard error
    // sqrt(sum_p var_p) / N, per channel, 64x64 at 16 samples.
    std::printf("mean shift (denoised - noisy) / standard error, 64x64, 16 samples:\n");
    double worst = 0;
    for (unsigned seed = 11; seed < 17; ++seed) {
      lt_render_settings d = render_settings(64, 64, 16, seed);
      d.threads = 2;
      d.denoise = 1;
      const Passes p = render(s.get(), d);
      std::printf("  seed %u:", seed);
      for (int c = 0; c < 3; ++c) {
        double noisy = 0, denoised = 0, var = 0;
        for (size_t i = 0; i < 64 * 64; ++i) {
          noisy += p.noisy[4 * i + c];
          denoised += p.combined[4 * i + c];
          var += p.variance[3 * i + c];
        }
        const double z = (denoised - noisy) / std::sqrt(var);
        worst = std::max(worst, std::abs(z));
        std::printf(" %+.2f", z);
      }
      std::printf("\n");
    }
    std::printf("  largest |shift|: %.2f standard errors\n", worst);
  }
  // Time per megapixel: what a render's end waits for (the film's half images, then the denoiser;
  // RenderJob::run) on a 1024 x 512 render of 4 samples, on a TBB arena of 2 threads, `reps` times
  // after one warm-up: wall time and process CPU time per call (on a shared machine the wall time
  // depends on the other jobs, the CPU time much less). Large blocks are fresh pages at every call,
  // as at a render's single call (glibc would otherwise keep freed blocks for the next).
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);
#endif
  lt_render_settings big = render_settings(1024, 512, 4, 3);
  big.threads = 2;
  const double mp = 1024 * 512 / 1e6;
  // Also what a render with denoising costs beyond the same render without (the features the film
  // keeps and the denoising), process CPU time: the measure of the reports before 2026-12-05.
  const std::clock_t b0 = std::clock();
  render(s.get(), big);
  const std::clock_t b1 = std::clock();
  big.denoise = 1;
  render(s.get(), big);
  const std::clock_t b2 = std::clock();
  std::printf("render with denoising minus without: %.2f CPU s per megapixel\n",
              (double(b2 - b1) - double(b1 - b0)) / CLOCKS_PER_SEC / mp);
  lt_render* raw = nullptr;
  check(lt_render_start(s.get(), &big, &raw), "lt_render_start");
  RenderPtr r(raw);
  check(lt_render_wait(r.get()), "lt_render_wait");
  const lt::Film& film = r->job->film();
  const int reps = 5;
  tbb::task_arena arena(2);
  std::vector<double> wall, cpu, cpu_halves;
  for (int i = 0; i <= reps; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    std::clock_t c1 = c0;
    arena.execute([&] {
      const lt::HalfImages halves = film.half_images();
      c1 = std::clock();
      (void)lt::denoise(halves);
    });
    const std::clock_t c2 = std::clock();
    const auto t1 = std::chrono::steady_clock::now();
    if (i == 0) continue;  // warm-up
    wall.push_back(std::chrono::duration<double>(t1 - t0).count() / mp);
    cpu.push_back(double(c2 - c0) / CLOCKS_PER_SEC / mp);
    cpu_halves.push_back(double(c1 - c0) / CLOCKS_PER_SEC / mp);
  }
  for (auto* v : {&wall, &cpu, &cpu_halves}) std::sort(v->begin(), v->end());
  std::printf(
      "denoiser, 1024x512 on 2 threads, median of %d (min, max): %.2f (%.2f, %.2f) wall s per megapixel, "
      "%.2f (%.2f, %.2f) CPU s per megapixel, of it %.2f the film's half images\n",
      reps, wall[reps / 2], wall.front(), wall.back(), cpu[reps / 2], cpu.front(), cpu.back(), cpu_halves[reps / 2]);
  return 0;
}
