#include "io/image_file.h"

#include <OpenImageIO/imageio.h>

#include <cstring>
#include <vector>

#include "core/error.h"

namespace lt {

namespace {

namespace OIIO = OIIO_NAMESPACE;

// Reads every scanline of channels [0, channels) as `type` into `out`, rows bottom to top (as
// Blender stores images; files store them top to bottom), a few rows per call so that what
// OpenImageIO allocates besides is a few rows' worth.
void read_rows(OIIO::ImageInput& in, const std::string& path, OIIO::TypeDesc type, int channels, void* out) {
  const OIIO::ImageSpec& spec = in.spec();
  const OIIO::stride_t row = OIIO::stride_t(spec.width) * channels * type.size();
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

}  // namespace

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
  // Blender's PNG and single-part OpenEXR loaders are the ones reproduced here.
  if (format != "png" && format != "openexr") throw unsupported(format + " files are loaded by Blender");
  if (w <= 0 || h <= 0 || w > 65536 || h > 65536 || spec.depth != 1 || spec.deep)
    throw unsupported("size " + std::to_string(w) + "x" + std::to_string(h) + " is not supported");
  if (spec.x != 0 || spec.y != 0 || in->seek_subimage(1, 0)) throw unsupported("a data window offset or several parts");
  in->seek_subimage(0, 0);
  const size_t n = size_t(w) * h;
  const bool has_alpha = c == 2 || c == 4;
  const FileAlphaMode mode = r.alpha_mode;
  const bool data = r.space == FileColorSpace::Data;

  if (format == "png" && spec.format == OIIO::TypeDesc::UINT8) {
    if (c < 1 || c > 4) throw unsupported(std::to_string(c) + " channels");
    // Blender unpremultiplies a byte buffer whose alpha mode is Premultiplied (imb_handle_alpha).
    if (has_alpha && mode == FileAlphaMode::Premultiplied && !data)
      throw unsupported("8-bit with Premultiplied alpha mode");
    ByteBuffer px(n * c);
    read_rows(*in, r.path, OIIO::TypeDesc::UINT8, c, px.data());
    return std::make_unique<Image>(w, h, c, std::move(px), r.space == FileColorSpace::Srgb, r.interp, r.ext,
                                   core_alpha(r, false));
  }

  // Float buffers: Blender converts them to scene linear from any other colour space (OCIO).
  if (r.space != FileColorSpace::Linear && !data)
    throw unsupported("a float image in a colour space that Blender converts");
  FloatBuffer px;
  if (format == "png" && spec.format == OIIO::TypeDesc::UINT16) {
    if (c != 1 && c != 3 && c != 4) throw unsupported(std::to_string(c) + " channels of 16 bits");
    // The 16-bit values in the buffer's second half, converted forwards in place into floats as
    // Blender's png.c does (v / 65535.0 in double): float i overwrites only values already read.
    px = FloatBuffer(n * c);
    uint16_t* v = reinterpret_cast<uint16_t*>(px.data()) + n * c;
    read_rows(*in, r.path, OIIO::TypeDesc::UINT16, c, v);
    for (size_t i = 0; i < n * c; ++i) {
      uint16_t u;
      std::memcpy(&u, v + i, sizeof u);
      px[i] = float(u / 65535.0);
    }
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

}  // namespace lt
