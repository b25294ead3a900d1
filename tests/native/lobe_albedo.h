// Directional albedo of one lobe by Monte Carlo with the lobe's own sampling: the mean of
// f |cos| / pdf, failed samples counting zero, and its standard error (the BSDF and hair tests).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/sampling.h"
#include "shading/bsdf.h"

namespace lt::test {

struct Estimate {
  double mean, se;
};

inline Estimate lobe_albedo(const Lobe& l, const Vec3& wo, int n, uint32_t seed, uint32_t stream = 1) {
  Sampler rng(seed, stream, 0);
  double sum = 0, sum2 = 0;
  for (int k = 0; k < n; ++k) {
    BsdfSample s;
    double v = 0;
    if (lobe_sample(l, wo, rng.next_2d(), rng.next_1d(), &s)) v = max_component(s.f) * std::abs(s.wi.z) / s.pdf;
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / n;
  return {mean, std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n)};
}

}  // namespace lt::test
