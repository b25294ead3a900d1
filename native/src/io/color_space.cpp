#include "io/color_space.h"

#include <OpenColorIO/OpenColorIO.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <mutex>
#include <utility>
#include <vector>

#include "core/error.h"

namespace lt {

namespace OCIO = OCIO_NAMESPACE;

float cycles_half_to_float(uint16_t h) {
  // half_to_float_image: the exponent rebiased without a denormal case (0 reads as 2^-15).
  const uint32_t x =
      (uint32_t(h & 0x8000u) << 16) | ((uint32_t(h & 0x7c00u) + 0x1c000u) << 13) | (uint32_t(h & 0x03ffu) << 13);
  float f;
  std::memcpy(&f, &x, sizeof f);
  return f;
}

uint16_t cycles_float_to_half(float f) {
  // float_to_half_image: mantissa truncated, flush to zero below 2^-14, clamped to 65504.
  uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  const uint32_t sign = (u & 0x80000000u) >> 16;
  const uint32_t exponent = u & 0x7f800000u;
  uint32_t value = ((u & 0x7fffffffu) >> 13) - 0x1c000u;
  value = exponent < 0x38800000u ? 0 : value;
  value = exponent > 0x47000000u ? 0x7bffu : value;
  value = exponent == 0 ? 0 : value;
  return uint16_t(value | sign);
}

namespace {

// One processor per (configuration, colour space), as Cycles caches them per colour space.
OCIO::ConstCPUProcessorRcPtr processor(const std::string& config, const std::string& space) {
  static std::mutex mutex;
  static std::map<std::pair<std::string, std::string>, OCIO::ConstCPUProcessorRcPtr> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto key = std::make_pair(config, space);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  try {
    OCIO::ConstConfigRcPtr c = OCIO::Config::CreateFromFile(config.c_str());
    OCIO::ConstCPUProcessorRcPtr p = c->getProcessor(space.c_str(), OCIO::ROLE_SCENE_LINEAR)->getDefaultCPUProcessor();
    return cache[key] = p;
  } catch (const OCIO::Exception& e) {
    throw InvalidArgument("colour space '" + space + "' of '" + config + "': " + e.what());
  }
}

}  // namespace

void halves_to_scene_linear(const std::string& config, const std::string& space, uint16_t* pixels, size_t n,
                            int channels) {
  if (channels != 1 && channels != 3 && channels != 4)
    throw InvalidArgument("halves_to_scene_linear: 1, 3 or 4 channels");
  const OCIO::ConstCPUProcessorRcPtr p = processor(config, space);
  const auto weighted = [](float a) { return !(a <= 0.0f || a == 1.0f); };
  // In chunks, as Cycles' processor_apply_pixels: a few rows' worth of floats at a time.
  constexpr size_t kChunk = 1 << 16;
  std::vector<float> rgb(3 * std::min(n, kChunk));
  for (size_t start = 0; start < n; start += kChunk) {
    const size_t count = std::min(kChunk, n - start);
    uint16_t* px = pixels + start * size_t(channels);
    for (size_t i = 0; i < count; ++i) {
      const uint16_t* v = px + i * size_t(channels);
      const float a = channels == 4 ? cycles_half_to_float(v[3]) : 1.0f;
      for (int k = 0; k < 3; ++k) {
        rgb[3 * i + k] = cycles_half_to_float(v[channels == 1 ? 0 : k]);
        if (weighted(a)) rgb[3 * i + k] *= 1.0f / a;
      }
    }
    OCIO::PackedImageDesc desc(rgb.data(), long(count), 1, 3);
    p->apply(desc);
    for (size_t i = 0; i < count; ++i) {
      uint16_t* v = px + i * size_t(channels);
      if (channels == 1) {
        v[0] = cycles_float_to_half((rgb[3 * i] + rgb[3 * i + 1] + rgb[3 * i + 2]) * (1.0f / 3.0f));
        continue;
      }
      const float a = channels == 4 ? cycles_half_to_float(v[3]) : 1.0f;
      for (int k = 0; k < 3; ++k) v[k] = cycles_float_to_half(weighted(a) ? rgb[3 * i + k] * a : rgb[3 * i + k]);
    }
  }
}

}  // namespace lt
