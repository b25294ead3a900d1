// Image files read by the core itself (OpenImageIO; Radiance files by read_radiance), as Cycles
// reads them, so that Blender never loads the pixels and they are held once, at the file's
// precision (8-bit PNG, JPEG, TIFF and TGA files as bytes, half OpenEXR files as half floats unless
// Blender would premultiply them, 16-bit PNG and TIFF, float OpenEXR and Radiance files as float).
// The texels are exactly those the add-on would get from Blender 3.4's Image.pixels for the same
// image datablock: what Blender's loader does to them (imbuf's png.c, jpeg.c, tiff.c, targa.c,
// radiance_hdr.c, openexr_api.cpp and imb_handle_alpha) is done here, and files for which that
// would need Blender's colour management (a float file in a colour space other than Linear or a
// data space), or that its loaders read their own way (CMYK JPEG, TIFF palettes and orientations,
// tiled grey or RGB TIFFs, colour-mapped and 16-bit TGA, ...) are refused (ImageFileUnsupported)
// for the caller to load through Blender; 8-bit buffers Blender unpremultiplies are unpremultiplied
// here as it does.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

#include "shading/image.h"

namespace lt {

// The image datablock's colour space: sRGB, the scene-linear Linear, a data space (Non-Color,
// Raw: is_data), or another: ocio_space of ocio_config (io/color_space.h; without them, byte values
// are used as they are).
enum class FileColorSpace { Srgb, Linear, Data, Other };
// Blender's Image.alpha_mode.
enum class FileAlphaMode { Straight, Premultiplied, ChannelPacked, None };

struct ImageFileRequest {
  std::string path;
  FileColorSpace space = FileColorSpace::Srgb;
  FileAlphaMode alpha_mode = FileAlphaMode::Straight;
  bool use_alpha = false;  // the texture's alpha is read (image textures); else dropped
  Interpolation interp = Interpolation::Linear;
  Extension ext = Extension::Repeat;
  std::string ocio_config, ocio_space;  // FileColorSpace::Other
};

// A file this reader does not take (the caller loads it another way); the message says why.
struct ImageFileUnsupported : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Reads the file (throws IoError when it cannot be opened or read, ImageFileUnsupported as above).
std::unique_ptr<Image> read_image_file(const ImageFileRequest& request);
// A Radiance (.hdr) file, decoded as Blender does (read_image_file calls it for them).
std::unique_ptr<Image> read_radiance(const ImageFileRequest& request);

// A byte image Blender holds in another colour space (packed, generated, or a file it loads), given
// as Image.pixels gives it (channels 1, 3 or 4 floats b / 255), converted as Cycles 3.4 loads it
// from Blender (blender/image.cpp's half pixels, the colours associated with alpha unless alpha is
// Ignore or ChannelPacked, an ignored alpha set to 1; then halves_to_scene_linear) and held as
// half floats. Takes the caller's buffer.
std::unique_ptr<Image> byte_image_to_scene_linear(int width, int height, int channels, FloatBuffer pixels,
                                                  ImageAlpha alpha, Interpolation interp, Extension ext,
                                                  const std::string& ocio_config, const std::string& ocio_space);

}  // namespace lt
