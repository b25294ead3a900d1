// Image lookups as Cycles' CPU kernel makes them (kernel/device/cpu/image.h): the cubic B-spline.
#include <Imath/half.h>
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

TEST(ImageCubic, QuadraticGainsTheBSplineOffsetUnlikeAnInterpolatingCubic) {
  // The uniform cubic B-spline of samples f(i) = i^2 is x^2 + 1/3 (Schoenberg's spline: its
  // weights' second moment about x is 1/3), where an interpolating cubic (Catmull-Rom) would give
  // x^2 and linear interpolation x^2 + t (1 - t). x in texels: u * width - 0.5.
  const int w = 16;
  std::vector<float> sq(w);
  for (int i = 0; i < w; ++i) sq[i] = float((i - 8) * (i - 8)) / 64.0f;
  const lt::Image img = grey(w, 1, sq, lt::Extension::Extend);
  for (float x : {5.0f, 6.25f, 7.5f, 8.0f, 9.8f}) {
    const float u = (x + 0.5f) / w;
    EXPECT_NEAR(img.lookup({u, 0.5f}).x, ((x - 8) * (x - 8) + 1.0f / 3.0f) / 64.0f, 2e-6f) << x;
  }
}

TEST(ImageCubic, PartitionOfUnityAndExtensionsAtTheEdges) {
  // A constant image: Repeat and Extend keep it everywhere (the weights sum to 1 for any t);
  // Clip drops the texels outside, so at a corner texel's centre one of the 4 per axis is gone
  // (weight 1/6): (5/6)^2 of the constant, and half a texel out (t = 1/2: 1/48 + 23/48 left)
  // 1/2 per axis.
  const float c = 0.6f;
  const std::vector<float> flat(5 * 4, c);
  for (float t : {0.0f, 0.1f, 0.37f, 0.5f, 0.93f}) {
    const lt::Vec2 uv{centre(2, 5) + t / 5, centre(1, 4) + t / 4};
    EXPECT_NEAR(grey(5, 4, flat, lt::Extension::Extend).lookup(uv).x, c, 1e-6f);
    EXPECT_NEAR(grey(5, 4, flat, lt::Extension::Clip).lookup(uv).x, c, 1e-6f);
  }
  EXPECT_NEAR(grey(5, 4, flat, lt::Extension::Clip).lookup({centre(0, 5), centre(3, 4)}).x, c * 25 / 36, 1e-6f);
  EXPECT_NEAR(grey(5, 4, flat, lt::Extension::Clip).lookup({1.0f, centre(2, 4)}).x, c * 0.5f, 1e-6f);
  EXPECT_EQ(grey(5, 4, flat, lt::Extension::Clip).lookup({1.5f, centre(2, 4)}).x, 0.0f);
  // A ramp 0.1 i on 4 x 1 texels: Extend repeats the edge texel (at texel 0's centre: 1/6 of
  // texel 1), Repeat wraps to the far edge (1/6 of texel 3 besides), Clip drops it (and the rows
  // above and below the only one: 2/3 of that).
  const std::vector<float> ramp = {0.0f, 0.1f, 0.2f, 0.3f};
  const lt::Vec2 first{centre(0, 4), 0.5f};
  EXPECT_NEAR(grey(4, 1, ramp, lt::Extension::Extend).lookup(first).x, 0.1f / 6, 1e-6f);
  EXPECT_NEAR(grey(4, 1, ramp, lt::Extension::Repeat).lookup(first).x, (0.1f + 0.3f) / 6, 1e-6f);
  EXPECT_NEAR(grey(4, 1, ramp, lt::Extension::Clip).lookup(first).x, (0.1f / 6) * (2.0f / 3.0f), 1e-6f);
  EXPECT_NEAR(grey(4, 1, ramp, lt::Extension::Repeat).lookup({centre(0, 4) + 1.0f, 0.5f}).x, (0.1f + 0.3f) / 6, 1e-6f);
}

