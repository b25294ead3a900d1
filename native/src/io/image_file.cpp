#include "io/image_file.h"

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "core/error.h"
#include "io/color_space.h"

namespace lt {

namespace {

namespace OIIO = OIIO_NAMESPACE;

// Reads every scanline of channels [0, channels) as `type` into `out`, rows bottom to top (as
// Blender stores images; files store them top to bottom), a few rows per call so that what
// OpenImageIO allocates besides is a few rows' worth.
void read_rows(OIIO::ImageInput& in, const std::string& path, OIIO::TypeDesc type, int channels, void* out) {
  const OIIO::ImageSpec& spec = in.spec();
  const OIIO::stride_t row = OIIO::stride_t(spec.width) * channels * type.size();
  if (spec.tile_width != 0) {
    // Tiles a row of tiles at a time (OpenImageIO 2.4's read_scanlines on a tiled TIFF divides by
    // zero).
    char* top = static_cast<char*>(out) + (spec.height - 1) * row;
    if (!in.read_image(0, 0, 0, channels, type, top, OIIO::AutoStride, -row))
      throw IoError("cannot read image '" + path + "': " + in.geterror());
    return;
  }
  constexpr int kRows = 64;
  for (int y = 0; y < spec.height; y += kRows) {
    const int end = std::min(spec.height, y + kRows);
    char* first = static_cast<char*>(out) + (spec.height - 1 - y) * row;  // file row y
    if (!in.read_scanlines(0, 0, y, end, 0, 0, channels, type, first, OIIO::AutoStride, -row))
      throw IoError("cannot read image '" + path + "': " + in.geterror());
  }
}

ImageAlpha core_alpha(const ImageFileRequest& r, bool premultiplied) {
  if (!r.use_alpha || r.alpha_mode == FileAlphaMode::None) return ImageAlpha::Ignore;
  if (r.alpha_mode == FileAlphaMode::ChannelPacked || r.space == FileColorSpace::Data) return ImageAlpha::ChannelPacked;
  return premultiplied ? ImageAlpha::Premultiplied : ImageAlpha::Straight;
}

// An integer attribute of the file (0 when absent).
int int_attribute(const OIIO::ImageSpec& spec, const char* name) { return spec.get_int_attribute(name, 0); }

// The TGA header's fields Blender's targa.c and OpenImageIO might read differently: only
// uncompressed or RLE true-colour or grey images of 8, 24 or 32 bits without a colour map, stored
// left to right, with an alpha size that matches the pixel size, are taken.
std::string targa_refusal(const std::string& path) {
  unsigned char h[18];
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return "cannot be opened";
  const size_t got = std::fread(h, 1, sizeof h, f);
  std::fclose(f);
  if (got != sizeof h) return "a truncated header";
  const int type = h[2], bits = h[16], alpha_bits = h[17] & 0x0f;
  if (h[1] != 0 || (type != 2 && type != 3 && type != 10 && type != 11)) return "a colour-mapped TGA";
  if (bits != 8 && bits != 24 && bits != 32) return std::to_string(bits) + "-bit TGA pixels";
  if (alpha_bits != (bits == 32 ? 8 : 0)) return "a TGA alpha of " + std::to_string(alpha_bits) + " bits";
  if (h[17] & 0x10) return "a right-to-left TGA";
  return "";
}

// What of a file Blender's loaders (imbuf's jpeg.c, tiff.c, targa.c) would read differently from
// OpenImageIO, or "" (PNG and OpenEXR are checked by the readers below).
std::string format_refusal(OIIO::ImageInput& in, const std::string& path) {
  const OIIO::ImageSpec& spec = in.spec();
  const std::string format = in.format_name();
  const int c = spec.nchannels;
  if (format == "jpeg") {
    // CMYK and YCCK (which OpenImageIO converts to RGB and names in jpeg:ColorSpace): Blender's own
    // conversion (and its alpha from K) is not OpenImageIO's.
    if (c != 1 && c != 3) return std::to_string(c) + "-channel JPEG";
    if (const std::string space = spec.get_string_attribute("jpeg:ColorSpace"); !space.empty())
      return "a " + space + " JPEG";
  } else if (format == "tiff") {
    // Blender reads 8-bit TIFFs with libtiff's TIFFReadRGBAImage (which applies the orientation
    // and expands palettes its way) and 16 and 32-bit ones scanline by scanline.
    const int photometric = int_attribute(spec, "tiff:PhotometricInterpretation");
    if (!((photometric == 1 && c == 1) || (photometric == 2 && (c == 3 || c == 4))))
      return "TIFF photometric " + std::to_string(photometric) + " with " + std::to_string(c) + " channels";
    if (spec.get_int_attribute("Orientation", 1) != 1) return "a TIFF orientation";
    const int bits = int_attribute(spec, "oiio:BitsPerSample");
    // Tiles and separate planes are only a layout for TIFFReadRGBAImage (8 bits; measured equal),
    // but Blender 3.4 loads no pixels from a tiled grey or RGB TIFF (measured), and its 16 and
    // 32-bit readers take neither.
    if (spec.tile_width != 0 && (bits != 8 || c != 4)) return "a tiled TIFF of " + std::to_string(c) + " channels";
    if (int_attribute(spec, "tiff:PlanarConfiguration") != 1 && bits != 8) return "a TIFF with separate planes";
    const bool ok = (bits == 8 && spec.format == OIIO::TypeDesc::UINT8) ||
                    (bits == 16 && spec.format == OIIO::TypeDesc::UINT16) ||
                    (bits == 32 && spec.format == OIIO::TypeDesc::FLOAT);
    if (!ok || !spec.channelformats.empty()) return std::to_string(bits) + "-bit " + spec.format.c_str() + " TIFF";
  } else if (format == "targa") {
    return targa_refusal(path);
  }
  return "";
}

// Bytes of a file through a small buffer (Radiance files are read in one pass).
class ByteReader {
 public:
  explicit ByteReader(const std::string& path) : f_(std::fopen(path.c_str(), "rb")), buf_(1 << 16) {}
  ~ByteReader() {
    if (f_) std::fclose(f_);
  }
  ByteReader(const ByteReader&) = delete;
  ByteReader& operator=(const ByteReader&) = delete;
  bool open() const { return f_ != nullptr; }
  // The next byte, or -1 at the end of the file.
  int next() {
    if (pos_ == end_) {
      end_ = std::fread(buf_.data(), 1, buf_.size(), f_);
      pos_ = 0;
      if (end_ == 0) return -1;
    }
    return buf_[pos_++];
  }

