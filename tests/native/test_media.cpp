// Participating media: Henyey-Greenstein sampling, transmittance estimators and free-flight
// distance sampling against closed forms and quadrature, chromatic unbiasedness, the majorant grid
// and its DDA, extreme parameters and the ray-marching bias table (docs/volumes.md).
// Tolerances follow from the estimators' variance (5 standard errors) or from the suite's
// Sidak-corrected chi-square level; seeds are fixed.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <limits>
#include <memory>

#include "chi2.h"
#include "core/error.h"
#include "media/medium.h"
#include "media/volume_material.h"
#include "test_media_util.h"

namespace lt {
namespace {

using media_test::cumulative;
using media_test::Mean;
using media_test::pearson_1d;
using media_test::RefGrid;
using media_test::within_se;

constexpr VolumeEstimator kMarch = VolumeEstimator::RayMarching, kTrack = VolumeEstimator::Tracking;

Ray make_ray(const Vec3& o, const Vec3& d) {
  Ray r;
  r.o = o;
  r.d = d;
  return r;
}

// ---- grids -------------------------------------------------------------------------------------

// A Gaussian blob on 32^3 voxels, 1/16 world units per voxel, centred on the world origin.
RefGrid blob(double amplitude = 1, double sigma_voxels = 6) {
  RefGrid g;
  g.n[0] = g.n[1] = g.n[2] = 32;
  g.scale = 1.0 / 16;
  for (double& o : g.offset) o = -15.5 / 16;
  g.v.resize(32 * 32 * 32);
  for (int k = 0; k < 32; ++k)
    for (int j = 0; j < 32; ++j)
      for (int i = 0; i < 32; ++i) {
        double r2 = sqr(i - 15.5f) + sqr(j - 15.5f) + sqr(k - 15.5f);
        g.v[(k * 32 + j) * 32 + i] = float(amplitude * std::exp(-r2 / (2 * sigma_voxels * sigma_voxels)));
      }
  return g;
}

RefGrid constant_grid(int n, float value) {
  RefGrid g;
  g.n[0] = g.n[1] = g.n[2] = n;
  g.v.assign(size_t(n) * n * n, value);
  return g;
}

Medium make_medium(const RefGrid& g, const Spectrum& sigma_a, const Spectrum& sigma_s, float hg = 0,
                   int cell = Medium::kDefaultMajorantCell) {
  auto data = std::make_shared<const GridData>(GridData::from_dense(g.v, g.n[0], g.n[1], g.n[2]));
  return Medium::heterogeneous(data, sigma_a, sigma_s, hg, g.index_to_world(), cell);
}

// Optical depth per unit sigma_t (i.e. the density integral) at m + 1 nodes along [t0, t1].
std::vector<double> density_integral(const RefGrid& g, const Ray& r, double t0, double t1, int m) {
  double len = length(r.d);
  return cumulative(
      [&](double t) { return len * g.world_density(r.o.x + t * r.d.x, r.o.y + t * r.d.y, r.o.z + t * r.d.z); }, t0, t1,
      m);
}

// Expected counts for free-flight samples over nb equal bins of [t0, t1] plus a last bin for "no
// collision", given the density integral at m + 1 nodes (m a multiple of nb) and sigma_t per unit.
std::vector<double> free_flight_expected(const std::vector<double>& D, int nb, double sigma, double n) {
  int m = int(D.size()) - 1, per = m / nb;
  std::vector<double> e(nb + 1);
  for (int b = 0; b < nb; ++b) e[b] = n * (std::exp(-sigma * D[b * per]) - std::exp(-sigma * D[(b + 1) * per]));
  e[nb] = n * std::exp(-sigma * D[m]);
  return e;
}

int bin_of(float t, float t0, float t1, int nb) { return clamp(int((t - t0) / (t1 - t0) * nb), 0, nb - 1); }

// ---- phase function ---------------------------------------------------------------------------

// Chi-square test of a phase function's sampling (a single HG lobe or a mixture) seen from wo.
template <class P>
test::Chi2Result phase_chi2(const P& phase, const Vec3& wo, const test::Chi2Options& o) {
  return test::chi2_test(
      [&](Sampler& rng, test::DirectionSample* s) {
        float pdf;
        if (!phase.sample(wo, rng.next_2d(), &s->dir, &pdf)) return false;
        s->pdf = pdf;
        return true;
      },
      [&](const Vec3& wi) { return double(phase.eval(wo, wi)); }, o);
}

class PhaseChi2 : public ::testing::TestWithParam<float> {};

TEST_P(PhaseChi2, SamplingFollowsPdf) {
  const PhaseHG phase{GetParam()};
  const Vec3 wo = normalize(Vec3(0.3f, -0.5f, 0.8f));
  test::Chi2Options o;
  o.name = "phase_hg_g" + std::to_string(phase.g);
  // Resolve the peak: forward (wi = -wo) for g > 0, backward (wi = wo) for g < 0.
  o.pole = phase.g >= 0 ? -wo : wo;
  o.theta_power = std::abs(phase.g) > 0.9f ? 2 : 1;
  o.expected_integral = 1;
  o.seed = 77 + uint32_t(std::abs(phase.g) * 100);
  test::Chi2Result r = phase_chi2(phase, wo, o);
  EXPECT_TRUE(r.passed()) << r.summary;
  EXPECT_EQ(r.pdf_mismatches, 0u) << r.summary;  // pdf == value by construction
}

INSTANTIATE_TEST_SUITE_P(PhaseHG, PhaseChi2, ::testing::Values(-0.99f, -0.5f, 0.0f, 0.5f, 0.99f));

// Mixtures of HG lobes (volume shader mixes, media/phase.h): sampling follows the mixture's pdf.
struct MixtureCase {
  std::vector<float> g, w;
};

class PhaseMixtureChi2 : public ::testing::TestWithParam<MixtureCase> {};

TEST_P(PhaseMixtureChi2, SamplingFollowsPdf) {
  const MixtureCase& c = GetParam();
  const Phase phase = Phase::mixture(c.g.data(), c.w.data(), int(c.g.size()));
  ASSERT_EQ(phase.count, int(c.g.size()));
  const Vec3 wo = normalize(Vec3(-0.6f, 0.2f, 0.7f));
  test::Chi2Options o;
  o.name = "phase_mixture";
  for (size_t i = 0; i < c.g.size(); ++i) o.name += "_g" + std::to_string(c.g[i]) + "w" + std::to_string(c.w[i]);
  o.pole = -wo;  // the forward peak; backward lobes are resolved by the theta bins too
  o.theta_power = 2;
  o.expected_integral = 1;
  o.seed = 1234 + uint32_t(c.g.size());
  test::Chi2Result r = phase_chi2(phase, wo, o);
  EXPECT_TRUE(r.passed()) << r.summary;
  EXPECT_EQ(r.pdf_mismatches, 0u) << r.summary;  // pdf == eval of the whole mixture
}

INSTANTIATE_TEST_SUITE_P(Phase, PhaseMixtureChi2,
                         ::testing::Values(MixtureCase{{0.8f, -0.5f}, {0.3f, 0.7f}},
                                           MixtureCase{{0.95f, 0.0f, -0.9f}, {0.5f, 0.25f, 0.25f}},
                                           MixtureCase{{0.6f, 0.3f}, {1.0f, 3.0f}}));

TEST(Phase, MixtureWeightsMergeAndSingleLobe) {
  // Equal anisotropies merge (as Cycles merges identical HG closures); weights are normalised.
  const float g[] = {0.5f, 0.5f, -0.2f, 0.1f}, w[] = {1.0f, 1.0f, 2.0f, 0.0f};
  Phase p = Phase::mixture(g, w, 4);
  ASSERT_EQ(p.count, 2);
  EXPECT_FLOAT_EQ(p.g[0], 0.5f);
  EXPECT_FLOAT_EQ(p.weight[0], 0.5f);
  EXPECT_FLOAT_EQ(p.weight[1], 0.5f);
  const Vec3 wo = normalize(Vec3(0.1f, 0.2f, 0.9f)), wi = normalize(Vec3(-0.3f, 0.5f, -0.4f));
  EXPECT_NEAR(p.eval(wo, wi), 0.5f * hg_phase(dot(wo, wi), 0.5f) + 0.5f * hg_phase(dot(wo, wi), -0.2f), 1e-6f);
  // One lobe is exactly the HG phase function, also in sampling.
  Phase one = Phase::hg(0.7f);
  Sampler rng(media_test::seed(9), 0, 0);
  for (int i = 0; i < 100; ++i) {
    Vec2 u = rng.next_2d();
    Vec3 a, b;
    float pa, pb;
    ASSERT_TRUE(one.sample(wo, u, &a, &pa));
    ASSERT_TRUE(PhaseHG{0.7f}.sample(wo, u, &b, &pb));
    EXPECT_EQ(a.x, b.x);
    EXPECT_EQ(pa, pb);
  }
  const float bad_w[] = {-1.0f};
  EXPECT_THROW(Phase::mixture(g, bad_w, 1), InvalidArgument);
  const float zero_w[] = {0.0f, 0.0f};
  EXPECT_THROW(Phase::mixture(g, zero_w, 2), InvalidArgument);
}

TEST(PhaseHG, Normalisation) {
  // 2 pi * integral of p over cos in [-1, 1] by Simpson's rule; 2e6 intervals resolve even the
  // g = +-0.99 peaks (width ~ 1e-2 in cos).
  for (float g : {-0.99f, -0.5f, 0.0f, 0.3f, 0.5f, 0.99f}) {
    const int m = 2000000;
    double h = 2.0 / m, sum = 0;
    for (int k = 0; k < m; ++k) {
      double a = -1 + k * h;
      sum += h / 6 * (hg_phase(float(a), g) + 4 * hg_phase(float(a + h / 2), g) + hg_phase(float(a + h), g));
    }
    EXPECT_NEAR(2 * kPi * sum, 1.0, 2e-4) << "g " << g;
  }
}

TEST(PhaseHG, ForwardScatteringConvention) {
  // wo and wi both point away from the scattering point; light arriving from wi and leaving along
  // wo turns by angle theta with cos theta = -dot(wo, wi), and E[cos theta] = g.
  const Vec3 wo = normalize(Vec3(-0.2f, 0.9f, 0.4f));
  Sampler rng(media_test::seed(5), 0, 0);
  for (float g : {-0.7f, 0.0f, 0.5f, 0.9f}) {
    PhaseHG p{g};
    Mean m;
    for (int i = 0; i < 200000; ++i) {
      Vec3 wi;
      float pdf;
      ASSERT_TRUE(p.sample(wo, rng.next_2d(), &wi, &pdf));
      ASSERT_EQ(pdf, p.eval(wo, wi));
      m.add(-dot(wo, wi));
    }
    EXPECT_TRUE(within_se(m, g)) << "g " << g;
    if (g > 0) EXPECT_GT(p.eval(wo, -wo), p.eval(wo, wo));  // forward peak, as Cycles
    Vec3 a = normalize(Vec3(1, 2, 3)), b = normalize(Vec3(-2, 0.5f, 1));
    EXPECT_FLOAT_EQ(p.eval(a, b), p.eval(b, a));
  }
  EXPECT_NEAR(PhaseHG{0}.eval(wo, wo), kInv4Pi, 1e-7);
}

// ---- homogeneous media ------------------------------------------------------------------------

TEST(MediaHomogeneous, ClosedFormTransmittanceForEveryEstimator) {
  const Spectrum sa(0.1f, 0.4f, 2.0f), ss(0.5f, 0.2f, 1.0f);
  Medium m = Medium::homogeneous(sa, ss, 0.3f);
  ASSERT_TRUE(m.is_homogeneous());
  ASSERT_FALSE(m.empty());
  const Ray r = make_ray(Vec3(0.2f, -1, 3), Vec3(0, 2, 0));  // |d| = 2: distances are 2 (t1 - t0)
  for (VolumeEstimator e : {kMarch, kTrack}) {
    Sampler s(media_test::seed(1), 2, 3), copy = s;
    Spectrum T = m.transmittance(r, 0.25f, 1.5f, s, e, 0.01f);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(T[c], std::exp(-(sa[c] + ss[c]) * 2.5), 1e-6) << "channel " << c;
    EXPECT_EQ(s.next_1d(), copy.next_1d()) << "closed form must consume no random numbers";
    Spectrum Tinf = m.transmittance(r, 0, INFINITY, s, e, 0.01f);
    EXPECT_EQ(max_component(Tinf), 0.0f);
    EXPECT_EQ(m.transmittance(r, 1, 1, s, e, 0.01f).x, 1.0f);
  }
  // A channel without extinction passes even an infinite segment (no 0 * inf).
  Medium partial = Medium::homogeneous(Spectrum(0, 1, 1), Spectrum(0.0f), 0);
  Sampler s(media_test::seed(1), 0, 0);
  Spectrum T = partial.transmittance(r, 0, INFINITY, s, kTrack, 0);
  EXPECT_EQ(T.x, 1.0f);
  EXPECT_EQ(T.y, 0.0f);
}

TEST(MediaHomogeneous, DistancesFollowTruncatedExponential) {
  const float sigma_t = 1.3f, albedo = 0.7f;
  Medium m = Medium::homogeneous(Spectrum(sigma_t * (1 - albedo)), Spectrum(sigma_t * albedo), 0);
  const Ray r = make_ray(Vec3(0.0f), normalize(Vec3(1, 1, 0)));
  const float t0 = 0.5f, t1 = 2.0f;
  const int nb = 50, n = 400000;
  std::vector<double> obs(nb + 1, 0.0);
  Sampler s(media_test::seed(11), 0, 0);
  for (int i = 0; i < n; ++i) {
    MediumInteraction mi;
    if (m.sample_distance(r, t0, t1, s, kTrack, 0, &mi)) {
      ASSERT_TRUE(mi.t >= t0 && mi.t < t1) << mi.t;
      ASSERT_NEAR(mi.weight.x, albedo, 1e-6);  // grey: the weight is the albedo
      obs[bin_of(mi.t, t0, t1, nb)] += 1;
    } else {
      ASSERT_NEAR(mi.weight.x, 1.0f, 1e-6);
      obs[nb] += 1;
    }
  }
  std::vector<double> D(nb + 1);
  for (int b = 0; b <= nb; ++b) D[b] = (t1 - t0) * b / nb;
  media_test::Pearson p = pearson_1d(obs, free_flight_expected(D, nb, sigma_t, n));
  EXPECT_TRUE(p.ok()) << p.summary();
}

TEST(MediaHomogeneous, ChromaticEstimatorIsUnbiasedPerChannel) {
  const Spectrum sa(0.2f, 0.5f, 3.0f), ss(0.3f, 1.5f, 1.0f), st = sa + ss;
  Medium m = Medium::homogeneous(sa, ss, 0);
  const Ray r = make_ray(Vec3(1, 2, 3), Vec3(0, 0, -2));  // non-unit direction
  const float t0 = 0.3f, t1 = 1.5f, len = 2;
  const int nb = 4, n = 400000;
  Mean pass[3], scat[3][nb];
  Sampler s(media_test::seed(12), 0, 0);
  for (int i = 0; i < n; ++i) {
    MediumInteraction mi;
    bool hit = m.sample_distance(r, t0, t1, s, kTrack, 0, &mi);
    ASSERT_TRUE(is_finite(mi.weight));
    int b = hit ? bin_of(mi.t, t0, t1, nb) : -1;
    for (int c = 0; c < 3; ++c) {
      pass[c].add(hit ? 0 : mi.weight[c]);
      for (int k = 0; k < nb; ++k) scat[c][k].add(hit && b == k ? mi.weight[c] : 0);
    }
    if (hit) ASSERT_NEAR(length(mi.p - (r.o + r.d * mi.t)), 0, 1e-5);
  }
  for (int c = 0; c < 3; ++c) {
    EXPECT_TRUE(within_se(pass[c], std::exp(-st[c] * len * (t1 - t0)))) << "pass, channel " << c;
    for (int k = 0; k < nb; ++k) {
      double a = (t1 - t0) * k / nb * len, b = (t1 - t0) * (k + 1) / nb * len;
      double expect = ss[c] / st[c] * (std::exp(-st[c] * a) - std::exp(-st[c] * b));
      EXPECT_TRUE(within_se(scat[c][k], expect)) << "scatter bin " << k << ", channel " << c;
    }
  }
}

// ---- constant-density grid: the heterogeneous machinery on a homogeneous slab -----------------

TEST(MediaConstantGrid, TransmittanceOfEveryEstimatorIsClosedForm) {
  // 12^3 voxels of density 1 with one voxel of 3 in a corner: the rays run where the interpolated
  // density is exactly 1, through cells whose majorant is 1 (tight: ratio tracking's weights are 0
  // or 1) and, for the second ray, partly 3 (loose: fractional weights).
  RefGrid g = constant_grid(12, 1.0f);
  g.v[0] = 3.0f;
  const float sigma_t = 0.9f;
  Medium m = make_medium(g, Spectrum(sigma_t * 0.4f), Spectrum(sigma_t * 0.6f), 0, 4);
  for (float yz : {6.5f, 1.5f}) {
    const Ray r = make_ray(Vec3(-3, yz, yz), Vec3(1, 0, 0));
    const float t0 = 3.5f, t1 = 13.75f;  // x from 0.5 to 10.75, inside the voxel centres 0..11
    const double expect = std::exp(-sigma_t * (t1 - t0));
    Sampler s(media_test::seed(21), 0, 0);
    for (float step : {0.3f, 1.0f, 2.5f}) {
      Spectrum T = m.transmittance(r, t0, t1, s, kMarch, step);
      EXPECT_NEAR(T.x, expect, 2e-6 * expect) << "marching step " << step;
    }
    Mean mt;
    for (int i = 0; i < 200000; ++i) mt.add(m.transmittance(r, t0, t1, s, kTrack, 0).x);
    EXPECT_TRUE(within_se(mt, expect)) << "ratio tracking, y = z = " << yz;
  }
}

TEST(MediaConstantGrid, DistancesFollowExponentialForTrackingAndMarching) {
  RefGrid g = constant_grid(12, 1.0f);
  g.v[0] = 3.0f;
  const float sigma_t = 0.35f;
  Medium m = make_medium(g, Spectrum(0.0f), Spectrum(sigma_t), 0, 4);
  const Ray r = make_ray(Vec3(-3, 1.5f, 1.5f), Vec3(1, 0, 0));
  const float t0 = 3.5f, t1 = 13.75f;
  const int nb = 40, n = 200000;
  std::vector<double> D(nb + 1);
  for (int b = 0; b <= nb; ++b) D[b] = (t1 - t0) * b / nb;
  std::vector<double> expected = free_flight_expected(D, nb, sigma_t, n);
  for (VolumeEstimator e : {kTrack, kMarch}) {
    std::vector<double> obs(nb + 1, 0.0);
    Sampler s(media_test::seed(e == kTrack ? 31 : 32), 0, 0);
    for (int i = 0; i < n; ++i) {
      MediumInteraction mi;
      if (m.sample_distance(r, t0, t1, s, e, 0.7f, &mi)) {
        ASSERT_TRUE(mi.t >= t0 && mi.t <= t1);
        ASSERT_NEAR(mi.weight.x, 1.0f, 1e-5);  // albedo 1
        obs[bin_of(mi.t, t0, t1, nb)] += 1;
      } else {
        obs[nb] += 1;
      }
    }
    media_test::Pearson p = pearson_1d(obs, expected);
    EXPECT_TRUE(p.ok()) << (e == kTrack ? "delta tracking: " : "ray marching: ") << p.summary();
  }
}

// ---- heterogeneous: Gaussian blob against quadrature -------------------------------------------

std::vector<Ray> blob_rays() {
  return {make_ray(Vec3(-2, 0, 0), Vec3(1, 0, 0)), make_ray(Vec3(-2, 0.3f, -0.2f), Vec3(1, 0, 0)),
          make_ray(Vec3(0.6f, -2, 0.5f), Vec3(0, 1, 0)),
          make_ray(Vec3(-1.5f, -0.9f, 0.9f), normalize(Vec3(1, 0.4f, -0.5f))),
          make_ray(Vec3(0.1f, 0.2f, 2), Vec3(0, 0, -3))};  // non-unit direction
}

TEST(MediaHeterogeneous, RatioTrackingMatchesQuadrature) {
  RefGrid g = blob();
  const float sigma_t = 3.0f;
  Medium m = make_medium(g, Spectrum(1.0f), Spectrum(2.0f));
  Sampler s(media_test::seed(41), 0, 0);
  int k = 0;
  for (const Ray& r : blob_rays()) {
    const float t0 = 0.2f / length(r.d), t1 = 3.6f / length(r.d);
    std::vector<double> D = density_integral(g, r, t0, t1, 8000);
    const double expect = std::exp(-sigma_t * D.back());
    Mean mt;
    for (int i = 0; i < 100000; ++i) {
      Spectrum T = m.transmittance(r, t0, t1, s, kTrack, 0);
      ASSERT_TRUE(T.x >= 0 && std::isfinite(T.x));
      mt.add(T.x);
    }
    EXPECT_TRUE(within_se(mt, expect)) << "ray " << k << " (tau " << sigma_t * D.back() << ")";
    ++k;
  }
}

// Residual ratio tracking (the Tracking transmittance) and plain ratio tracking (the same with the
// control dropped) against quadrature on a denser blob cut to zero below 1e-3 of its peak (empty
// cells at the corners), through the dense centre, thin edges, empty cells and along the grid's
// boundary; then the variance on the dense ray, which the control must reduce.
TEST(MediaHeterogeneous, ResidualRatioTrackingMatchesQuadratureWithLessVariance) {
  RefGrid g = blob(4, 5);
  for (float& v : g.v)
    if (v < 4e-3f) v = 0;
  const float sigma_t = 2.0f;
  Medium m = make_medium(g, Spectrum(0.5f), Spectrum(1.5f)), plain = m;
  plain.drop_control();
  const float lo = -16.5f / 16;  // the domain's face: one voxel beyond the first voxel centre
  const std::vector<Ray> rays = {
      make_ray(Vec3(-2, 0.01f, -0.02f), Vec3(1, 0, 0)),                      // dense (first: the variance ray)
      make_ray(Vec3(-2, 0.6f, 0.3f), Vec3(1, 0, 0)),                         // thin
      make_ray(Vec3(-1.5f, -0.9f, 0.9f), normalize(Vec3(1, 0.9f, -0.95f))),  // empty corner cells
      make_ray(Vec3(-2, lo + 1e-3f, 0.1f), Vec3(1, 0, 0)),                   // grazing the boundary
      make_ray(Vec3(0.2f, -0.1f, 2), Vec3(0.01f, 0.02f, -3))};               // non-unit direction
  Sampler s(media_test::seed(44), 0, 0);
  double var_new = 0, var_plain = 0;
  for (size_t k = 0; k < rays.size(); ++k) {
    const Ray& r = rays[k];
    const float t0 = 0.1f / length(r.d), t1 = 3.9f / length(r.d);
    std::vector<double> D = density_integral(g, r, t0, t1, 8000);
    const double expect = std::exp(-sigma_t * D.back());
    for (Medium* med : {&m, &plain}) {
      Mean mt;
      for (int i = 0; i < 100000; ++i) {
        Spectrum T = med->transmittance(r, t0, t1, s, kTrack, 0);
        ASSERT_TRUE(T.x >= 0 && std::isfinite(T.x));
        mt.add(T.x);
      }
      const char* name = med == &m ? "residual ratio tracking" : "ratio tracking";
      EXPECT_TRUE(within_se(mt, expect)) << name << ", ray " << k << " (tau " << sigma_t * D.back() << ")";
      if (k == 0) (med == &m ? var_new : var_plain) = sqr(mt.se()) * mt.n;
    }
  }
  std::printf("[ media    ] dense ray variance: residual ratio tracking %.3g, ratio tracking %.3g\n", var_new,
              var_plain);
  EXPECT_LT(var_new, 0.5 * var_plain);
}

TEST(MediaHeterogeneous, DeltaTrackingDistancesFollowFreeFlightDistribution) {
  RefGrid g = blob();
  const float sigma_t = 3.0f;
  Medium m = make_medium(g, Spectrum(0.6f), Spectrum(2.4f));
  const int nb = 40, n = 200000;
  int k = 0;
  for (const Ray& r : blob_rays()) {
    if (k == 1 || k == 2) {  // three rays are enough; keep the runtime down
      ++k;
      continue;
    }
    const float t0 = 0.2f / length(r.d), t1 = 3.6f / length(r.d);
    std::vector<double> D = density_integral(g, r, t0, t1, nb * 200);
    std::vector<double> obs(nb + 1, 0.0);
    Sampler s(media_test::seed(42 + k), 0, 0);
    for (int i = 0; i < n; ++i) {
      MediumInteraction mi;
      if (m.sample_distance(r, t0, t1, s, kTrack, 0, &mi)) {
        ASSERT_NEAR(mi.weight.x, 0.8f, 1e-5);
        ASSERT_NEAR(mi.sigma_s.x, 2.4 * g.world_density(mi.p.x, mi.p.y, mi.p.z), 1e-4);
        obs[bin_of(mi.t, t0, t1, nb)] += 1;
      } else {
        ASSERT_NEAR(mi.weight.x, 1.0f, 1e-6);
        obs[nb] += 1;
      }
    }
    media_test::Pearson p = pearson_1d(obs, free_flight_expected(D, nb, sigma_t, n));
    EXPECT_TRUE(p.ok()) << "ray " << k << ": " << p.summary();
    ++k;
  }
}

// The test's own model of the marched field: midpoint density per step, steps from the entry
// into the grid's domain, the last step shortened. Returns the density integral at t.
struct MarchedModel {
  std::vector<double> edges, rho;  // step boundaries (t) and midpoint densities
  double integral(double t) const {
    double D = 0;
    for (size_t k = 0; k + 1 < edges.size(); ++k) {
      if (t <= edges[k]) break;
      D += rho[k] * (std::min(t, edges[k + 1]) - edges[k]);
    }
    return D;
  }
};
MarchedModel marched_model(const RefGrid& g, const Medium& m, const Ray& r, float t0, float t1, float step) {
  MarchedModel mm;
  float a = t0, b = t1;
  if (!m.clip(r, &a, &b)) return mm;
  double h = step / length(r.d);
  long n = long(std::ceil((b - a) / h));
  for (long k = 0; k <= n; ++k) mm.edges.push_back(k == n ? b : a + float(k) * float(h));
  for (long k = 0; k < n; ++k) {
    double mid = 0.5 * (mm.edges[k] + mm.edges[k + 1]);
    mm.rho.push_back(length(r.d) * g.world_density(r.o.x + mid * r.d.x, r.o.y + mid * r.d.y, r.o.z + mid * r.d.z));
  }
  return mm;
}

TEST(MediaHeterogeneous, RayMarchingRevertsExactlyToSampledOpticalDepth) {
  // Samples of the marching distance sampler follow the marched (piecewise-constant) field's
  // free-flight distribution exactly: the linear revert inside the last step is exact. A coarse
  // step (1.5 voxels) makes the marched field clearly different from the true one.
  RefGrid g = blob();
  const float sigma_t = 3.0f, step = 1.5f / 16;
  Medium m = make_medium(g, Spectrum(0.0f), Spectrum(sigma_t));
  const Ray r = make_ray(Vec3(-1.5f, -0.9f, 0.9f), normalize(Vec3(1, 0.4f, -0.5f)));
  const float t0 = 0.2f, t1 = 3.6f;
  const int nb = 60, n = 200000;
  MarchedModel mm = marched_model(g, m, r, t0, t1, step);
  std::vector<double> D(nb + 1);
  for (int b = 0; b <= nb; ++b) D[b] = mm.integral(t0 + (t1 - t0) * double(b) / nb);
  // Test the transmittance against the same model first (deterministic).
  Sampler s(media_test::seed(51), 0, 0);
  EXPECT_NEAR(m.transmittance(r, t0, t1, s, kMarch, step).x, std::exp(-sigma_t * D[nb]), 2e-5);
  std::vector<double> obs(nb + 1, 0.0);
  for (int i = 0; i < n; ++i) {
    MediumInteraction mi;
    if (m.sample_distance(r, t0, t1, s, kMarch, step, &mi))
      obs[bin_of(mi.t, t0, t1, nb)] += 1;
    else
      obs[nb] += 1;
  }
  media_test::Pearson p = pearson_1d(obs, free_flight_expected(D, nb, sigma_t, n));
  EXPECT_TRUE(p.ok()) << p.summary();
}

TEST(MediaHeterogeneous, RayMarchingBiasShrinksWithStep) {
  // |T_march - T_true| over 64 random rays through a smooth and a sharp Gaussian blob (standard
  // deviation 6 and 1.5 voxels), T_true by quadrature; steps in voxels. The table goes to
  // docs/volumes.md.
  const float voxel = 1.0f / 16;
  const float steps[] = {2.0f, 1.0f, 0.5f, 0.25f};
  std::string table =
      "ray-marching bias, midpoint rule, 64 random rays per blob:\n"
      "  blob sigma  sigma_t  step/voxel  mean|dT|   max|dT|    mean|dT|/T\n";
  for (double width : {6.0, 1.5}) {
    RefGrid g = blob(1, width);
    const float sigma_t = width > 3 ? 3.0f : 30.0f;  // optical depths through the centre ~2.8 both
    Medium m = make_medium(g, Spectrum(sigma_t / 3), Spectrum(sigma_t * 2 / 3));
    Sampler rng(media_test::seed(61), 0, 0);
    std::vector<Ray> rays;
    std::vector<double> truth;
    for (int i = 0; i < 64; ++i) {
      Vec3 o = sample_uniform_sphere(rng.next_2d()) * 2.0f;
      Vec3 target = sample_uniform_sphere(rng.next_2d()) * (float(width / 10) * rng.next_1d());
      Ray r = make_ray(o, normalize(target - o));
      rays.push_back(r);
      truth.push_back(std::exp(-sigma_t * density_integral(g, r, 0, 4, 8000).back()));
    }
    double prev = INFINITY;
    for (float st : steps) {
      double sum = 0, mx = 0, rel = 0;
      for (size_t i = 0; i < rays.size(); ++i) {
        Sampler s(media_test::seed(0), 0, 0);
        double T = m.transmittance(rays[i], 0, 4, s, kMarch, st * voxel).x;
        double e = std::abs(T - truth[i]);
        sum += e;
        mx = std::max(mx, e);
        rel += e / truth[i];
      }
      double mean = sum / rays.size();
      char line[160];
      std::snprintf(line, sizeof line, "  %6.1f vx  %7.1f  %8.2f    %.2e   %.2e   %.2e\n", width, sigma_t, st, mean, mx,
                    rel / rays.size());
      table += line;
      EXPECT_LT(mean, prev) << "bias must shrink with the step (blob " << width << ")";
      prev = mean;
    }
  }
  std::printf("[ media    ] %s", table.c_str());
  RecordProperty("ray_marching_bias", table);
}

// ---- chromatic heterogeneous media ------------------------------------------------------------

TEST(MediaChromatic, TrackingIsUnbiasedPerChannel) {
  RefGrid g = blob();
  const Spectrum sa(0.2f, 1.5f, 6.0f), ss(0.8f, 1.5f, 2.0f), st = sa + ss;  // sigma_t 1, 3, 8
  Medium m = make_medium(g, sa, ss);
  const Ray r = make_ray(Vec3(-1.5f, -0.3f, 0.2f), normalize(Vec3(1, 0.2f, -0.1f)));
  const float t0 = 0.1f, t1 = 3.2f;
  const int nb = 4, n = 300000, M = nb * 2000;
  std::vector<double> D = density_integral(g, r, t0, t1, M);
  Sampler s(media_test::seed(71), 0, 0);
  Mean tr[3], pass[3], scat[3][nb];
  for (int i = 0; i < n; ++i) {
    Spectrum T = m.transmittance(r, t0, t1, s, kTrack, 0);
    MediumInteraction mi;
    bool hit = m.sample_distance(r, t0, t1, s, kTrack, 0, &mi);
    ASSERT_TRUE(is_finite(T) && is_finite(mi.weight));
    int b = hit ? bin_of(mi.t, t0, t1, nb) : -1;
    for (int c = 0; c < 3; ++c) {
      tr[c].add(T[c]);
      pass[c].add(hit ? 0 : mi.weight[c]);
      for (int k = 0; k < nb; ++k) scat[c][k].add(b == k ? mi.weight[c] : 0);
    }
  }
  for (int c = 0; c < 3; ++c) {
    const double T = std::exp(-st[c] * D.back());
    EXPECT_TRUE(within_se(tr[c], T)) << "ratio tracking, channel " << c;
    EXPECT_TRUE(within_se(pass[c], T)) << "spectral tracking pass-through, channel " << c;
    for (int k = 0; k < nb; ++k) {
      // integral over the bin of sigma_s(t) T(t) dt = albedo (T(a) - T(b)) (constant albedo).
      int a = k * M / nb, b = (k + 1) * M / nb;
      double expect = ss[c] / st[c] * (std::exp(-st[c] * D[a]) - std::exp(-st[c] * D[b]));
      EXPECT_TRUE(within_se(scat[c][k], expect)) << "spectral tracking bin " << k << ", channel " << c;
    }
  }
}

TEST(MediaChromatic, RayMarchingIsUnbiasedForTheMarchedField) {
  // Per channel, the hero-channel marching sampler's expectations equal the marched field's
  // transmittance (pass-through) and its scattered fraction albedo (1 - T) (real collisions).
  RefGrid g = blob();
  const Spectrum sa(0.2f, 1.5f, 6.0f), ss(0.8f, 1.5f, 2.0f), st = sa + ss;
  Medium m = make_medium(g, sa, ss);
  const Ray r = make_ray(Vec3(-1.5f, -0.3f, 0.2f), normalize(Vec3(1, 0.2f, -0.1f)));
  const float t0 = 0.1f, t1 = 3.2f, step = 1.0f / 16;
  Sampler s(media_test::seed(72), 0, 0);
  const Spectrum T = m.transmittance(r, t0, t1, s, kMarch, step);
  MarchedModel mm = marched_model(g, m, r, t0, t1, step);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(T[c], std::exp(-st[c] * mm.integral(t1)), 3e-5) << "channel " << c;
  Mean pass[3], scat[3];
  for (int i = 0; i < 300000; ++i) {
    MediumInteraction mi;
    bool hit = m.sample_distance(r, t0, t1, s, kMarch, step, &mi);
    for (int c = 0; c < 3; ++c) {
      pass[c].add(hit ? 0 : mi.weight[c]);
      scat[c].add(hit ? mi.weight[c] : 0);
    }
  }
  for (int c = 0; c < 3; ++c) {
    EXPECT_TRUE(within_se(pass[c], T[c])) << "channel " << c;
    EXPECT_TRUE(within_se(scat[c], ss[c] / st[c] * (1 - T[c]))) << "channel " << c;
  }
}

// ---- majorant grid and DDA -------------------------------------------------------------------

TEST(MediaMajorant, BoundsTheInterpolatedDensityAndIsTight) {
  // Sparse spikes on noise: a cell's bounds must cover the interpolation footprint one voxel past
  // the cell, and equal the largest and the smallest voxel in it.
  RefGrid g;
  g.n[0] = 21;
  g.n[1] = 17;
  g.n[2] = 9;
  g.v.resize(21 * 17 * 9);
  Sampler rng(media_test::seed(81), 0, 0);
  for (float& v : g.v) v = rng.next_1d() < 0.03f ? 50 * rng.next_1d() : 0.05f + 0.1f * rng.next_1d();
  int lower_bounded = 0;  // cells with a positive lower bound (the interior ones)
  for (int cell : {1, 4, 8}) {
    Medium m = make_medium(g, Spectrum(1.0f), Spectrum(0.0f), 0, cell);
    const MajorantGrid& maj = m.majorant_grid();
    ASSERT_TRUE(maj.valid());
    // Every cell equals the maximum over its footprint (tightness) ...
    for (int z = 0; z < maj.resolution(2); ++z)
      for (int y = 0; y < maj.resolution(1); ++y)
        for (int x = 0; x < maj.resolution(0); ++x) {
          int v0[3], v1[3];
          const int c[3] = {x, y, z};
          for (int a = 0; a < 3; ++a) maj.footprint(a, c[a], &v0[a], &v1[a]);
          // The lower bound: the smallest voxel of the footprint within the domain (0 outside
          // the array), clamped >= 0.
          double mx = 0, mn = INFINITY;
          for (int k = v0[2]; k <= std::min(v1[2], maj.hi()[2]); ++k)
            for (int j = v0[1]; j <= std::min(v1[1], maj.hi()[1]); ++j)
              for (int i = v0[0]; i <= std::min(v1[0], maj.hi()[0]); ++i) {
                mx = std::max(mx, g.at(i, j, k));
                mn = std::min(mn, g.at(i, j, k));
              }
          ASSERT_FLOAT_EQ(maj.cell_value(x, y, z), float(mx)) << "cell " << x << " " << y << " " << z;
          ASSERT_FLOAT_EQ(maj.cell_min(x, y, z), float(std::max(0.0, mn))) << "cell " << x << " " << y << " " << z;
          lower_bounded += maj.cell_min(x, y, z) > 0;
        }
    // ... and bounds the interpolated density from above and below at random points of the domain.
    for (int i = 0; i < 200000; ++i) {
      Vec3 p;
      for (int a = 0; a < 3; ++a) p[a] = maj.lo()[a] + rng.next_1d() * (maj.hi()[a] - maj.lo()[a]);
      MajorantGrid::Iterator it = maj.traverse(p, Vec3(1, 0, 0), 0, 1e-6f);
      MajorantSegment seg;
      ASSERT_TRUE(it.next(&seg));
      float d = g.index_density(p.x, p.y, p.z);
      ASSERT_LE(d, maj.value_at(p) * (1 + 1e-6f)) << "cell size " << cell;
      ASSERT_EQ(seg.value, maj.value_at(p));
      ASSERT_GE(d, seg.min * (1 - 1e-6f)) << "cell size " << cell;
    }
  }
  EXPECT_GT(lower_bounded, 1000);  // the lower bounds are not all 0
}

TEST(MediaMajorant, DdaVisitsCellsInOrderAndCoversTheSegment) {
  const int lo[3] = {-1, -1, -1}, hi[3] = {20, 17, 9};
  MajorantGrid grid(lo, hi, 4);
  for (int z = 0; z < grid.resolution(2); ++z)
    for (int y = 0; y < grid.resolution(1); ++y)
      for (int x = 0; x < grid.resolution(0); ++x) grid.raise_cell(x, y, z, float(1 + x + 10 * y + 100 * z));
  Sampler rng(media_test::seed(82), 0, 0);
  int crossed = 0;
  for (int i = 0; i < 20000; ++i) {
    Vec3 o = Vec3(-10, -10, -10) + Vec3(rng.next_1d(), rng.next_1d(), rng.next_1d()) * 40.0f;
    Vec3 d = sample_uniform_sphere(rng.next_2d());
    if (i % 10 == 0) d[i / 10 % 3] = 0;  // axis-parallel directions
    if (i % 30 == 0) d[(i / 30 + 1) % 3] = 0;
    float t0 = 0, t1 = 60, a = t0, b = t1;
    bool hits = grid.clip(o, d, &a, &b);
    MajorantGrid::Iterator it = grid.traverse(o, d, t0, t1);
    MajorantSegment seg;
    float expect_start = a, covered = 0;
    int count = 0;
    while (it.next(&seg)) {
      ASSERT_TRUE(hits);
      ASSERT_NEAR(seg.t0, expect_start, 1e-4f);
      ASSERT_GE(seg.t1, seg.t0);
      if (seg.t1 - seg.t0 > 1e-3f) {
        Vec3 mid = o + d * (0.5f * (seg.t0 + seg.t1));
        ASSERT_EQ(seg.value, grid.value_at(mid)) << "ray " << i << " segment " << count;
      }
      covered += seg.t1 - seg.t0;
      expect_start = seg.t1;
      ++count;
    }
    if (hits) {
      EXPECT_NEAR(covered, b - a, 1e-3f) << "ray " << i;
      crossed += count;
    } else {
      EXPECT_EQ(count, 0);
    }
  }
  EXPECT_GT(crossed, 5000);  // the rays do cross many cells
}

TEST(MediaMajorant, WideSparseBoundsCoarsenTheCellsInsteadOfFailing) {
  // Two voxels 4000 apart (a sparse VDB, or one changed coordinate in fuzz_vdb's inputs): at 4
  // voxels per cell that is 10^9 cells (8 GB); the cells double until at most kMaxCells remain.
  const int lo[3] = {-1, -1, -1}, hi[3] = {4001, 4001, 4001};
  MajorantGrid grid(lo, hi, 4);
  EXPECT_EQ(grid.cell_size(), 16);
  int64_t cells = 1;
  for (int a = 0; a < 3; ++a) cells *= grid.resolution(a);
  EXPECT_LE(cells, MajorantGrid::kMaxCells);
  EXPECT_GT(cells * 8, MajorantGrid::kMaxCells);  // and no coarser than needed
  const int a0[3] = {0, 0, 0}, a1[3] = {4000, 4000, 4000};
  grid.add_voxels(a0, a0, 3.0f);
  grid.add_voxels(a1, a1, 5.0f);
  EXPECT_EQ(grid.value_at(Vec3(0, 0, 0)), 3.0f);
  EXPECT_EQ(grid.value_at(Vec3(4000, 4000, 4000)), 5.0f);
  EXPECT_EQ(grid.value_at(Vec3(2000, 2000, 2000)), 0.0f);
  // Bounds that fit keep the requested cell.
  const int small[3] = {100, 100, 100};
  EXPECT_EQ(MajorantGrid(lo, small, 4).cell_size(), 4);
}

// ---- extremes and bounded work ------------------------------------------------------------------

TEST(MediaExtremes, FiniteOutputsAndBoundedWork) {
  const RefGrid base = blob();
  const Vec3 dirs[] = {normalize(Vec3(1, 0.1f, 0.05f)), normalize(Vec3(-0.3f, 1, 0.2f))};
  Sampler s(media_test::seed(91), 0, 0);
  long calls = 0, max_steps = 0;
  auto t_start = std::chrono::steady_clock::now();
  for (double density : {1e-6, 1.0, 1e6})
    for (float albedo : {0.0f, 1.0f})
      for (double scale : {1e-3, 1.0, 1e4}) {
        RefGrid g = base;
        for (float& v : g.v) v = float(v * density);
        g.scale *= scale;
        for (double& o : g.offset) o *= scale;
        const Spectrum sa(1 - albedo), ss(albedo);
        std::vector<Medium> media = {make_medium(g, sa, ss),
                                     Medium::homogeneous(sa * float(density), ss * float(density), 0),
                                     make_medium(g, Spectrum(1 - albedo, 0.5f, 0), Spectrum(albedo, 0.5f, 2))};
        for (const Medium& m : media)
          for (const Vec3& d : dirs)
            for (VolumeEstimator e : {kMarch, kTrack})
              for (float t1 : {float(3 * scale), INFINITY})
                for (int rep = 0; rep < 4; ++rep) {
                  const Ray r = make_ray(-d * float(1.5 * scale), d);
                  Spectrum T = m.transmittance(r, 0, t1, s, e, float(scale / 16));
                  ASSERT_TRUE(is_finite(T) && T.x >= 0 && T.y >= 0 && T.z >= 0)
                      << "density " << density << " scale " << scale;
                  MediumInteraction mi;
                  bool hit = m.sample_distance(r, 0, t1, s, e, float(scale / 16), &mi);
                  ASSERT_TRUE(is_finite(mi.weight) && mi.weight.x >= 0 && mi.weight.y >= 0 && mi.weight.z >= 0)
                      << "density " << density << " scale " << scale << " albedo " << albedo;
                  if (hit) ASSERT_TRUE(is_finite(mi.p) && std::isfinite(mi.t) && is_finite(mi.sigma_s));
                  if (albedo == 0 && hit && m.sigma_s_unit().y == 0) ASSERT_TRUE(is_black(mi.weight));
                  ASSERT_LE(mi.steps, std::max(Medium::kMaxTrackingSteps, Medium::kMaxMarchingSteps) + 1);
                  max_steps = std::max<long>(max_steps, mi.steps);
                  calls += 2;
                }
      }
  for (float g : {-0.99f, 0.0f, 0.99f}) {
    PhaseHG p{g};
    for (int i = 0; i < 10000; ++i) {
      Vec3 wo = sample_uniform_sphere(s.next_2d()), wi;
      float pdf;
      ASSERT_TRUE(p.sample(wo, s.next_2d(), &wi, &pdf));
      ASSERT_TRUE(is_finite(wi) && std::isfinite(pdf) && pdf > 0) << "g " << g;
    }
  }
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  std::printf("[ media    ] extremes: %ld calls in %.2f s, max steps per call %ld\n", calls, secs, max_steps);
}

TEST(MediaExtremes, TrackingStepCapTerminatesAndIsCounted) {
  // A loose majorant over a huge optical depth: one voxel of 1e9 in every cell's footprint, the
  // ray where the density is ~1e-3: ratio tracking would need ~1e9 steps.
  RefGrid g = constant_grid(16, 1e-3f);
  for (int k = 0; k < 16; k += 4)
    for (int j = 0; j < 16; j += 4)
      for (int i = 0; i < 16; i += 4) g.v[(k * 16 + j) * 16 + i] = 1e9f;
  Medium m = make_medium(g, Spectrum(0.5f), Spectrum(0.5f), 0, 4);
  const Ray r = make_ray(Vec3(-1, 2.5f, 2.5f), Vec3(1, 0, 0));
  Sampler s(media_test::seed(92), 0, 0);
  auto t_start = std::chrono::steady_clock::now();
  Spectrum T = m.transmittance(r, 0, 20, s, kTrack, 0);
  EXPECT_EQ(max_component(T), 0.0f);
  EXPECT_EQ(m.capped_calls(), 1u);
  MediumInteraction mi;
  EXPECT_TRUE(m.sample_distance(r, 0, 20, s, kTrack, 0, &mi));
  EXPECT_EQ(mi.steps, Medium::kMaxTrackingSteps + 1);
  EXPECT_TRUE(is_finite(mi.weight));
  EXPECT_EQ(m.capped_calls(), 2u);
  // Ray marching with a step that would need ~3e6 steps takes at most kMaxMarchingSteps (the step
  // grows) and stays accurate on the smooth blob.
  RefGrid b = blob();
  Medium mb = make_medium(b, Spectrum(1.0f), Spectrum(2.0f));
  const Ray rb = make_ray(Vec3(-2, 0.3f, -0.2f), Vec3(1, 0, 0));
  MediumInteraction mm;
  mb.sample_distance(rb, 0, 4, s, kMarch, 1e-6f, &mm);
  EXPECT_LE(mm.steps, Medium::kMaxMarchingSteps);
  const double truth = std::exp(-3 * density_integral(b, rb, 0, 4, 8000).back());
  EXPECT_NEAR(mb.transmittance(rb, 0, 4, s, kMarch, 1e-6f).x, truth, 1e-5);
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  EXPECT_LT(secs, 2.0);
}

// ---- construction, queries, transforms ------------------------------------------------------------

TEST(MediaGrid, ValidationEmptinessBoundsAndTransforms) {
  EXPECT_THROW(GridData::from_dense({1, 2, 3}, 2, 2, 2), InvalidArgument);
  EXPECT_THROW(GridData::from_dense({}, 0, 1, 1), InvalidArgument);
  EXPECT_THROW(GridData::from_dense({1, NAN}, 2, 1, 1), InvalidArgument);
  EXPECT_THROW(Medium::heterogeneous(nullptr, Spectrum(1.0f), Spectrum(1.0f), 0), InvalidArgument);
  EXPECT_THROW(Medium::homogeneous(Spectrum(-1.0f), Spectrum(1.0f), 0), InvalidArgument);

  auto zeros = std::make_shared<const GridData>(GridData::from_dense(std::vector<float>(8, 0.0f), 2, 2, 2));
  EXPECT_TRUE(zeros->empty());
  Medium empty = Medium::heterogeneous(zeros, Spectrum(1.0f), Spectrum(1.0f), 0);
  EXPECT_TRUE(empty.empty());
  Sampler s(media_test::seed(93), 0, 0);
  const Ray r = make_ray(Vec3(-1, 0.5f, 0.5f), Vec3(1, 0, 0));
  EXPECT_EQ(empty.transmittance(r, 0, 10, s, kTrack, 0).x, 1.0f);
  EXPECT_TRUE(Medium().empty());
  EXPECT_TRUE(Medium::homogeneous(Spectrum(0.0f), Spectrum(0.0f), 0).empty());

  // Non-trivial transforms: index -> object scales by 2 and shifts; object -> world rotates 90
  // degrees about z and shifts. The test maps world points back by hand.
  std::vector<float> v(4 * 5 * 6);
  for (size_t i = 0; i < v.size(); ++i) v[i] = float(1 + i % 7);
  Transform i2o;
  i2o.m[0] = i2o.m[5] = i2o.m[10] = 2;
  i2o.m[3] = 1;
  i2o.m[7] = -1;
  i2o.m[11] = 3;
  Transform o2w;  // (x, y, z) -> (-y, x, z) + (10, 0, 0)
  o2w.m[0] = 0;
  o2w.m[1] = -1;
  o2w.m[4] = 1;
  o2w.m[5] = 0;
  o2w.m[3] = 10;
  auto grid = std::make_shared<const GridData>(GridData::from_dense(v, 4, 5, 6, i2o));
  Medium m = Medium::heterogeneous(grid, Spectrum(1.0f), Spectrum(0.0f), 0, o2w);
  RefGrid ref;
  ref.v = v;
  ref.n[0] = 4;
  ref.n[1] = 5;
  ref.n[2] = 6;
  for (int i = 0; i < 1000; ++i) {
    Vec3 w = Vec3(0, -4, 0) + Vec3(s.next_1d() * 16, s.next_1d() * 16, s.next_1d() * 20);
    Vec3 obj(w.y, -(w.x - 10), w.z);  // inverse of o2w
    Vec3 idx = (obj - Vec3(1, -1, 3)) / 2;
    EXPECT_NEAR(m.density(w), ref.index_density(idx.x, idx.y, idx.z), 1e-4) << i;
  }
  EXPECT_NEAR(m.voxel_size(), 2.0f, 1e-6);
  Vec3 lo, hi;
  ASSERT_TRUE(m.bounds(&lo, &hi));
  // Index domain [-1, 4] x [-1, 5] x [-1, 6] -> object [-1, 9] x [-3, 9] x [1, 15] -> world.
  EXPECT_NEAR(lo.x, 1, 1e-4);
  EXPECT_NEAR(hi.x, 13, 1e-4);
  EXPECT_NEAR(lo.y, -1, 1e-4);
  EXPECT_NEAR(hi.y, 9, 1e-4);
  EXPECT_NEAR(lo.z, 1, 1e-4);
  EXPECT_NEAR(hi.z, 15, 1e-4);
  EXPECT_FALSE(Medium::homogeneous(Spectrum(1.0f), Spectrum(0.0f), 0).bounds(&lo, &hi));
  float t0 = -100, t1 = 100;
  EXPECT_TRUE(m.clip(make_ray(Vec3(0, 4, 8), Vec3(1, 0, 0)), &t0, &t1));
  EXPECT_NEAR(t0, 1, 1e-4);
  EXPECT_NEAR(t1, 13, 1e-4);
  EXPECT_GT(m.memory_bytes(), v.size() * sizeof(float));
}

// A Volume object moving over the shutter (Medium::set_motion): at each ray's time it is the still
// medium placed at its pose then (the transform interpolated as instances'), in density, clipping
// and transmittance; its bounds hold every pose. Fails if the ray's time is ignored.
TEST(MediaGrid, AMovingGridIsTheStillGridAtItsPoseAtTheRaysTime) {
  const RefGrid g = blob(4);
  auto data = std::make_shared<const GridData>(GridData::from_dense(g.v, g.n[0], g.n[1], g.n[2]));
  auto turned = [&](float x, float degrees) {
    const float a = degrees * kPi / 180, c = std::cos(a), s = std::sin(a);
    Transform m;  // a turn about z, then x along x
    m.m[0] = c, m.m[1] = -s, m.m[4] = s, m.m[5] = c, m.m[3] = x;
    return compose(m, g.index_to_world());
  };
  const std::vector<Transform> steps{turned(-0.6f, -40), turned(0, 0), turned(0.6f, 40)};
  Medium moving = Medium::heterogeneous(data, Spectrum(0.5f), Spectrum(1.5f), 0, steps[1]);
  moving.set_motion(steps);
  EXPECT_TRUE(moving.moves());
  const std::vector<DecomposedTransform> decomposed = decompose_motion(steps);
  Sampler points(3, 0, 0);
  for (float time : {0.0f, 0.2f, 0.5f, 0.9f, 1.0f}) {
    const Medium still =
        Medium::heterogeneous(data, Spectrum(0.5f), Spectrum(1.5f), 0, interpolate_motion(decomposed, time));
    for (int i = 0; i < 200; ++i) {
      const Vec3 p(points.next_1d() * 3 - 1.5f, points.next_1d() * 2 - 1, points.next_1d() * 2 - 1);
      EXPECT_NEAR(moving.density(p, time), still.density(p), 1e-4) << "time " << time << " point " << i;
    }
    Ray r = make_ray(Vec3(-3, 0.1f, 0.05f), normalize(Vec3(1, 0.05f, 0.02f)));
    r.time = time;
    float a0 = 0, a1 = 10, b0 = 0, b1 = 10;
    ASSERT_EQ(moving.clip(r, &a0, &a1), still.clip(r, &b0, &b1)) << time;
    EXPECT_NEAR(a0, b0, 1e-4) << time;
    EXPECT_NEAR(a1, b1, 1e-4) << time;
    Sampler s1(7, 1, 2), s2(7, 1, 2);
    const Spectrum tm = moving.transmittance(r, 0, 10, s1, kMarch, 0.02f);
    const Spectrum ts = still.transmittance(r, 0, 10, s2, kMarch, 0.02f);
    EXPECT_NEAR(tm.x, ts.x, 1e-4) << time;
    EXPECT_LT(ts.x, 0.9f) << time;  // the ray crosses the blob
  }
  // The bounds hold the poses at the ends of the shutter.
  Vec3 lo, hi, l0, h0, l1, h1;
  ASSERT_TRUE(moving.bounds(&lo, &hi));
  Medium::heterogeneous(data, Spectrum(1.0f), Spectrum(0.0f), 0, steps[0]).bounds(&l0, &h0);
  Medium::heterogeneous(data, Spectrum(1.0f), Spectrum(0.0f), 0, steps[2]).bounds(&l1, &h1);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LE(lo[a], std::min(l0[a], l1[a]) + 1e-5f) << a;
    EXPECT_GE(hi[a], std::max(h0[a], h1[a]) - 1e-5f) << a;
  }
  // Bad input.
  Medium homogeneous = Medium::homogeneous(Spectrum(1.0f), Spectrum(0.0f), 0);
  EXPECT_THROW(homogeneous.set_motion(steps), InvalidArgument);
  std::vector<Transform> bad = steps;
  bad[2].m[5] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(moving.set_motion(bad), InvalidArgument);
  EXPECT_THROW(moving.set_motion({steps[0]}), InvalidArgument);
  moving.set_motion({});  // still again
  EXPECT_FALSE(moving.moves());
}

// ---- the statistical checks can fail ------------------------------------------------------------

TEST(MediaStats, ChecksRejectWrongDistributionsAndBias) {
  // Homogeneous samples tested against a 3% different sigma_t: the chi-square test rejects it.
  const float sigma_t = 1.3f;
  Medium m = Medium::homogeneous(Spectrum(0.0f), Spectrum(sigma_t), 0);
  const Ray r = make_ray(Vec3(0.0f), Vec3(0, 0, 1));
  const int nb = 50, n = 400000;
  std::vector<double> obs(nb + 1, 0.0);
  Sampler s(media_test::seed(94), 0, 0);
  for (int i = 0; i < n; ++i) {
    MediumInteraction mi;
    if (m.sample_distance(r, 0, 2, s, kTrack, 0, &mi))
      obs[bin_of(mi.t, 0, 2, nb)] += 1;
    else
      obs[nb] += 1;
  }
  std::vector<double> D(nb + 1);
  for (int b = 0; b <= nb; ++b) D[b] = 2.0 * b / nb;
  EXPECT_FALSE(pearson_1d(obs, free_flight_expected(D, nb, sigma_t * 1.03, n)).ok());
  EXPECT_TRUE(pearson_1d(obs, free_flight_expected(D, nb, sigma_t, n)).ok());

  // Ratio tracking's mean is more than 5 SE away from coarse ray marching's (12-voxel steps): the
  // 5-SE check detects the marching bias (and accepts fine marching).
  RefGrid g = blob();
  Medium h = make_medium(g, Spectrum(1.0f), Spectrum(2.0f));
  const Ray rb = make_ray(Vec3(-2, 0.3f, -0.2f), Vec3(1, 0, 0));
  Mean mt;
  for (int i = 0; i < 100000; ++i) mt.add(h.transmittance(rb, 0.2f, 3.6f, s, kTrack, 0).x);
  const double coarse = h.transmittance(rb, 0.2f, 3.6f, s, kMarch, 12.0f / 16).x;
  EXPECT_FALSE(within_se(mt, coarse)) << "ratio tracking " << mt.mean() << " +- " << mt.se() << ", marching " << coarse;
  EXPECT_TRUE(within_se(mt, h.transmittance(rb, 0.2f, 3.6f, s, kMarch, 0.25f / 16).x));
}

// ---- volume shader mixes and emission (media/volume_material.h) ------------------------------

TEST(VolumeMaterial, ComponentsAddAndPhaseLobesFollowScattering) {
  // Add Shader(Volume Scatter, Volume Absorption): the coefficients add; one lobe.
  VolumeCoefficients c[3];
  c[0] = volume_coefficients(VolumeNode::Scatter, Spectrum(0.8f, 0.5f, 0.2f), 2.0f, Spectrum(0.0f), 0.6f);
  c[1] = volume_coefficients(VolumeNode::Absorption, Spectrum(0.25f), 4.0f, Spectrum(0.0f), 0.0f);
  VolumeMix m = sum_volume_components(c, 2);
  EXPECT_FLOAT_EQ(m.sigma_s.x, 1.6f);
  EXPECT_FLOAT_EQ(m.sigma_s.z, 0.4f);
  EXPECT_FLOAT_EQ(m.sigma_a.y, 3.0f);
  ASSERT_EQ(m.phase.count, 1);
  EXPECT_FLOAT_EQ(m.phase.g[0], 0.6f);
  // A second scatter with another anisotropy: lobes weighted by their average sigma_s.
  c[2] = volume_coefficients(VolumeNode::Scatter, Spectrum(0.5f), 1.0f, Spectrum(0.0f), -0.4f);
  m = sum_volume_components(c, 3);
  ASSERT_EQ(m.phase.count, 2);
  const float avg0 = (1.6f + 1.0f + 0.4f) / 3, avg2 = 0.5f;
  EXPECT_NEAR(m.phase.weight[0], avg0 / (avg0 + avg2), 1e-6f);
  EXPECT_FLOAT_EQ(m.phase.g[1], -0.4f);
}

TEST(VolumeMaterial, BlackbodyMatchesCyclesAndHasUnitLuminance) {
  // Cycles 3.4.1's Blackbody node rendered at these temperatures (independent of the fitted samples).
  struct {
    float T;
    Spectrum c;
  } cycles[] = {{1000, Spectrum(4.60136175f, 0.03904079f, 0.0f)},
                {1500, Spectrum(3.26430678f, 0.43404534f, 0.0f)},
                {2500, Spectrum(2.06762958f, 0.76932192f, 0.13942985f)},
                {4000, Spectrum(1.41411519f, 0.92364097f, 0.53367424f)},
                {6500, Spectrum(1.04255068f, 0.98405147f, 1.03527117f)},
                {12000, Spectrum(0.82629371f, 0.99450684f, 1.56630695f)}};
  for (const auto& k : cycles) {
    Spectrum c = blackbody_rec709(k.T);
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(c[ch], k.c[ch], 2e-5f) << k.T << " channel " << ch;
  }
  for (float T = 2000; T < 20000; T *= 1.1f) {  // unclamped range: Y = 1 (Rec. 709 luminance)
    Spectrum c = blackbody_rec709(T);
    EXPECT_NEAR(0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z, 1.0f, 2e-3f) << T;
  }
  // Cycles 3.4.1's Principled Volume (density 0, Blackbody Intensity 1, 2 m deep: pixel / (2 sigma_SB
  // 1e-6 / pi T^4)) at temperatures apart from the fitted samples: unclamped, negative below ~1900 K.
  struct {
    float T;
    Spectrum c;
  } volume[] = {{700, Spectrum(5.41329241f, -0.203193843f, -0.0822535306f)},
                {1000, Spectrum(4.60136080f, 0.0390419327f, -0.0900272653f)},
                {1500, Spectrum(3.26430583f, 0.434046298f, -0.0642370209f)},
                {2500, Spectrum(2.06762981f, 0.769322693f, 0.139429674f)},
                {6000, Spectrum(1.08869064f, 0.978328586f, 0.953050792f)}};
  for (const auto& k : volume) {
    Spectrum c = blackbody_rec709_unclamped(k.T);
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(c[ch], k.c[ch], 2e-5f) << k.T << " channel " << ch;
    for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(blackbody_rec709(k.T)[ch], std::max(0.0f, c[ch]));
  }
  // Principled Volume: strength x colour + tint x sigma_SB 1e-6 / pi x T^4 x blackbody(T).
  Spectrum e = principled_volume_emission(2.0f, Spectrum(0.5f, 0.25f, 1.0f), 1.0f, Spectrum(1.0f), 3000.0f);
  Spectrum bb = blackbody_rec709(3000.0f) * float(5.670373e-14 / kPi * 81e12);
  EXPECT_NEAR(e.x, 1.0f + bb.x, 1e-4f);
  EXPECT_NEAR(e.z, 2.0f + bb.z, 1e-4f);
}

}  // namespace
}  // namespace lt
