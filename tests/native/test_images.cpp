// Image lookups as Cycles' CPU kernel makes them (kernel/device/cpu/image.h): the cubic B-spline.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/error.h"
#include "io/image_file.h"
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

namespace {

std::string write_file(const std::string& name, const std::string& bytes) {
  const std::string path = ::testing::TempDir() + name;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
  return path;
}

// Blender's radiance_hdr.c value of mantissa m with exponent byte e: (m + 0.5) 2^(e - 136).
float ward(int m, int e) { return e == 0 ? 0.0f : float(std::ldexp(m + 0.5, e - 136)); }

std::unique_ptr<lt::Image> read(const std::string& path) {
  lt::ImageFileRequest r;
  r.path = path;
  r.space = lt::FileColorSpace::Linear;
  return lt::read_image_file(r);
}

}  // namespace

TEST(ImageFile, RadianceDecodesAsBlenderOldAndRunLengthScanlines) {
  const std::string header = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n";
  // 3 wide (under 8: flat pixels), top row first ("-Y"): a pixel and an old-style run of 2 of it;
  // then a zero exponent, a bright and a tiny pixel.
  const std::string flat = header + "-Y 2 +X 3\n" + std::string("\x0a\x14\x1e\x82\x01\x01\x01\x02", 8) +
                           std::string("\x07\x00\x00\x00\xff\x80\x01\x81\x05\x06\x07\x01", 12);
  auto img = read(write_file("lantern_flat.hdr", flat));
  ASSERT_EQ(img->width(), 3);
  for (int x = 0; x < 3; ++x) {  // the file's top row is Blender's row 1
    EXPECT_EQ(img->texel(x, 1).x, ward(10, 130));
    EXPECT_EQ(img->texel(x, 1).z, ward(30, 130));
  }
  EXPECT_EQ(img->texel(0, 0).x, 0.0f);
  EXPECT_EQ(img->texel(1, 0).x, ward(255, 129));
  EXPECT_EQ(img->texel(1, 0).z, ward(1, 129));
  EXPECT_EQ(img->texel(2, 0).y, ward(6, 1));
  EXPECT_GT(img->texel(2, 0).y, 0.0f);  // a denormal float, not flushed

  // 8 wide, bottom row first ("+Y"): run-length components (runs of 8, literals).
  std::string rle = header + "+Y 1 +X 8\n" + std::string("\x02\x02\x00\x08", 4);
  rle += std::string("\x88\x40", 2);                              // R: a run of 8
  rle += std::string("\x08\x00\x01\x02\x03\x04\x05\x06\x07", 9);  // G: 8 literals
  rle += std::string("\x84\x10\x04\x11\x12\x13\x14", 7);          // B: a run of 4, 4 literals
  rle += std::string("\x88\x88", 2);                              // E: a run of 8
  img = read(write_file("lantern_rle.hdr", rle));
  for (int x = 0; x < 8; ++x) {
    EXPECT_EQ(img->texel(x, 0).x, ward(0x40, 0x88));
    EXPECT_EQ(img->texel(x, 0).y, ward(x, 0x88));
    EXPECT_EQ(img->texel(x, 0).z, ward(x < 4 ? 0x10 : 0x11 + x - 4, 0x88));
  }
  // Truncated: an I/O error (the add-on then loads it through Blender, which reports it).
  EXPECT_THROW(read(write_file("lantern_short.hdr", rle.substr(0, rle.size() - 3))), lt::IoError);
  // A transposed image (Blender reads it as if it were not) and a float image Blender would
  // convert from sRGB are left to Blender.
  EXPECT_THROW(read(write_file("lantern_xy.hdr", header + "+X 8 -Y 1\n" + rle.substr(rle.find("\x02\x02")))),
               lt::ImageFileUnsupported);
  lt::ImageFileRequest srgb;
  srgb.path = ::testing::TempDir() + "lantern_rle.hdr";
  EXPECT_THROW(lt::read_image_file(srgb), lt::ImageFileUnsupported);
}