 private:
  std::FILE* f_;
  std::vector<unsigned char> buf_;
  size_t pos_ = 0, end_ = 0;
};

// Blender's RGBE to float (radiance_hdr.c, RGBE2FLOAT): Ward's (m + 0.5) 2^(e - 136), which
// OpenImageIO's reader (m 2^(e - 136)) is not.
inline float rgbe_value(int m, int e) {
  if (e == 0) return 0.0f;
  const float f = float(std::ldexp(1.0, e - 136));
  return f * (float(m) + 0.5f);
}

// Blender 3.4's IMB_unpremultiply_rect on n texels of c channels (the last one alpha), in place:
// each colour byte becomes unit_float_to_uchar_clamp(b * (1 / a)), with 1 for a = 0 (so that a
// transparent texel's colours become 255 where not 0), in single-precision floats as Blender's.
void unpremultiply_bytes(uint8_t* p, size_t n, int c) {
  auto unit_to_byte = [](float v) {
    return v <= 0.0f ? uint8_t(0) : v > 1.0f - 0.5f / 255.0f ? uint8_t(255) : uint8_t(255.0f * v + 0.5f);
  };
  for (size_t i = 0; i < n; ++i) {
    uint8_t* t = p + i * c;
    const float inv = t[c - 1] != 0 ? 1.0f / float(t[c - 1]) : 1.0f;
    for (int k = 0; k < c - 1; ++k) t[k] = unit_to_byte(float(t[k]) * inv);
  }
}

}  // namespace

// Radiance RGBE files decoded as Blender 3.4's radiance_hdr.c decodes them (header up to the first
// empty line, "-Y h +X w" or "+Y h +X w", new run-length scanlines or old flat ones with old runs),
// into RGB floats (12 bytes per texel). What Blender would read differently or not at all (other
// orientations, irregular run lengths) is left to it (ImageFileUnsupported); truncated files are an
// IoError, for the caller to load through Blender, which reports them.
std::unique_ptr<Image> read_radiance(const ImageFileRequest& r) {
  auto unsupported = [&](const std::string& why) { return ImageFileUnsupported("image '" + r.path + "': " + why); };
  auto corrupt = [&](const std::string& why) { return IoError("cannot read image '" + r.path + "': " + why); };
  if (r.space != FileColorSpace::Linear && r.space != FileColorSpace::Data)
    throw unsupported("a float image in a colour space that Blender converts");
  ByteReader in(r.path);
  if (!in.open()) throw IoError("cannot open image '" + r.path + "'");
  auto line = [&](std::string* s) {
    s->clear();
    for (int b; (b = in.next()) != '\n';) {
      if (b < 0 || s->size() > 4096) return false;
      s->push_back(char(b));
    }
    return true;
  };
  std::string text;
  if (!line(&text) || text.compare(0, 2, "#?") != 0) throw unsupported("not a Radiance file");
  do {
    if (!line(&text)) throw corrupt("no end of header");
  } while (!text.empty());
  if (!line(&text)) throw corrupt("no resolution");
  char y_axis[8], x_axis[8], rest;
  int w = 0, h = 0;
  if (std::sscanf(text.c_str(), "%7s %d %7s %d %c", y_axis, &h, x_axis, &w, &rest) != 4 ||
      (std::strcmp(y_axis, "-Y") != 0 && std::strcmp(y_axis, "+Y") != 0) || std::strcmp(x_axis, "+X") != 0)
    throw unsupported("resolution line '" + text + "'");
  if (w <= 0 || h <= 0 || w > 65536 || h > 65536)
    throw unsupported("size " + std::to_string(w) + "x" + std::to_string(h));
  const bool top_down = y_axis[0] == '-';  // Blender flips these: file rows run top to bottom

  FloatBuffer px(size_t(w) * h * 3);
  std::vector<unsigned char> scan(size_t(w) * 4);
  auto byte = [&] {
    const int b = in.next();
    if (b < 0) throw corrupt("truncated pixels");
    return (unsigned char)b;
  };
  for (int row = 0; row < h; ++row) {
    unsigned char first[4];
    for (auto& b : first) b = byte();
    if (w >= 8 && w <= 0x7fff && first[0] == 2) {
      // Run-length scanline: the 4 components apart, each as runs (count > 128) or literals.
      if (first[1] != 2 || ((first[2] << 8) | first[3]) != w) throw unsupported("an irregular scanline header");
      for (int k = 0; k < 4; ++k)
        for (int x = 0; x < w;) {
          int code = byte();
          const bool run = code > 128;
          if (run) code &= 127;
          if (x + code > w) throw corrupt("a run past the scanline");
          const unsigned char v = run ? byte() : 0;
          for (; code > 0; --code) scan[size_t(x++) * 4 + k] = run ? v : byte();
        }
    } else {
      // Flat pixels; (1, 1, 1, n) repeats the previous pixel n << shift times (shift grows by 8
      // for consecutive repeats).
      int x = 0, shift = 0;
      for (bool have = true; x < w; have = false) {
        unsigned char p[4];
        for (int k = 0; k < 4; ++k) p[k] = have ? first[k] : byte();
        if (p[0] == 1 && p[1] == 1 && p[2] == 1) {
          const long n = long(p[3]) << shift;
          if (x == 0 || x + n > w) throw unsupported("an irregular old-style run");
          for (long i = 0; i < n; ++i, ++x) std::memcpy(&scan[size_t(x) * 4], &scan[size_t(x - 1) * 4], 4);
          shift += 8;
        } else {
          std::memcpy(&scan[size_t(x++) * 4], p, 4);
          shift = 0;
        }
      }
    }
    float* out = px.data() + size_t(top_down ? h - 1 - row : row) * w * 3;
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < 3; ++k) out[3 * x + k] = rgbe_value(scan[4 * size_t(x) + k], scan[4 * size_t(x) + 3]);
  }
  return std::make_unique<Image>(w, h, 3, std::move(px), false, r.interp, r.ext, ImageAlpha::Ignore);
}