// fuzz_abi: a texture coordinate of 5.7e34 (a mapping's scale) was converted to int (undefined
// behaviour: UBSan's float-cast-overflow; in Release INT_MIN, so Extend gave the left edge for
// any far coordinate). Far coordinates now give the edge they lie beyond (Extend), nothing (Clip)
// or a texel of the period (Repeat), for every interpolation.
TEST(ImageLookup, CoordinatesBeyondTheIntegerRange) {
  const std::vector<float> ramp = {0.0f, 0.1f, 0.2f, 0.3f};
  for (lt::Interpolation interp : {lt::Interpolation::Closest, lt::Interpolation::Linear, lt::Interpolation::Cubic})
    for (float u : {5.7e34f, -5.7e34f, 3e9f, -3e9f}) {
      const int k = int(interp);
      const lt::Vec2 uv{u, 0.5f};
      const lt::Image extend(4, 1, 1, ramp.data(), false, interp, lt::Extension::Extend);
      EXPECT_NEAR(extend.lookup(uv).x, u > 0 ? 0.3f : 0.0f, 1e-6f) << k << " " << u;
      const lt::Image clip(4, 1, 1, ramp.data(), false, interp, lt::Extension::Clip);
      EXPECT_EQ(clip.lookup(uv).x, 0.0f) << k << " " << u;
      const lt::Image repeat(4, 1, 1, ramp.data(), false, interp, lt::Extension::Repeat);
      const float r = repeat.lookup(uv).x;
      EXPECT_TRUE(r >= 0.0f && r <= 0.3f) << k << " " << u << ": " << r;
    }
}

TEST(ImageCubic, OneFilterForBytesHalvesAndFloats) {
  // The same texels stored as bytes (a file's), half floats (a half OpenEXR's) and floats give the
  // same cubic lookups: one filter reads each storage in place. The float images hold one texel
  // that is not a byte value (column 6, outside every footprint sampled) so that they stay float.
  const int w = 12, h = 3, n = w * h;
  std::vector<uint8_t> bytes(n * 3);
  std::vector<float> byte_values(n * 3), eighths(n * 3);
  std::vector<uint16_t> halfs(n * 3);
  for (int i = 0; i < n * 3; ++i) {
    bytes[i] = uint8_t((i * 37) % 256);
    byte_values[i] = float(bytes[i]) * (1.0f / 255.0f);
    eighths[i] = float((i * 5) % 17) / 8.0f;  // exact in half
    halfs[i] = imath_float_to_half(eighths[i]);
  }
  byte_values[3 * (w + 6)] += 1e-3f;
  const auto cubic = lt::Interpolation::Cubic;
  for (auto ext : {lt::Extension::Repeat, lt::Extension::Extend, lt::Extension::Clip}) {
    lt::ByteBuffer b(n * 3);
    lt::HalfBuffer hb(n * 3);
    std::copy(bytes.begin(), bytes.end(), b.data());
    std::copy(halfs.begin(), halfs.end(), hb.data());
    const lt::Image from_bytes(w, h, 3, std::move(b), false, cubic, ext);
    const lt::Image from_halfs(w, h, 3, std::move(hb), cubic, ext);
    const lt::Image byte_floats(w, h, 3, byte_values.data(), false, cubic, ext);
    const lt::Image half_floats(w, h, 3, eighths.data(), false, cubic, ext);
    ASSERT_TRUE(from_bytes.is_byte());
    ASSERT_FALSE(byte_floats.is_byte());
    ASSERT_EQ(from_halfs.bytes(), size_t(n) * 3 * 2);
    ASSERT_EQ(half_floats.bytes(), size_t(n) * 3 * 4);
    // Footprints (4 texels around u w - 0.5) that miss column 6.
    for (lt::Vec2 uv : {lt::Vec2{0.03f, 0.5f}, lt::Vec2{0.2f, 0.77f}, lt::Vec2{0.99f, 0.02f}, lt::Vec2{1.2f, -0.1f}}) {
      const lt::Vec3 a = from_bytes.lookup(uv), a2 = byte_floats.lookup(uv);
      const lt::Vec3 c = from_halfs.lookup(uv), c2 = half_floats.lookup(uv);
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(a[k], a2[k]) << uv.x << " " << uv.y;
        EXPECT_EQ(c[k], c2[k]) << uv.x << " " << uv.y;
      }
    }
  }
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
