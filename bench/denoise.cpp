// The denoiser's trade, measured (issue 16): relMSE against a high-sample reference of the noisy
// and the denoised Cornell box over a range of sample counts, with each render's time (denoising
// included) so that equal-time rows can be compared; and the denoiser's time per megapixel on 2
// threads. Run: build/bench/denoise_bench [reference samples, default 2048]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <vector>

#include "../tests/native/scene_builders.h"

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
  const int ref_samples = argc > 1 ? std::atoi(argv[1]) : 2048, w = 96, h = 96;
  ScenePtr s = cornell_scene();
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
  // Time per megapixel: a 1024 x 512 render of 4 samples, denoised on 2 threads: its wall time, and
  // its CPU time (process CPU time of the render with denoising minus the same render without it;
  // on a shared machine the wall time depends on the other jobs, the CPU time much less).
  lt_render_settings big = render_settings(1024, 512, 4, 3);
  big.threads = 2;
  const double mp = 1024 * 512 / 1e6;
  const std::clock_t c0 = std::clock();
  render(s.get(), big);
  const std::clock_t c1 = std::clock();
  big.denoise = 1;
  const Passes p = render(s.get(), big);
  const std::clock_t c2 = std::clock();
  const double cpu = (double(c2 - c1) - double(c1 - c0)) / CLOCKS_PER_SEC;
  std::printf("denoiser: %.3f s for %.2f MP on 2 threads: %.2f s per megapixel (wall), %.2f CPU s per megapixel\n",
              p.status.denoise_seconds, mp, p.status.denoise_seconds / mp, cpu / mp);
  return 0;
}
