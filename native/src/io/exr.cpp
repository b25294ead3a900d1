#include "io/exr.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>

#include "core/error.h"
#include "core/render.h"

namespace lt {

void write_exr(const std::string& path, int width, int height, const std::vector<ExrChannel>& channels,
               const std::map<std::string, std::string>& attributes) {
  try {
    Imf::Header header(width, height);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const auto& [k, v] : attributes) header.insert(k, Imf::StringAttribute(v));
    Imf::FrameBuffer fb;
    std::vector<std::vector<float>> flipped(channels.size());
    for (size_t c = 0; c < channels.size(); ++c) {
      header.channels().insert(channels[c].name, Imf::Channel(Imf::FLOAT));
      // EXR scanlines run top to bottom; Lantern's buffers bottom to top.
      flipped[c].resize(size_t(width) * height);
      for (int y = 0; y < height; ++y)
        std::copy_n(channels[c].pixels.data() + size_t(height - 1 - y) * width, width, flipped[c].data() + size_t(y) * width);
      fb.insert(channels[c].name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(flipped[c].data()), sizeof(float),
                                             sizeof(float) * width));
    }
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(height);
  } catch (const std::exception& e) {
    throw IoError("could not write " + path + ": " + e.what());
  }
}

void write_render_exr(const std::string& path, const RenderJob& job) {
  const int w = job.region_width(), h = job.region_height();
  const size_t n = size_t(w) * h;
  struct Out { Pass pass; std::vector<std::string> names; };
  const Out outs[] = {
      {Pass::Combined, {"R", "G", "B", "A"}},
      {Pass::Depth, {"Depth.Z"}},
      {Pass::Normal, {"Normal.X", "Normal.Y", "Normal.Z"}},
      {Pass::Albedo, {"Albedo.R", "Albedo.G", "Albedo.B"}},
      {Pass::Variance, {"Variance.R", "Variance.G", "Variance.B"}},
      {Pass::SampleCount, {"SampleCount.X"}},
  };
  std::vector<ExrChannel> channels;
  for (const Out& o : outs) {
    int c = pass_channels(o.pass);
    std::vector<float> buf(n * c);
    job.film().read(o.pass, buf.data());
    for (int k = 0; k < c; ++k) {
      ExrChannel ch;
      ch.name = o.names[k];
      ch.pixels.resize(n);
      for (size_t i = 0; i < n; ++i) ch.pixels[i] = buf[i * c + k];
      channels.push_back(std::move(ch));
    }
  }
  RenderStatus st = job.status();
  std::map<std::string, std::string> attrs = {
      {"lantern/samples", std::to_string(st.samples_done)},
      {"lantern/seed", std::to_string(job.settings().seed)},
      {"lantern/integrator", "path"},
      {"lantern/render_seconds", std::to_string(st.elapsed)},
  };
  write_exr(path, w, h, channels, attrs);
}

}  // namespace lt
