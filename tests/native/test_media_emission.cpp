// Emission of heterogeneous media read from grids (a Volume object's fire: Emission Strength from a
// 'flame' grid, blackbody from a 'temperature' grid; media/grid_emission.h): both estimators of
// Medium::emission_integral against quadrature of the integral of E(s) T(t0, s) ds, with the
// emission's grids in index spaces other than the density's. Tracking within 5 standard errors
// (unbiased); ray marching within its measured O(h^2) bias. Seeds are fixed.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <memory>

#include "core/error.h"
#include "media/grid_emission.h"
#include "media/medium.h"
#include "media/volume_material.h"
#include "test_media_util.h"

namespace lt {
namespace {

using media_test::Mean;
using media_test::RefGrid;
using media_test::within_se;

// A Gaussian blob of n^3 voxels of `scale` world units centred at `centre` (world).
RefGrid blob(int n, double scale, double amplitude, double sigma_voxels, const Vec3& centre = Vec3(0.0f)) {
  RefGrid g;
  g.n[0] = g.n[1] = g.n[2] = n;
  g.scale = scale;
  const double c = 0.5 * (n - 1);
  for (int a = 0; a < 3; ++a) g.offset[a] = centre[a] - c * scale;
  g.v.resize(size_t(n) * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        double r2 = sqr(i - c) + sqr(j - c) + sqr(k - c);
        g.v[(size_t(k) * n + j) * n + i] = float(amplitude * std::exp(-r2 / (2 * sigma_voxels * sigma_voxels)));
      }
  return g;
}

std::shared_ptr<const GridData> grid_data(const RefGrid& g) {
  return std::make_shared<const GridData>(GridData::from_dense(g.v, g.n[0], g.n[1], g.n[2], g.index_to_world()));
}

Ray make_ray(const Vec3& o, const Vec3& d) {
  Ray r;
  r.o = o;
  r.d = d;
  return r;
}

struct Fire {
  RefGrid density = blob(32, 1.0 / 16, 2.0, 5.0);
  // Coarser and shifted: the emission's grids have index spaces of their own.
  RefGrid flame = blob(16, 1.0 / 8, 1.5, 2.5, Vec3(0.1f, -0.05f, -0.2f));
  RefGrid temperature = blob(24, 1.0 / 12, 1.2, 6.0, Vec3(0.0f, 0.0f, 0.1f));
  Spectrum sigma_a{0.8f, 1.0f, 1.2f}, sigma_s{1.5f};
  Spectrum color{1.0f, 0.5f, 0.2f};
  float strength = 2.0f, kelvin = 1500.0f;
  bool read_temperature = true;  // the Temperature Attribute grid

