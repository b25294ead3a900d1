// EXR output: lt_render_write_exr writes every pass as 32-bit float channels; OpenEXR reads back
// the same Combined values (bit for bit; EXR scanlines run top to bottom, the ABI's rows bottom to
// top), a plausible file size, and the render's metadata.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfStringAttribute.h>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "scene_builders.h"

using namespace lt_test;

namespace {

// Reads one FLOAT channel of an EXR into a bottom-to-top buffer.
std::vector<float> read_channel(Imf::InputFile& file, const char* name, int width, int height) {
  const Imath::Box2i dw = file.header().dataWindow();
  std::vector<float> top_down(size_t(width) * height, -12345.0f);
  Imf::FrameBuffer fb;
  char* base = reinterpret_cast<char*>(top_down.data()) - (size_t(dw.min.x) + size_t(dw.min.y) * width) * sizeof(float);
  fb.insert(name, Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * width));
  file.setFrameBuffer(fb);
  file.readPixels(dw.min.y, dw.max.y);
  std::vector<float> out(top_down.size());
  for (int y = 0; y < height; ++y)
    std::memcpy(&out[size_t(height - 1 - y) * width], &top_down[size_t(y) * width], sizeof(float) * width);
  return out;
}

}  // namespace

TEST(ApiExr, WritesEveryPassAndReadsBackTheSameCombined) {
  ScenePtr s = new_scene();
  add_object(s.get(), plane(10, 10), add_diffuse(s.get(), {0.8f, 0.5f, 0.3f}));
  add_object(s.get(), icosphere(0.6f, 3), add_diffuse(s.get(), {0.3f, 0.6f, 0.9f}), translate({0, 0, 0.6f}));
  add_light(s.get(), point_light({1, -1, 2}, 300));
  set_world(s.get(), {0.1f, 0.15f, 0.2f}, 1);
  set_camera(s.get(), perspective_camera(look_at({0, -4, 2}, {0, 0, 0.4f}), 40));
  ASSERT_EQ(lt_scene_commit(s.get()), LT_OK) << lt_last_error();

  const int W = 37, H = 23;  // odd sizes catch row/column mix-ups
  lt_render_settings rs = render_settings(W, H, 8, 77);
  lt_render* raw = nullptr;
  ASSERT_EQ(lt_render_start(s.get(), &rs, &raw), LT_OK) << lt_last_error();
  RenderPtr r(raw);
  ASSERT_EQ(lt_render_wait(r.get()), LT_OK);
  Passes p = read_passes(r.get(), W, H);
  ASSERT_EQ(p.first_non_finite(), "");

  TempDir dir;
  const std::string path = dir.path + "/render.exr";
  ASSERT_EQ(lt_render_write_exr(r.get(), path.c_str()), LT_OK) << lt_last_error();
  ASSERT_TRUE(std::filesystem::exists(path));

  // Size: more than a header, less than the uncompressed channels (4 + 1 + 3 + 3 + 3 + 1 = 15
  // floats per pixel, and the light and data passes: 13 RGB, Position, UV, Mist and the two
  // indices, 48, and the Shadow Catcher pass, 3) plus a generous header and line-offset table.
  const int kChannels = 15 + 48 + 3;
  const auto bytes = std::filesystem::file_size(path);
  EXPECT_GT(bytes, 500u);
  EXPECT_LT(bytes, size_t(W) * H * kChannels * 4 + 16384);

  Imf::InputFile file(path.c_str());
  const Imath::Box2i dw = file.header().dataWindow();
  ASSERT_EQ(dw.max.x - dw.min.x + 1, W);
  ASSERT_EQ(dw.max.y - dw.min.y + 1, H);
  const Imf::ChannelList& channels = file.header().channels();
  int count = 0;
  for (auto it = channels.begin(); it != channels.end(); ++it, ++count)
    EXPECT_EQ(it.channel().type, Imf::FLOAT) << it.name() << " is not 32-bit float";
  EXPECT_EQ(count, kChannels);
  for (const char* name :
       {"R",          "G",           "B",        "A",          "Depth.Z",    "Normal.X",   "Normal.Y",      "Normal.Z",
        "Albedo.R",   "Albedo.G",    "Albedo.B", "Variance.R", "Variance.G", "Variance.B", "SampleCount.X", "DiffDir.R",
        "GlossCol.B", "VolumeInd.G", "Emit.R",   "Env.B",      "Position.X", "UV.U",       "UV.A",          "Mist.Z",
        "IndexOB.X",  "IndexMA.X"})
    EXPECT_NE(channels.findChannel(name), nullptr) << "missing channel " << name;

  const char* rgba[4] = {"R", "G", "B", "A"};
  for (int c = 0; c < 4; ++c) {
    std::vector<float> ch = read_channel(file, rgba[c], W, H);
    int differing = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const float expected = p.rgba(x, y)[c];
        if (std::memcmp(&ch[size_t(y) * W + x], &expected, sizeof(float)) != 0 && differing++ < 5)
          ADD_FAILURE() << rgba[c] << " at (" << x << ", " << y << "): file " << ch[size_t(y) * W + x] << ", render "
                        << expected;
      }
    EXPECT_EQ(differing, 0) << "channel " << rgba[c];
  }
  // The data passes too (spot checks of one channel each).
  std::vector<float> depth = read_channel(file, "Depth.Z", W, H);
  EXPECT_EQ(std::memcmp(depth.data(), p.depth.data(), depth.size() * sizeof(float)), 0) << "Depth.Z differs";
  std::vector<float> count_ch = read_channel(file, "SampleCount.X", W, H);
  for (float v : count_ch) ASSERT_EQ(v, 8.0f);
  std::vector<float> var_g = read_channel(file, "Variance.G", W, H);
  for (int i = 0; i < W * H; ++i) ASSERT_EQ(var_g[i], p.variance[size_t(i) * 3 + 1]) << "Variance.G at " << i;

  const auto* samples = file.header().findTypedAttribute<Imf::StringAttribute>("lantern/samples");
  ASSERT_NE(samples, nullptr);
  EXPECT_EQ(samples->value(), "8");
  const auto* seed = file.header().findTypedAttribute<Imf::StringAttribute>("lantern/seed");
  ASSERT_NE(seed, nullptr);
  EXPECT_EQ(seed->value(), "77");
  // What the image is worth and what stopped it.
  const auto* err = file.header().findTypedAttribute<Imf::StringAttribute>("lantern/rel_error");
  ASSERT_NE(err, nullptr);
  EXPECT_NEAR(std::stod(err->value()), p.status.rel_error, 1e-6 * p.status.rel_error);
  const auto* halt = file.header().findTypedAttribute<Imf::StringAttribute>("lantern/halt_reason");
  ASSERT_NE(halt, nullptr);
  EXPECT_EQ(halt->value(), "samples");
  const auto* integrator = file.header().findTypedAttribute<Imf::StringAttribute>("lantern/integrator");
  ASSERT_NE(integrator, nullptr);
  EXPECT_EQ(integrator->value(), "PATH");
}

