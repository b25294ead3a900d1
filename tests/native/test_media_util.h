// Shared helpers of the participating-media tests (test_media*.cpp): running means with standard
// errors, a 1D Pearson chi-square test, a double-precision reference of the dense grids' trilinear
// density, and quadrature of the optical depth along a ray, all independent of media/medium.cpp.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "chi2.h"
#include "core/math.h"

namespace lt::media_test {

// The tests' fixed seeds, shifted by LANTERN_CHI2_SEED=<k> like the chi-square tests' (to look at
// the spread of outcomes over other fixed seeds).
inline uint32_t seed(uint32_t s) {
  if (const char* env = std::getenv("LANTERN_CHI2_SEED")) s += uint32_t(std::strtoul(env, nullptr, 10)) * 7919u;
  return s;
}

struct Mean {
  double sum = 0, sum2 = 0;
  long n = 0;
  void add(double x) {
    sum += x;
    sum2 += x * x;
    ++n;
  }
  double mean() const { return n ? sum / n : 0; }
  double se() const {
    if (n < 2) return INFINITY;
    double m = mean();
    return std::sqrt(std::max(0.0, sum2 / n - m * m) / (n - 1));
  }
};

// |mean - expected| <= k SE (+ a float-rounding floor, so that zero-variance estimators compare
// at float precision).
inline ::testing::AssertionResult within_se(const Mean& m, double expected, double k = 5, double floor = 2e-6) {
  double tol = k * m.se() + floor * std::max(1.0, std::abs(expected));
  double err = std::abs(m.mean() - expected);
  if (err <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "mean " << m.mean() << " expected " << expected << " (|err| " << err << " > "
                                       << k << " SE = " << tol << ", n " << m.n << ")";
}

struct Pearson {
  double chi2 = 0, p = 0, alpha = 0;
  int dof = 0;
  bool ok() const { return dof > 0 && p >= alpha; }
  std::string summary() const {
    return "chi2 " + std::to_string(chi2) + " dof " + std::to_string(dof) + " p " + std::to_string(p) + " alpha " +
           std::to_string(alpha);
  }
};

// Pearson's test of observed against expected counts; neighbouring bins are pooled until each
// pooled expected count is >= 5. Rejects at the suite's Sidak-corrected level (chi2.h).
inline Pearson pearson_1d(const std::vector<double>& observed, const std::vector<double>& expected) {
  Pearson r;
  std::vector<std::pair<double, double>> cells;
  double po = 0, pe = 0;
  for (size_t i = 0; i < observed.size(); ++i) {
    po += observed[i];
    pe += expected[i];
    if (pe >= 5) {
      cells.push_back({po, pe});
      po = pe = 0;
    }
  }
  if (pe > 0 || po > 0) {
    if (cells.empty())
      cells.push_back({po, pe});
    else {
      cells.back().first += po;
      cells.back().second += pe;
    }
  }
  for (auto& c : cells)
    r.chi2 += c.second > 0 ? (c.first - c.second) * (c.first - c.second) / c.second : (c.first > 0 ? INFINITY : 0);
  r.dof = int(cells.size()) - 1;
  r.p = test::chi2_survival(r.chi2, r.dof);
  r.alpha = test::sidak_alpha(0.01, test::kChi2SuiteTests);
  return r;
}

// A dense grid with its own double-precision trilinear interpolation (voxel centres at integer
// index coordinates, zero outside, clamped >= 0) and an index_to_world of scale and translation.
struct RefGrid {
  std::vector<float> v;
  int n[3] = {0, 0, 0};
  double scale = 1;              // world units per voxel
  double offset[3] = {0, 0, 0};  // world position of index (0, 0, 0)

  double at(int i, int j, int k) const {
    if (i < 0 || j < 0 || k < 0 || i >= n[0] || j >= n[1] || k >= n[2]) return 0;
    return v[(size_t(k) * n[1] + j) * n[0] + i];
  }
  double index_density(double x, double y, double z) const {
    double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    int i = int(fx), j = int(fy), k = int(fz);
    double u = x - fx, w = y - fy, s = z - fz, r = 0;
    for (int c = 0; c < 8; ++c) {
      int di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
      r += at(i + di, j + dj, k + dk) * (di ? u : 1 - u) * (dj ? w : 1 - w) * (dk ? s : 1 - s);
    }
    return std::max(0.0, r);
  }
  double world_density(double x, double y, double z) const {
    return index_density((x - offset[0]) / scale, (y - offset[1]) / scale, (z - offset[2]) / scale);
  }
  Transform index_to_world() const {
    Transform t;
    t.m[0] = t.m[5] = t.m[10] = float(scale);
    t.m[3] = float(offset[0]);
    t.m[7] = float(offset[1]);
    t.m[11] = float(offset[2]);
    return t;
  }
};

// Cumulative integral of f(t) at nodes t0 + (t1 - t0) k / m, k = 0..m (composite Simpson on each
// of the m intervals; the density is smooth between voxel planes and the intervals are fine).
inline std::vector<double> cumulative(const std::function<double(double)>& f, double t0, double t1, int m) {
  std::vector<double> c(m + 1, 0.0);
  double h = (t1 - t0) / m, fa = f(t0);
  for (int k = 0; k < m; ++k) {
    double a = t0 + k * h, b = a + h;
    double fm = f(0.5 * (a + b)), fb = f(b);
    c[k + 1] = c[k] + h / 6 * (fa + 4 * fm + fb);
    fa = fb;
  }
  return c;
}

}  // namespace lt::media_test
