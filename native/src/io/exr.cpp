#include "io/exr.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "core/error.h"
#include "render/render.h"

namespace lt {

const ExrChannel* ExrImage::find(const std::string& name) const {
  for (const ExrChannel& c : channels)
    if (c.name == name) return &c;
  return nullptr;
}

void write_exr(const std::string& path, int width, int height, const std::vector<ExrChannel>& channels,
               const std::map<std::string, std::string>& attributes) {
  // A unique temporary name in the same directory (rename is atomic only within a file system).
  const std::string tmp = path + ".tmp" + std::to_string(std::random_device{}());
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
        std::copy_n(channels[c].pixels.data() + size_t(height - 1 - y) * width, width,
                    flipped[c].data() + size_t(y) * width);
      fb.insert(channels[c].name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(flipped[c].data()), sizeof(float),
                                             sizeof(float) * width));
    }
    {
      Imf::OutputFile file(tmp.c_str(), header);
      file.setFrameBuffer(fb);
      file.writePixels(height);
    }
    std::filesystem::rename(tmp, path);
  } catch (const std::exception& e) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw IoError("could not write " + path + ": " + e.what());
  }
}

namespace {

// OpenEXR 3.1 allocates what an attribute's size field says before it reads the value, so a
// corrupt or hostile file made a merge allocate gigabytes before failing (found by
// tests/fuzz/fuzz_exr_merge). The headers are walked here first, and a size that runs past the end
// of the file is refused. OpenEXR reads a known type by its own layout whatever the size field says
// (Header::readFrom, TypedAttribute<T>::readValueFrom): a channel list to its empty name, a
// preview by its width and height, a fixed-size type by its size, a string vector string by
// string; the walk does the same, or it would lose step where OpenEXR does (fuzz_exr_merge: a
// channel list shorter than its size made OpenEXR read a 1.8 GB string from what followed).
// Anything else wrong is left to OpenEXR's own messages.
void check_attribute_sizes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return;
  f.seekg(0, std::ios::end);
  const std::streamoff file_size = f.tellg();
  f.seekg(0);
  auto u32 = [&f]() {
    unsigned char b[4] = {0, 0, 0, 0};
    f.read(reinterpret_cast<char*>(b), 4);
    return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
  };
  auto truncated = [&path]() { throw IoError("could not read " + path + ": the header is truncated"); };
  // A NUL-terminated name (at most 255 characters with long names, 31 without).
  auto name = [&]() {
    std::string s;
    for (char c; f.get(c) && c != '\0';) {
      if (s.size() == 255) throw IoError("could not read " + path + ": a header name is longer than 255 characters");
      s += c;
    }
    if (!f) truncated();
    return s;
  };
  // Skips n bytes of attribute attr's value, refused when they run past the end of the file.
  auto skip = [&](const std::string& attr, int64_t n) {
    if (!f) truncated();
    const std::streamoff left = file_size - f.tellg();
    if (n < 0 || n > left)
      throw IoError("could not read " + path + ": header attribute '" + attr + "' claims " + std::to_string(n) +
                    " bytes, but the file has " + std::to_string(left) + " left");
    f.seekg(std::streamoff(n), std::ios::cur);
  };
  static const std::map<std::string, int> kFixed = {{"box2i", 16},
                                                    {"box2f", 16},
                                                    {"chromaticities", 32},
                                                    {"compression", 1},
                                                    {"deepImageState", 1},
                                                    {"double", 8},
                                                    {"envmap", 1},
                                                    {"float", 4},
                                                    {"int", 4},
                                                    {"keycode", 28},
                                                    {"lineOrder", 1},
                                                    {"m33f", 36},
                                                    {"m33d", 72},
                                                    {"m44f", 64},
                                                    {"m44d", 128},
                                                    {"rational", 8},
                                                    {"tiledesc", 9},
                                                    {"timecode", 8},
                                                    {"v2i", 8},
                                                    {"v2f", 8},
                                                    {"v2d", 16},
                                                    {"v3i", 12},
                                                    {"v3f", 12},
                                                    {"v3d", 24}};
  if (u32() != 20000630u) return;  // not OpenEXR: OpenEXR says so
  const bool multipart = (u32() & 0x1000u) != 0;
  if (!f) return;
  for (;;) {
    for (std::string attr = name(); !attr.empty(); attr = name()) {
      const std::string type = name();
      const int64_t size = int32_t(u32());
      const auto fixed = kFixed.find(type);
      if (fixed != kFixed.end()) {
        skip(attr, fixed->second);
      } else if (type == "chlist") {
        while (!name().empty()) skip(attr, 16);  // pixel type, pLinear, 3 reserved, x and y sampling
      } else if (type == "preview") {
        const int64_t w = u32(), h = u32();
        skip(attr, 4 * w * h);
      } else if (type == "stringvector") {
        for (int64_t read = 0; read < size;) {
          const int64_t n = int32_t(u32());
          skip(attr, n);
          read += 4 + n;
        }
      } else {
        skip(attr, size);
      }
    }
    if (!multipart || f.peek() == 0 || f.peek() == std::char_traits<char>::eof()) return;
  }
}

}  // namespace

