// Image lookups as Cycles' CPU kernel makes them (kernel/device/cpu/image.h): the cubic B-spline.
#include <gtest/gtest.h>

#include <vector>

#include "shading/image.h"

namespace {

lt::Image grey(int w, int h, const std::vector<float>& v, lt::Extension ext) {
  return lt::Image(w, h, 1, v.data(), false, lt::Interpolation::Cubic, ext);
}

// Texel centres of an n-texel axis: (i + 0.5) / n.
float centre(int i, int n) { return (i + 0.5f) / n; }

TEST(ImageCubic, BSplineWeightsAtTexelCentresAndBetween) {
  // One texel of 1 among zeros (Clip): at its centre the B-spline gives (2/3)^2, at its
  // neighbour's centre (2/3)(1/6), halfway between two texels (23/48)^2 (weights at t = 1/2:
  // 1/48, 23/48, 23/48, 1/48).
  std::vector<float> v(49, 0.0f);
  v[3 * 7 + 3] = 1.0f;
  const lt::Image img = grey(7, 7, v, lt::Extension::Clip);
  EXPECT_NEAR(img.lookup({centre(3, 7), centre(3, 7)}).x, 4.0f / 9.0f, 1e-6f);
  EXPECT_NEAR(img.lookup({centre(4, 7), centre(3, 7)}).x, (2.0f / 3.0f) * (1.0f / 6.0f), 1e-6f);
  EXPECT_NEAR(img.lookup({3.0f / 7.0f, 3.0f / 7.0f}).x, (23.0f / 48.0f) * (23.0f / 48.0f), 1e-6f);
  EXPECT_EQ(img.lookup({centre(6, 7) + 0.5f, centre(3, 7)}).x, 0.0f);
}

TEST(ImageCubic, ReproducesRampsAndWrapsLikeLinear) {
  // A B-spline reproduces affine functions: a ramp's interior is exact (Extend), and the weights
  // sum to 1 (a constant image stays constant, across a Repeat image's edge too).
  std::vector<float> ramp(8 * 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 8; ++x) ramp[y * 8 + x] = 0.1f * x;
  const lt::Image r = grey(8, 2, ramp, lt::Extension::Extend);
  for (float u : {0.3f, 0.41f, 0.5f, 0.66f}) EXPECT_NEAR(r.lookup({u, 0.5f}).x, 0.1f * (u * 8 - 0.5f), 1e-5f);
  const lt::Image flat = grey(4, 4, std::vector<float>(16, 0.7f), lt::Extension::Repeat);
  for (float u : {0.0f, 0.01f, 0.99f, 2.37f, -1.2f}) EXPECT_NEAR(flat.lookup({u, u * 0.7f}).x, 0.7f, 1e-6f);
}

}  // namespace
