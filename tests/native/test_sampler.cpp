// The sample patterns (core/sampling.h): Sobol-Owen points are stratified in each call's
// dimensions over every power-of-two run of a half's samples, deterministic, uniform over pixels,
// and integrate smooth functions with far less error than independent numbers.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

#include "core/sampling.h"

using lt::SamplePattern;
using lt::Sampler;
using lt::Vec2;

namespace {

// The 2D points the `call`-th draw (0-based; earlier calls are 2D draws too) gives to the first n
// samples of one half (sample indices half, half + 2, ...) of a pixel.
std::vector<Vec2> half_points(uint32_t seed, uint32_t pixel, int half, int n, int call) {
  std::vector<Vec2> out;
  for (int i = 0; i < n; ++i) {
    Sampler s(seed, pixel, uint32_t(2 * i + half), SamplePattern::SobolOwen);
    Vec2 p;
    for (int c = 0; c <= call; ++c) p = s.next_2d();
    out.push_back(p);
  }
  return out;
}

// (0, m, 2)-net: every elementary interval of area 2^-m (2^j x 2^(m-j) cells) holds one point.
bool is_net(const std::vector<Vec2>& pts, int m) {
  for (int j = 0; j <= m; ++j) {
    const int nx = 1 << j, ny = 1 << (m - j);
    std::vector<int> count(size_t(nx) * ny, 0);
    for (const Vec2& p : pts) ++count[size_t(int(p.y * ny)) * nx + int(p.x * nx)];
    for (int c : count)
      if (c != 1) return false;
  }
  return true;
}

}  // namespace

TEST(Sampler, SobolOwenPointsAreNetsInEveryCallAndHalf) {
  for (uint32_t pixel : {0u, 7u, 123456u})
    for (int half : {0, 1})
      for (int call : {0, 1, 5, 40})
        for (int m = 0; m <= 10; ++m)
          EXPECT_TRUE(is_net(half_points(3, pixel, half, 1 << m, call), m))
              << "pixel " << pixel << " half " << half << " call " << call << " m " << m;
}

TEST(Sampler, SobolOwen1DIsStratified) {
  // The first 2^m samples of a half put one value in each 1/2^m interval, in any call.
  for (int call : {0, 3}) {
    const int m = 9, n = 1 << m;
    std::vector<int> count(n, 0);
    for (int i = 0; i < n; ++i) {
      Sampler s(5, 42, uint32_t(2 * i + 1), SamplePattern::SobolOwen);
      float u = 0;
      for (int c = 0; c <= call; ++c) u = s.next_1d();
      ASSERT_GE(u, 0.0f);
      ASSERT_LT(u, 1.0f);
      ++count[int(u * n)];
    }
    for (int c : count) EXPECT_EQ(c, 1) << "call " << call;
  }
}

TEST(Sampler, NumbersDependOnlyOnSeedPixelIndexAndCall) {
  for (SamplePattern pattern : {SamplePattern::SobolOwen, SamplePattern::Independent}) {
    Sampler a(9, 77, 1000, pattern), b(9, 77, 1000, pattern);
    for (int k = 0; k < 50; ++k) {
      Vec2 pa = a.next_2d(), pb = b.next_2d();
      EXPECT_EQ(pa.x, pb.x);
      EXPECT_EQ(pa.y, pb.y);
      EXPECT_EQ(a.next_1d(), b.next_1d());
    }
    // Another seed, pixel or sample index gives other numbers.
    const float base = Sampler(9, 77, 1000, pattern).next_1d();
    EXPECT_NE(Sampler(10, 77, 1000, pattern).next_1d(), base);
    EXPECT_NE(Sampler(9, 78, 1000, pattern).next_1d(), base);
    EXPECT_NE(Sampler(9, 77, 1001, pattern).next_1d(), base);
  }
}

TEST(Sampler, SobolOwenHalvesAndPixelsAreScrambledIndependently) {
  // The two halves of a pixel and neighbouring pixels are different nets (different scrambles):
  // no point repeats between them.
  std::set<float> seen;
  size_t total = 0;
  for (uint32_t pixel : {0u, 1u, 640u})
    for (int half : {0, 1})
      for (const Vec2& p : half_points(1, pixel, half, 64, 0)) {
        seen.insert(p.x);
        ++total;
      }
  EXPECT_EQ(seen.size(), total);
}

TEST(Sampler, SobolOwenIsUniformOverPixels) {
  // One sample (index 5) in each of 2^16 pixels: each call's values are uniform (chi-square over
  // 64 x 64 cells, 4095 degrees of freedom: mean 4095, sd 90.5; bound at 5 sd).
  const int cells = 64, n = 1 << 16;
  for (int call : {0, 1, 17, 70}) {
    std::vector<int> count(size_t(cells) * cells, 0);
    double mean_x = 0;
    for (int px = 0; px < n; ++px) {
      Sampler s(2, uint32_t(px), 5, SamplePattern::SobolOwen);
      Vec2 p;
      for (int c = 0; c <= call; ++c) p = s.next_2d();
      ++count[size_t(int(p.y * cells)) * cells + int(p.x * cells)];
      mean_x += p.x / n;
    }
    const double expect = double(n) / (cells * cells);
    double chi2 = 0;
    for (int c : count) chi2 += (c - expect) * (c - expect) / expect;
    EXPECT_LT(std::abs(chi2 - 4095), 5 * 90.5) << "call " << call;
    EXPECT_NEAR(mean_x, 0.5, 5 * std::sqrt(1.0 / 12 / n)) << "call " << call;
  }
}

TEST(Sampler, SobolOwenIntegratesSmoothFunctionsBetter) {
  // Estimate the integral of a smooth 2D function (soft-shadow-like) with 64 samples per pixel
  // (32 per half) in 1024 pixels, the 2D point taken in the third call. Both patterns are unbiased
  // (the mean over pixels within 5 SE); Sobol-Owen's per-pixel error is far below independent's
  // (Owen scrambling: variance O(n^-3) for smooth integrands, against n^-1).
  auto f = [](Vec2 p) { return std::exp(-3 * p.x) * (1 + std::sin(4 * p.y)) + p.x * p.y; };
  // Closed form: (1 - e^-3)/3 * (1 + (1 - cos 4)/4) + 1/4.
  const double exact = (1 - std::exp(-3.0)) / 3 * (1 + (1 - std::cos(4.0)) / 4) + 0.25;
  const int pixels = 1024, spp = 64;
  double mse[2] = {0, 0};
  for (SamplePattern pattern : {SamplePattern::SobolOwen, SamplePattern::Independent}) {
    const int k = int(pattern);
    double sum = 0, sum2 = 0;
    for (int px = 0; px < pixels; ++px) {
      double est = 0;
      for (int i = 0; i < spp; ++i) {
        Sampler s(11, uint32_t(px), uint32_t(i), pattern);
        s.next_2d();
        s.next_1d();
        est += f(s.next_2d()) / spp;
      }
      sum += est;
      sum2 += est * est;
      mse[k] += (est - exact) * (est - exact) / pixels;
    }
    const double mean = sum / pixels, var = sum2 / pixels - mean * mean;
    EXPECT_NEAR(mean, exact, 5 * std::sqrt(var / pixels)) << "pattern " << k;
  }
  EXPECT_LT(mse[0], mse[1] / 20) << "Sobol-Owen MSE " << mse[0] << ", independent " << mse[1];
}