TEST(ApiExr, BorderRenderWritesTheRegion) {
  ScenePtr s = new_scene();
  add_object(s.get(), plane(10, 10), add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}));
  add_light(s.get(), sun_light({0.3f, 0.2f, -1}, 2));
  set_camera(s.get(), perspective_camera(look_at({0, -4, 2}, {0, 0, 0}), 35));
  ASSERT_EQ(lt_scene_commit(s.get()), LT_OK);
  lt_render_settings rs = render_settings(40, 30, 2, 5);
  rs.border[0] = 5;
  rs.border[1] = 25;
  rs.border[2] = 3;
  rs.border[3] = 14;
  lt_render* raw = nullptr;
  ASSERT_EQ(lt_render_start(s.get(), &rs, &raw), LT_OK);
  RenderPtr r(raw);
  ASSERT_EQ(lt_render_wait(r.get()), LT_OK);
  Passes p = read_passes(r.get(), 20, 11);
  ASSERT_EQ(p.first_non_finite(), "");
  TempDir dir;
  const std::string path = dir.path + "/border.exr";
  ASSERT_EQ(lt_render_write_exr(r.get(), path.c_str()), LT_OK) << lt_last_error();
  Imf::InputFile file(path.c_str());
  const Imath::Box2i dw = file.header().dataWindow();
  EXPECT_EQ(dw.max.x - dw.min.x + 1, 20);
  EXPECT_EQ(dw.max.y - dw.min.y + 1, 11);
  std::vector<float> g = read_channel(file, "G", 20, 11);
  for (int i = 0; i < 20 * 11; ++i) ASSERT_EQ(g[i], p.combined[size_t(i) * 4 + 1]);
}

TEST(ApiExr, UnwritablePathIsAnIoError) {
  ScenePtr s = new_scene();
  set_camera(s.get(), perspective_camera(identity()));
  ASSERT_EQ(lt_scene_commit(s.get()), LT_OK);
  lt_render_settings rs = render_settings(4, 4, 1);
  lt_render* raw = nullptr;
  ASSERT_EQ(lt_render_start(s.get(), &rs, &raw), LT_OK);
  RenderPtr r(raw);
  ASSERT_EQ(lt_render_wait(r.get()), LT_OK);
  TempDir dir;
  const std::string path = dir.path + "/no/such/directory/out.exr";
  EXPECT_EQ(lt_render_write_exr(r.get(), path.c_str()), LT_ERROR_IO);
  EXPECT_NE(std::string(lt_last_error()).find(path), std::string::npos) << lt_last_error();
  EXPECT_FALSE(std::filesystem::exists(path));
}
