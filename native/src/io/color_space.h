// Image colour spaces other than sRGB, scene linear and data, converted to scene linear with
// OpenColorIO as Cycles 3.4 converts them when it loads an image (scene/colorspace.cpp,
// ColorSpaceManager::to_scene_linear; ImageMetaData::detect_colorspace).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace lt {

// Converts n pixels of `channels` half floats (1: grey, 3: RGB, 4: RGBA) from colour space `space`
// of the OpenColorIO configuration file `config` to its scene_linear role, in place, as Cycles does
// for an 8-bit image it has read as halves: each half widened as Cycles' half_to_float_image, the
// CPU processor applied (grey as (v, v, v), then averaged; RGBA with the colour divided by an
// alpha other than 0 and 1 before and multiplied after, as processor_apply_pixels_rgba), narrowed
// as float_to_half_image (truncated, denormals flushed, clamped to 65504). Throws InvalidArgument
// when the configuration or the colour space cannot be used (OpenColorIO's message).
void halves_to_scene_linear(const std::string& config, const std::string& space, uint16_t* pixels, size_t n,
                            int channels);

// Cycles' util/half.h conversions for image texels (not IEEE rounding: kept bit for bit).
float cycles_half_to_float(uint16_t h);
uint16_t cycles_float_to_half(float f);

}  // namespace lt