ExrImage read_exr(const std::string& path, bool pixels) {
  check_attribute_sizes(path);
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& h = file.header();
    const Imath::Box2i dw = h.dataWindow();
    ExrImage img;
    img.width = dw.max.x - dw.min.x + 1;
    img.height = dw.max.y - dw.min.y + 1;
    for (auto it = h.begin(); it != h.end(); ++it)
      if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
        img.attributes[it.name()] = s->value();
    for (auto it = h.channels().begin(); it != h.channels().end(); ++it) img.channels.push_back({it.name(), {}});
    if (!pixels) return img;
    std::vector<std::vector<float>> top_down(img.channels.size(), std::vector<float>(size_t(img.width) * img.height));
    Imf::FrameBuffer fb;
    for (size_t c = 0; c < img.channels.size(); ++c) {
      char* base = reinterpret_cast<char*>(top_down[c].data()) -
                   (ptrdiff_t(dw.min.x) + ptrdiff_t(dw.min.y) * img.width) * ptrdiff_t(sizeof(float));
      fb.insert(img.channels[c].name, Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * img.width));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    for (size_t c = 0; c < img.channels.size(); ++c) {
      auto& out = img.channels[c].pixels;
      out.resize(top_down[c].size());
      for (int y = 0; y < img.height; ++y)
        std::copy_n(top_down[c].data() + size_t(y) * img.width, img.width,
                    out.data() + size_t(img.height - 1 - y) * img.width);
    }
    return img;
  } catch (const std::exception& e) {
    throw IoError("could not read " + path + ": " + e.what());
  }
}

namespace {
void add_channels(std::vector<ExrChannel>& channels, const std::vector<float>& buf, size_t n,
                  const std::vector<std::string>& names) {
  const size_t c = names.size();
  for (size_t k = 0; k < c; ++k) {
    ExrChannel ch{names[k], std::vector<float>(n)};
    for (size_t i = 0; i < n; ++i) ch.pixels[i] = buf[i * c + k];
    channels.push_back(std::move(ch));
  }
}
}  // namespace

