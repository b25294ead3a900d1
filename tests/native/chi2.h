// One generic chi-square goodness-of-fit tester for direction sampling routines, in the style of
// Mitsuba 3's ChiSquareTest: a sampler adapter draws directions (with the pdf it claims), a pdf
// adapter evaluates the density it is meant to follow, and the tester
//   1. bins N samples over the sphere in (theta, phi) around a chosen pole, with theta edges
//      pi * (k / theta_bins)^theta_power so that a power > 1 resolves a peak placed at the pole;
//   2. integrates the pdf over every bin with nested adaptive Simpson quadrature (expected counts);
//   3. adds one bin for failed samples, expected N * (1 - integral of the pdf), so a sampler that
//      loses or invents mass is caught as well as one that puts it in the wrong place;
//   4. pools bins with expected count < 5 (smallest first) and runs Pearson's test, rejecting at
//      a significance level Sidak-corrected for the number of tests in the suite;
//   5. checks that each sample's claimed pdf equals pdf(direction) and that the pdf integrates
//      to at most 1 (or to a given value).
// BSDFs, phase functions and light shapes all test through it with a small adapter each.
// Seeds are fixed; LANTERN_CHI2_SEED=<k> shifts them all (to check the spread of p-values), and
// LANTERN_CHI2_DUMP=<dir> writes each test's observed and expected histograms there;
// LANTERN_CHI2_SAMPLE_DIVISOR=<d> draws 1/d of the samples (the sanitizer run).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "core/math.h"
#include "core/sampling.h"

namespace lt::test {

struct DirectionSample {
  Vec3 dir;        // unit direction
  double pdf = 0;  // the solid-angle pdf the sampler claims for it
};

// Draws whatever random numbers it needs from rng; returns false when the routine produces no
// direction (that sample then counts in the failure bin).
using DirectionSampler = std::function<bool(Sampler& rng, DirectionSample* out)>;
// Solid-angle density of a unit direction.
using DirectionPdf = std::function<double(const Vec3& dir)>;

// Number of chi-square tests in the whole native suite (an upper bound): each test runs at the
// Sidak-corrected level so that the family-wise significance is `significance`. Raise it when the
// suite grows past it (over-counting only makes each test slightly more lenient to noise).
constexpr int kChi2SuiteTests = 170;

struct Chi2Options {
  std::string name = "chi2";
  int theta_bins = 40;
  int phi_bins = 80;
  Vec3 pole{0, 0, 1};      // bins are laid out around this axis
  double theta_power = 1;  // >= 1; bins concentrate near the pole as it grows
  uint64_t samples = 1000000;
  bool keep_samples = false;  // ignore LANTERN_CHI2_SAMPLE_DIVISOR (the tester's own power checks)
  uint32_t seed = 1;
  double min_expected = 5;           // pool bins below this expected count
  double significance = 0.01;        // before the Sidak correction
  int test_count = kChi2SuiteTests;  // tests sharing the family-wise level (Sidak)
  double pdf_rel_tolerance = 1e-3;
  // Samples allowed to disagree with pdf() or to land where the expected count is zero, as a
  // fraction of all samples: float rounding puts the odd direction just across a shape's outline
  // or the horizon. A wrong pdf on any region of real measure exceeds this by orders.
  double boundary_fraction = 2e-5;
  double integral_tolerance = 1e-3;  // integral <= 1 + tolerance
  double expected_integral = -1;     // if >= 0: |integral - expected| <= tolerance as well
  int max_depth = 20;                // adaptive quadrature depth (1D halvings) per bin
};

struct Chi2Result {
  double chi2 = 0;
  int dof = 0;
  double p_value = 0;
  double alpha = 0;             // the corrected significance level the p-value is compared with
  double pdf_integral = 0;      // of the pdf adapter over the sphere
  uint64_t failures = 0;        // samples for which the sampler returned false
  uint64_t pdf_mismatches = 0;  // claimed pdf differs from pdf(dir) by more than the tolerance
  double max_pdf_rel_error = 0;
  uint64_t zero_pdf_samples = 0;  // samples landing where the expected count is exactly zero
  bool chi2_ok = false, integral_ok = false, pdf_ok = false;
  std::string summary;
  bool passed() const { return chi2_ok && integral_ok && pdf_ok; }
};

Chi2Result chi2_test(const DirectionSampler& sample, const DirectionPdf& pdf, const Chi2Options& options);

// P(X >= chi2) for a chi-square distribution with dof degrees of freedom.
double chi2_survival(double chi2, int dof);
// Per-test significance such that the family-wise level over `tests` tests is `alpha`.
double sidak_alpha(double alpha, int tests);

}  // namespace lt::test
