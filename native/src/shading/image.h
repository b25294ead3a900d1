// Images for textures and environment maps, rows bottom to top as Blender stores them, looked up
// like Cycles (pixel centres at (i + 0.5) / width). Stored at the source's precision: 8 bits per
// channel when every value is one Blender gives for a byte image (b * (1/255)), else 32-bit float;
// grey images keep one channel, others RGB, and an alpha plane when the alpha is used and not 1
// everywhere (colours then associated as Cycles stores them: ImageAlpha).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/math.h"
#include "core/sampling.h"

namespace lt {

// Cubic: Cycles' CPU bicubic B-spline (kernel/device/cpu/image.h, interp_cubic).
enum class Interpolation { Linear, Closest, Cubic };
enum class Extension { Repeat, Extend, Clip };
// lt_image_alpha: what a 4-channel image's alpha means.
enum class ImageAlpha { Ignore, Straight, Premultiplied, ChannelPacked };

// A malloc'd float buffer: an image's pixels as the caller fills them (lt_scene_begin_image),
// shrunk in place once converted.
class FloatBuffer {
 public:
  FloatBuffer() = default;
  explicit FloatBuffer(size_t n);  // throws std::bad_alloc
  FloatBuffer(FloatBuffer&& o) noexcept : p_(o.p_), n_(o.n_) {
    o.p_ = nullptr;
    o.n_ = 0;
  }
  FloatBuffer& operator=(FloatBuffer&& o) noexcept;
  ~FloatBuffer();
  float* data() const { return p_; }
  size_t size() const { return n_; }
  void shrink(size_t n);  // keeps the first n floats (realloc: in place for large blocks)
  void reset();

 private:
  float* p_ = nullptr;
  size_t n_ = 0;
};

class Image {
 public:
  // channels 1, 3 or 4; srgb: decode the sRGB transfer function to linear. Copies the pixels.
  Image(int width, int height, int channels, const float* pixels, bool srgb, Interpolation interp, Extension ext,
        ImageAlpha alpha = ImageAlpha::Ignore);
  // Takes `pixels` (width*height*channels floats) and converts it in place: no second copy.
  Image(int width, int height, int channels, FloatBuffer pixels, bool srgb, Interpolation interp, Extension ext,
        ImageAlpha alpha = ImageAlpha::Ignore);
  int width() const { return width_; }
  int height() const { return height_; }
  // RGB; unassociate: divide associated colours by alpha before decoding sRGB, as Cycles'
  // svm_image_texture does where the Alpha output is used.
  Vec3 lookup(Vec2 uv, bool unassociate = false) const;
  float lookup_alpha(Vec2 uv) const;  // 1 without an alpha plane
  // Colours are associated with alpha: divide by it where the Alpha output is used (Cycles'
  // NODE_IMAGE_ALPHA_UNASSOCIATE).
  bool associated() const { return has_alpha() && alpha_mode_ != ImageAlpha::ChannelPacked; }
  bool has_alpha() const { return !alpha_bytes_.empty() || !alpha_floats_.empty(); }
  Vec3 texel(int x, int y) const;  // linear
  size_t bytes() const {
    return bytes_.size() + floats_.size() * sizeof(float) + alpha_bytes_.size() + alpha_floats_.size() * sizeof(float);
  }
  bool is_byte() const { return !bytes_.empty(); }

 private:
  int width_, height_;
  Interpolation interp_;
  Extension ext_;
  // sRGB images stay encoded and are decoded after interpolation, as Cycles does for 8-bit sRGB
  // textures (they differ from interpolating decoded values at sharp edges).
  bool srgb_ = false;
  int channels_ = 3;            // stored: 1 or 3
  std::vector<uint8_t> bytes_;  // 8-bit storage, or
  FloatBuffer floats_;          // float storage
  ImageAlpha alpha_mode_ = ImageAlpha::Ignore;
  std::vector<uint8_t> alpha_bytes_;  // the alpha plane at the colours' precision, or empty
  std::vector<float> alpha_floats_;
  void store(int channels, FloatBuffer pixels);
  Vec3 fetch(size_t i) const;
  template <class T, class F>
  T filtered(Vec2 uv, F fetch) const;
};

float srgb_to_linear(float c);

}  // namespace lt