void write_render_exr(const std::string& path, const RenderJob& job, const std::map<std::string, std::string>& extra) {
  const int w = job.region_width(), h = job.region_height();
  const size_t n = size_t(w) * h;
  struct Out {
    Pass pass;
    std::vector<std::string> names;
  };
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
    std::vector<float> buf(n * pass_channels(o.pass));
    // Parts hold the image as rendered, so that merging them stays exact (a merge is not denoised).
    const Pass pass = o.pass == Pass::Combined && job.film().has(Pass::NoisyImage) ? Pass::NoisyImage : o.pass;
    job.film().read(pass, buf.data());
    add_channels(channels, buf, n, o.names);
  }
  // The light and data passes the film keeps, under Blender's names (merge.cpp knows which are
  // divided by a Colour and which hold the first sample's value).
  for (int p = kFirstSummedPass; p < int(Pass::Count); ++p) {
    if (!job.film().has(Pass(p))) continue;
    std::vector<float> buf(n * pass_channels(Pass(p)));
    job.film().read(Pass(p), buf.data());
    std::vector<std::string> names;
    for (const char* c = exr_channel_letters(Pass(p)); *c; ++c)
      names.push_back(std::string(exr_pass_name(Pass(p))) + "." + *c);
    add_channels(channels, buf, n, names);
    // The Vector pass is a mean over the samples that wrote one: their share, for merges.
    if (Pass(p) == Pass::Vector && job.film().read_vector_coverage(buf.data()))
      add_channels(channels, buf, n, {"VectorCoverage.X"});
    // BDPT: the splats' part apart, as for Combined, so that merges stay exact (merge.cpp).
    if (is_light_pass(Pass(p)) && job.film().read_light_tracing(Pass(p), buf.data()))
      add_channels(channels, buf, n,
                   {std::string("LightTracing.") + exr_pass_name(Pass(p)) + ".R",
                    std::string("LightTracing.") + exr_pass_name(Pass(p)) + ".G",
                    std::string("LightTracing.") + exr_pass_name(Pass(p)) + ".B"});
  }
  // Cryptomatte layers under Cycles' pass names (CryptoObject00.r = id, .g = coverage, ...); the
  // manifests come from the caller's attributes (cryptomatte/<key>/..., the specification's).
  for (int t = 0; t < kCryptoTypes; ++t) {
    if (!job.film().has_cryptomatte(t)) continue;
    std::vector<float> buf(n * 4);
    for (int layer = 0; 2 * layer < job.film().layout().cryptomatte_slots(); ++layer) {
      job.film().read_cryptomatte_rows(t, layer, 0, h, buf.data());
      char prefix[32];
      std::snprintf(prefix, sizeof prefix, "%s%02d.", cryptomatte_type_name(t), layer);
      // Lower case, as the specification and Blender name them.
      add_channels(
          channels, buf, n,
          {std::string(prefix) + "r", std::string(prefix) + "g", std::string(prefix) + "b", std::string(prefix) + "a"});
    }
  }
  // Light groups as Cycles names them (Combined_<name>), their splats' part apart (BDPT).
  for (int g = 0; g < job.film().lightgroups(); ++g) {
    const std::string name = "Combined_" + job.settings().lightgroup_names[size_t(g)];
    std::vector<float> buf(n * 3);
    job.film().read_lightgroup_rows(g, 0, h, buf.data());
    add_channels(channels, buf, n, {name + ".R", name + ".G", name + ".B"});
    if (job.film().read_lightgroup_light_tracing(g, buf.data()))
      add_channels(channels, buf, n,
                   {"LightTracing." + name + ".R", "LightTracing." + name + ".G", "LightTracing." + name + ".B"});
  }
  // Shader AOVs: a colour's RGBA, a value's X (Blender's channels for them).
  for (int a = 0; a < job.film().aovs(); ++a) {
    const std::string& name = job.settings().aov_names[size_t(a)];
    const bool colour = job.settings().aov_colors[size_t(a)];
    std::vector<float> buf(n * (colour ? 4 : 1));
    job.film().read_aov_rows(a, colour ? 4 : 1, 0, h, buf.data());
    if (colour)
      add_channels(channels, buf, n, {name + ".R", name + ".G", name + ".B", name + ".A"});
    else
      add_channels(channels, buf, n, {name + ".X"});
  }
  // Shadow catchers: the means Combined and the Shadow Catcher pass are read from (film.h), so that
  // merges recompute both exactly.
  for (int part = 0; part < kCatcherParts; ++part) {
    const std::string letters = catcher_part_letters(part);
    std::vector<float> buf(n * letters.size());
    if (!job.film().read_catcher_part(part, buf.data())) break;
    std::vector<std::string> names;
    for (char c : letters) names.push_back(std::string(catcher_part_name(part)) + "." + c);
    add_channels(channels, buf, n, names);
  }
  std::vector<float> light(n * 3);
  if (job.film().read_light_tracing(light.data()))
    add_channels(channels, light, n, {"LightTracing.R", "LightTracing.G", "LightTracing.B"});
  RenderStatus st = job.status();
  const RenderSettings& s = job.settings();
  std::map<std::string, std::string> attrs = extra;
  // The sample indices used (a cut last pass included; per-pixel counts are in SampleCount) and
  // the light paths the splats are divided by, so that merges of such parts stay exact.
  attrs["lantern/samples"] = std::to_string(st.passes_started);
  attrs["lantern/sample_ranges"] =
      std::to_string(s.sample_offset) + "-" + std::to_string(s.sample_offset + st.passes_started);
  if (uint64_t lp = job.film().published_light_paths()) attrs["lantern/light_paths"] = std::to_string(lp);
  attrs["lantern/seed"] = std::to_string(s.seed);
  if (job.film().layout().shadow_catcher) {
    attrs["lantern/shadow_catcher"] = s.integrator_settings.shadow_catcher_approximate ? "approximate" : "matte";
    attrs["lantern/transparent"] = s.integrator_settings.transparent_background ? "1" : "0";
  }
  attrs["lantern/integrator"] = integrator_name(s.integrator);
  attrs["lantern/sample_pattern"] = s.pattern == SamplePattern::SobolOwen ? "SOBOL_OWEN" : "INDEPENDENT";
  attrs["lantern/resolution"] = std::to_string(s.width) + "x" + std::to_string(s.height);
  attrs["lantern/region"] =
      std::to_string(s.x0) + " " + std::to_string(s.y0) + " " + std::to_string(s.x1) + " " + std::to_string(s.y1);
  char secs[32];
  std::snprintf(secs, sizeof(secs), "%.3f", st.elapsed);
  attrs["lantern/render_seconds"] = secs;
  // The halting settings, what stopped the render and its estimated error (lantern.h,
  // lt_render_status.rel_error): what the image is worth, kept with it.
  static const char* const kHalts[] = {"running", "samples", "time_limit", "noise_target", "cancelled", "failed"};
  auto num = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.9g", v);
    return std::string(b);
  };
  attrs["lantern/rel_error"] = num(st.rel_error);
  attrs["lantern/halt_reason"] = kHalts[int(st.halt_reason)];
  attrs["lantern/max_samples"] = std::to_string(s.samples);
  attrs["lantern/time_limit"] = num(s.time_limit);
  attrs["lantern/noise_target"] = num(s.noise_target);
  attrs["lantern/adaptive"] = s.adaptive ? "1" : "0";
  attrs["lantern/min_samples"] = std::to_string(s.min_samples);
  write_exr(path, w, h, channels, attrs);
}

}  // namespace lt