std::unique_ptr<Image> read_image_file(const ImageFileRequest& r) {
  OIIO::ImageSpec config;
  // Straight alpha as the file stores it (OpenImageIO would associate PNG's), as Cycles asks.
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(r.path, &config);
  if (!in) throw IoError("cannot open image '" + r.path + "': " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  const std::string format = in->format_name();
  const int w = spec.width, h = spec.height, c = spec.nchannels;
  auto unsupported = [&](const std::string& why) { return ImageFileUnsupported("image '" + r.path + "': " + why); };
  // Blender's PNG, JPEG, TIFF, TGA, Radiance HDR and single-part OpenEXR loaders are the ones
  // reproduced here (HDR by read_radiance: OpenImageIO decodes RGBE differently).
  if (format == "hdr") {
    in.reset();
    return read_radiance(r);
  }
  if (format != "png" && format != "openexr" && format != "jpeg" && format != "tiff" && format != "targa")
    throw unsupported(format + " files are loaded by Blender");
  if (const std::string why = format_refusal(*in, r.path); !why.empty()) throw unsupported(why);
  if (w <= 0 || h <= 0 || w > 65536 || h > 65536 || spec.depth != 1 || spec.deep)
    throw unsupported("size " + std::to_string(w) + "x" + std::to_string(h) + " is not supported");
  if (spec.x != 0 || spec.y != 0 || in->seek_subimage(1, 0)) throw unsupported("a data window offset or several parts");
  in->seek_subimage(0, 0);
  const size_t n = size_t(w) * h;
  const bool has_alpha = c == 2 || c == 4;
  const FileAlphaMode mode = r.alpha_mode;
  const bool data = r.space == FileColorSpace::Data;

  if (spec.format == OIIO::TypeDesc::UINT8 && format != "openexr" && r.space == FileColorSpace::Other &&
      !r.ocio_space.empty()) {
    // Cycles reads an 8-bit file in another colour space as half floats and converts them to scene
    // linear (ImageMetaData::detect_colorspace): held so, 2 bytes per channel.
    if (c != 1 && c != 3) throw unsupported("an 8-bit file with alpha in colour space '" + r.ocio_space + "'");
    HalfBuffer px(n * c);
    read_rows(*in, r.path, OIIO::TypeDesc::HALF, c, px.data());
    halves_to_scene_linear(r.ocio_config, r.ocio_space, px.data(), n, c);
    return std::make_unique<Image>(w, h, c, std::move(px), r.interp, r.ext, ImageAlpha::Ignore);
  }
  if (spec.format == OIIO::TypeDesc::UINT8 && format != "openexr") {
    if (c < 1 || c > 4) throw unsupported(std::to_string(c) + " channels");
    ByteBuffer px(n * c);
    read_rows(*in, r.path, OIIO::TypeDesc::UINT8, c, px.data());
    // Blender unpremultiplies a byte buffer whose alpha mode is Premultiplied (imb_handle_alpha),
    // which then holds straight colours as any other byte image.
    if (has_alpha && mode == FileAlphaMode::Premultiplied && !data) unpremultiply_bytes(px.data(), n, c);
    return std::make_unique<Image>(w, h, c, std::move(px), r.space == FileColorSpace::Srgb, r.interp, r.ext,
                                   core_alpha(r, false));
  }

  // Float buffers: Blender converts them to scene linear from any other colour space (OCIO).
  if (r.space != FileColorSpace::Linear && !data)
    throw unsupported("a float image in a colour space that Blender converts");
  FloatBuffer px;
  if ((format == "png" || format == "tiff") && spec.format == OIIO::TypeDesc::UINT16) {
    if (c != 1 && c != 3 && c != 4) throw unsupported(std::to_string(c) + " channels of 16 bits");
    // The 16-bit values in the buffer's second half, converted forwards in place into floats as
    // Blender's png.c and tiff.c do (v / 65535.0): float i overwrites only values already read.
    px = FloatBuffer(n * c);
    uint16_t* v = reinterpret_cast<uint16_t*>(px.data()) + n * c;
    read_rows(*in, r.path, OIIO::TypeDesc::UINT16, c, v);
    for (size_t i = 0; i < n * c; ++i) {
      uint16_t u;
      std::memcpy(&u, v + i, sizeof u);
      px[i] = float(u / 65535.0);
    }
  } else if (format == "tiff" && spec.format == OIIO::TypeDesc::FLOAT) {
    px = FloatBuffer(n * c);  // Blender's tiff.c copies the floats as they are
    read_rows(*in, r.path, OIIO::TypeDesc::FLOAT, c, px.data());
  } else if (format == "openexr") {
    // Blender reads R, G, B and A (1 when missing) of a single-layer file.
    static const char* kNames[] = {"R", "G", "B", "A"};
    bool rgba = c == 3 || c == 4;
    for (int k = 0; k < c && rgba; ++k) rgba = spec.channelnames[k] == kNames[k];
    if (!rgba) throw unsupported("OpenEXR channels other than R, G, B(, A)");
    // Half files stay half (their texels are the same floats), unless Blender would premultiply
    // them in float (Straight alpha mode).
    const bool premultiply = c == 4 && !data && mode == FileAlphaMode::Straight;
    if (spec.format == OIIO::TypeDesc::HALF && spec.channelformats.empty() && !premultiply) {
      HalfBuffer halfs(n * c);
      read_rows(*in, r.path, OIIO::TypeDesc::HALF, c, halfs.data());
      return std::make_unique<Image>(w, h, c, std::move(halfs), r.interp, r.ext, core_alpha(r, true));
    }
    px = FloatBuffer(n * c);
    read_rows(*in, r.path, OIIO::TypeDesc::FLOAT, c, px.data());
  } else {
    throw unsupported(std::string("pixel format ") + spec.format.c_str());
  }
  in->close();
  // imb_handle_alpha: data and channel-packed images are left alone, None makes them opaque (the
  // core then ignores alpha), Premultiplied floats are kept and Straight ones premultiplied.
  if (c == 4 && !data && mode == FileAlphaMode::Straight)
    for (size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) px[4 * i + k] *= px[4 * i + 3];
  return std::make_unique<Image>(w, h, c, std::move(px), false, r.interp, r.ext, core_alpha(r, true));
}

std::unique_ptr<Image> byte_image_to_scene_linear(int width, int height, int channels, FloatBuffer pixels,
                                                  ImageAlpha alpha, Interpolation interp, Extension ext,
                                                  const std::string& ocio_config, const std::string& ocio_space) {
  const size_t n = size_t(width) * height;
  const bool rgba = channels == 4, associate = alpha == ImageAlpha::Straight || alpha == ImageAlpha::Premultiplied;
  HalfBuffer px(n * size_t(channels));
  for (size_t i = 0; i < n; ++i) {
    const float* v = &pixels[i * size_t(channels)];
    uint16_t* h = &px[i * size_t(channels)];
    const float a = !rgba || alpha == ImageAlpha::Ignore ? 1.0f : v[3];
    for (int k = 0; k < (rgba ? 3 : channels); ++k) h[k] = cycles_float_to_half(associate ? v[k] * a : v[k]);
    if (rgba) h[3] = cycles_float_to_half(a);
  }
  pixels.reset();
  halves_to_scene_linear(ocio_config, ocio_space, px.data(), n, channels);
  // Straight colours are associated now (never Straight for halves: Image's constructor).
  const ImageAlpha held = alpha == ImageAlpha::Straight ? ImageAlpha::Premultiplied : alpha;
  return std::make_unique<Image>(width, height, channels, std::move(px), interp, ext, held);
}

}  // namespace lt