  Medium medium() const {
    // The density grid's index space is the medium's object space here (index_to_world in the
    // grid itself, identity object transform), so the density's index -> object is its own.
    auto d = grid_data(density);
    Medium m = Medium::heterogeneous(d, sigma_a, sigma_s, 0.0f);
    EmissionComponent c;
    c.strength = {strength, 0};
    c.color = color;
    c.blackbody = {1.0f, -1};
    c.temperature = {kelvin, -1};
    c.temperature_attribute = read_temperature ? 1 : -1;
    c.tint = Spectrum(1.0f);
    m.set_grid_emission(std::make_shared<GridEmission>(
        std::vector<std::shared_ptr<const GridData>>{grid_data(flame), grid_data(temperature)},
        std::vector<EmissionComponent>{c}, d->index_to_object));
    return m;
  }
  // The emission at a world point from the reference grids, zero outside the density's domain
  // (its voxels widened by one).
  Spectrum emission(const Vec3& p) const {
    const double lo = density.offset[0] - density.scale, hi = density.offset[0] + density.n[0] * density.scale;
    for (int a = 0; a < 3; ++a)
      if (!(p[a] >= lo && p[a] <= hi)) return Spectrum(0.0f);
    const float f = float(flame.world_density(p.x, p.y, p.z));
    const float T = kelvin * float(temperature.world_density(p.x, p.y, p.z));
    return principled_volume_emission(strength * f, color, 1.0f, Spectrum(1.0f), T);
  }
};

// Simpson quadrature (m intervals) of integral E(s) T(t0, s) T_o(s) |d| dt over [t0, t1], T from the
// reference density, T_o = exp(-sigma_other (t - t0) |d|) x other_rate's exp(-other_rate (t - t0)).
Spectrum reference(const Fire& f, const Ray& r, double t0, double t1, const Spectrum& sigma_other, double other_rate,
                   int m = 8000) {
  const double len = length(r.d), h = (t1 - t0) / m;
  const Spectrum st = f.sigma_a + f.sigma_s;
  auto rho = [&](double t) { return f.density.world_density(r.o.x + t * r.d.x, r.o.y + t * r.d.y, r.o.z + t * r.d.z); };
  double D = 0;  // density integral (world length) from t0
  double L[3] = {0, 0, 0};
  auto integrand = [&](double t, double depth, int c) {
    const Vec3 p = r.o + r.d * float(t);
    return f.emission(p)[c] * std::exp(-st[c] * depth - sigma_other[c] * (t - t0) * len - other_rate * (t - t0)) * len;
  };
  for (int k = 0; k < m; ++k) {
    const double a = t0 + k * h, b = a + h, mid = 0.5 * (a + b);
    const double Dm = D + h * len / 6 * (rho(a) + 4 * rho(0.5 * (a + mid)) + rho(mid)) * 0.5;
    const double Db = D + h * len / 6 * (rho(a) + 4 * rho(mid) + rho(b));
    for (int c = 0; c < 3; ++c) L[c] += h / 6 * (integrand(a, D, c) + 4 * integrand(mid, Dm, c) + integrand(b, Db, c));
    D = Db;
  }
  return Spectrum(float(L[0]), float(L[1]), float(L[2]));
}

std::vector<Ray> fire_rays() {
  return {make_ray(Vec3(-2, 0.02f, -0.1f), Vec3(1, 0, 0)),                       // through the flame
          make_ray(Vec3(-2, 0.45f, 0.3f), Vec3(1, 0, 0)),                        // the thin edge
          make_ray(Vec3(-1.5f, -0.9f, 0.9f), normalize(Vec3(1, 0.9f, -0.95f))),  // corner cells
          make_ray(Vec3(0.1f, 0.2f, 2), Vec3(0.02f, -0.05f, -3))};               // non-unit direction
}

// Both overlap settings: alone, and inside other media (homogeneous sigma_other, and a
// heterogeneous one's transmittance estimate, here a known exp(-0.7 (t - t0))).
struct Overlap {
  Spectrum sigma_other;
  double other_rate;
};
const Overlap kOverlaps[] = {{Spectrum(0.0f), 0.0}, {Spectrum(0.3f, 0.6f, 0.1f), 0.7}};

// Calls f(ray index, overlap, ray, t0, t1, reference, estimate) for every ray and overlap setting;
// estimate(estimator, step) is one call of emission_integral on the case.
template <class F>
void for_each_case(const Fire& fire, const Medium& m, Sampler& s, F&& f) {
  for (const Overlap& o : kOverlaps)
    for (size_t k = 0; k < fire_rays().size(); ++k) {
      const Ray r = fire_rays()[k];
      const float t0 = 0.2f / length(r.d), t1 = 3.8f / length(r.d);
      const Spectrum expect = reference(fire, r, t0, t1, o.sigma_other, o.other_rate);
      std::function<Spectrum(float)> other = [&](float t) {
        return Spectrum(float(std::exp(-o.other_rate * (t - t0))));
      };
      auto estimate = [&](VolumeEstimator e, float step) {
        return m.emission_integral(r, t0, t1, s, e, step, o.sigma_other, o.other_rate > 0 ? &other : nullptr);
      };
      f(k, o, expect, estimate);
    }
}

TEST(MediaEmission, TrackingMatchesQuadrature) {
  const Fire fire;
  const Medium m = fire.medium();
  Sampler s(media_test::seed(71), 0, 0);
  for_each_case(fire, m, s, [&](size_t k, const Overlap& o, const Spectrum& expect, auto&& estimate) {
    Mean mean[3];
    for (int i = 0; i < 40000; ++i) {
      const Spectrum L = estimate(VolumeEstimator::Tracking, 0.0f);
      ASSERT_TRUE(is_finite(L));  // blue may be negative: Cycles' blackbody below ~1900 K
      for (int c = 0; c < 3; ++c) mean[c].add(L[c]);
    }
    for (int c = 0; c < 3; ++c)
      EXPECT_TRUE(within_se(mean[c], expect[c]))
          << "ray " << k << " channel " << c << " overlap " << o.other_rate << " (reference " << expect[c] << ")";
    EXPECT_GT(expect.x, 1e-3f) << "ray " << k << ": the ray must see emission";
  });
}

// Ray marching (Cycles' per-step integration): deterministic, its error against quadrature falls
// with the step (O(h^2) for the midpoint values, down to a float rounding floor near 1e-4) and is
// below 1e-3 relative at a quarter voxel.
TEST(MediaEmission, RayMarchingConvergesToQuadrature) {
  const Fire fire;
  const Medium m = fire.medium();
  Sampler s(media_test::seed(72), 0, 0);
  for_each_case(fire, m, s, [&](size_t k, const Overlap& o, const Spectrum& expect, auto&& estimate) {
    double coarse = 0;
    for (float step : {4.0f, 2.0f, 1.0f, 0.5f, 0.25f}) {
      const float h = step / 16;  // voxels -> world
      const Spectrum L = estimate(VolumeEstimator::RayMarching, h), again = estimate(VolumeEstimator::RayMarching, h);
      for (int c = 0; c < 3; ++c) EXPECT_EQ(L[c], again[c]);
      double err = 0;
      for (int c = 0; c < 3; ++c) err = std::max(err, std::abs(double(L[c]) - expect[c]) / expect[c]);
      std::printf("[ emission ] ray %zu overlap %.1f step %.2f voxel: max relative error %.2e\n", k, o.other_rate, step,
                  err);
      if (step == 4.0f) coarse = err;
      if (step == 0.5f) EXPECT_LT(err, 0.2 * coarse) << "ray " << k;  // measured: 0.004 to 0.017 x
      if (step == 0.25f) EXPECT_LT(err, 1e-3) << "ray " << k;         // measured: at most 1.5e-4
    }
  });
}

// Per-point lookups (each grid in its own index space, trilinear) equal the reference grids'.
TEST(MediaEmission, LookupsMatchTheReferenceGrids) {
  const Fire fire;
  const Medium m = fire.medium();
  int nonzero = 0;
  for (float x = -1.1f; x <= 1.1f; x += 0.137f)
    for (float y = -1.1f; y <= 1.1f; y += 0.173f)
      for (float z = -1.1f; z <= 1.1f; z += 0.191f) {
        const Spectrum e = m.emission_at(Vec3(x, y, z)), ref = fire.emission(Vec3(x, y, z));
        for (int c = 0; c < 3; ++c)
          ASSERT_NEAR(e[c], ref[c], 1e-5f * std::abs(ref[c]) + 1e-9f) << x << " " << y << " " << z;
        nonzero += !is_black(ref);
      }
  EXPECT_GT(nonzero, 1000);
}

// An emission-only Volume object (an Emission node: no extinction) is empty for transport but
// emits: tracking (one collision per voxel, weight 1) and marching give the plain integral of E.
TEST(MediaEmission, EmissionWithoutExtinction) {
  Fire fire;
  fire.sigma_a = fire.sigma_s = Spectrum(0.0f);
  const Medium m = fire.medium();
  EXPECT_TRUE(m.empty());
  EXPECT_TRUE(m.emissive());
  Sampler s(media_test::seed(74), 0, 0);
  const Ray r = fire_rays()[0];
  const float t0 = 0.2f, t1 = 3.8f;
  const Spectrum expect = reference(fire, r, t0, t1, Spectrum(0.0f), 0.0);
  Mean mean[3];
  for (int i = 0; i < 20000; ++i) {
    const Spectrum L = m.emission_integral(r, t0, t1, s, VolumeEstimator::Tracking, 0, Spectrum(0.0f), nullptr);
    for (int c = 0; c < 3; ++c) mean[c].add(L[c]);
  }
  const Spectrum marched =
      m.emission_integral(r, t0, t1, s, VolumeEstimator::RayMarching, 0.25f / 16, Spectrum(0.0f), nullptr);
  for (int c = 0; c < 3; ++c) {
    EXPECT_TRUE(within_se(mean[c], expect[c])) << "channel " << c;
    EXPECT_NEAR(marched[c], expect[c], 1e-3 * std::abs(expect[c])) << "channel " << c;
  }
}

TEST(MediaEmission, OnlyGridMediaTakeGridEmissionAndNonEmittersAddNothing) {
  Medium h = Medium::homogeneous(Spectrum(1.0f), Spectrum(1.0f), 0.0f);
  EXPECT_THROW(h.set_grid_emission(nullptr), InvalidArgument);
  Fire fire;
  auto d = grid_data(fire.density);
  const Medium plain = Medium::heterogeneous(d, fire.sigma_a, fire.sigma_s, 0.0f);
  EXPECT_FALSE(plain.emissive());
  Sampler s(media_test::seed(73), 0, 0);
  const Ray r = fire_rays()[0];
  EXPECT_TRUE(is_black(plain.emission_integral(r, 0, 4, s, VolumeEstimator::Tracking, 0, Spectrum(0.0f), nullptr)));
  EXPECT_TRUE(fire.medium().emissive());
  EmissionComponent bad;
  bad.strength = {1.0f, 3};  // no such grid
  EXPECT_THROW(GridEmission({grid_data(fire.flame)}, {bad}, d->index_to_object), InvalidArgument);
}

}  // namespace
}  // namespace lt
