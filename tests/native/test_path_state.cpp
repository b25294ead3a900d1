// Russian roulette (integrators/path_state.h): Cycles 3.4's survival probability and unbiasedness.
#include <gtest/gtest.h>

#include "integrators/path_state.h"

using lt::Spectrum;

TEST(PathState, RussianRouletteSurvivesAsCyclesSquareRoot) {
  // Cycles' path_state_continuation_probability: min(1, sqrt(max |throughput|)), here relative to
  // the path's start (a light subpath's emitted power), the sign ignored.
  EXPECT_FLOAT_EQ(lt::survival_probability(Spectrum(0.25f, 0.1f, 0.0f)), 0.5f);
  EXPECT_FLOAT_EQ(lt::survival_probability(Spectrum(0.0f, -0.04f, 0.01f)), 0.2f);
  EXPECT_FLOAT_EQ(lt::survival_probability(Spectrum(2.0f, 0.5f, 0.5f), 8.0f), 0.5f);
  EXPECT_EQ(lt::survival_probability(Spectrum(1.0f)), 1.0f);
  EXPECT_EQ(lt::survival_probability(Spectrum(3.0f, 0.0f, 0.0f)), 1.0f);
}

TEST(PathState, RussianRouletteIsUnbiasedAndNeverAmplifiesPastTheStart) {
  // Over every decision (the roulette's number is a call of the sample's Sampler, so average over
  // samples), survivors are divided by q: the mean throughput is the input's; a survivor's
  // relative throughput is sqrt(|beta| / start) <= 1. Before the first bounce nothing is drawn or ended.
  const Spectrum in(0.09f, 0.03f, 0.06f);
  const int n = 1 << 14;
  double mean[3] = {0, 0, 0};
  int survived = 0;
  for (int i = 0; i < n; ++i) {
    lt::Sampler s(5, 0, uint32_t(i), lt::SamplePattern::SobolOwen);
    Spectrum beta = in;
    if (!lt::russian_roulette(lt::kPathRouletteBounce, lt::kPathRouletteBounce, &beta, s)) continue;
    ++survived;
    EXPECT_NEAR(lt::max_abs_component(beta), 0.3f, 1e-6f);
    for (int k = 0; k < 3; ++k) mean[k] += beta[k] / n;
  }
  // Stratified numbers: the survivors' share is 0.3 to within a few over n.
  EXPECT_NEAR(double(survived) / n, 0.3, 4.0 / n);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(mean[k], in[k], 4.0 / n * in[k] / 0.3) << k;
  lt::Sampler s(5, 0, 0, lt::SamplePattern::SobolOwen);
  Spectrum beta = in;
  EXPECT_TRUE(lt::russian_roulette(lt::kPathRouletteBounce - 1, lt::kPathRouletteBounce, &beta, s));
  EXPECT_EQ(beta[0], in[0]);
}
