// Images for textures and environment maps, rows bottom to top as Blender stores them, looked up
// like Cycles (pixel centres at (i + 0.5) / width). Stored at the source's precision: 8 bits per
// channel when every value is one Blender gives for a byte image (b * (1/255)), else 32-bit float;
// grey images keep one channel, others RGB, and an alpha plane when the alpha is used and not 1
// everywhere (colours then associated as Cycles stores them: ImageAlpha).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <vector>

#include "core/math.h"
#include "core/sampling.h"

namespace lt {

// Cubic: Cycles' CPU bicubic B-spline (kernel/device/cpu/image.h, interp_cubic).
enum class Interpolation { Linear, Closest, Cubic };
enum class Extension { Repeat, Extend, Clip };
// lt_image_alpha: what a 4-channel image's alpha means.
enum class ImageAlpha { Ignore, Straight, Premultiplied, ChannelPacked };

// A malloc'd buffer: an image's pixels as the caller fills them (lt_scene_begin_image) or as a file
// is read (io/image_file.h), converted and shrunk in place (realloc) so that they are held once.
template <class T>
class MallocBuffer {
 public:
  MallocBuffer() = default;
  explicit MallocBuffer(size_t n)  // throws std::bad_alloc
      : p_(static_cast<T*>(std::malloc(std::max<size_t>(n, 1) * sizeof(T)))), n_(n) {
    if (!p_) throw std::bad_alloc();
  }
  MallocBuffer(MallocBuffer&& o) noexcept : p_(o.p_), n_(o.n_) {
    o.p_ = nullptr;
    o.n_ = 0;
  }
  MallocBuffer& operator=(MallocBuffer&& o) noexcept {
    if (this != &o) {
      reset();
      p_ = o.p_;
      n_ = o.n_;
      o.p_ = nullptr;
      o.n_ = 0;
    }
    return *this;
  }
  ~MallocBuffer() { reset(); }
  T* data() const { return p_; }
  size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  T& operator[](size_t i) const { return p_[i]; }
  // Keeps the first n values (realloc: in place for large blocks); a failed shrink keeps the
  // larger block, which is still valid.
  void shrink(size_t n) {
    if (n >= n_) return;
    if (void* q = std::realloc(p_, std::max<size_t>(n, 1) * sizeof(T))) p_ = static_cast<T*>(q);
    n_ = n;
  }
  void reset() {
    std::free(p_);
    p_ = nullptr;
    n_ = 0;
  }

 private:
  T* p_ = nullptr;
  size_t n_ = 0;
};
using FloatBuffer = MallocBuffer<float>;
using ByteBuffer = MallocBuffer<uint8_t>;
using HalfBuffer = MallocBuffer<uint16_t>;  // IEEE half floats (OpenEXR's)

class Image {
 public:
  // channels 1, 3 or 4; srgb: decode the sRGB transfer function to linear. Copies the pixels.
  Image(int width, int height, int channels, const float* pixels, bool srgb, Interpolation interp, Extension ext,
        ImageAlpha alpha = ImageAlpha::Ignore);
  // Takes `pixels` (width*height*channels floats) and converts it in place: no second copy.
  Image(int width, int height, int channels, FloatBuffer pixels, bool srgb, Interpolation interp, Extension ext,
        ImageAlpha alpha = ImageAlpha::Ignore);
  // 8-bit pixels as a file stores them: channels 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA),
  // alpha straight. Taken and converted in place, stored as the float constructor stores the
  // values b * (1/255) of a byte image's 4 channels (grey as 1 channel: the same texels).
  Image(int width, int height, int channels, ByteBuffer pixels, bool srgb, Interpolation interp, Extension ext,
        ImageAlpha alpha = ImageAlpha::Ignore);
  // Half floats as a file stores them (channels 1, 3 or 4, alpha associated or apart as `alpha`
  // says; never Straight): taken and kept as half floats, converted in place like the float
  // constructor's (the texels are the same floats).
  Image(int width, int height, int channels, HalfBuffer pixels, Interpolation interp, Extension ext,
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
    return bytes_.size() + floats_.size() * sizeof(float) + halfs_.size() * sizeof(uint16_t) + alpha_bytes_.size() +
           alpha_floats_.size() * sizeof(float);
  }
  bool is_byte() const { return !bytes_.empty(); }

 private:
  int width_, height_;
  Interpolation interp_;
  Extension ext_;
  // sRGB images stay encoded and are decoded after interpolation, as Cycles does for 8-bit sRGB
  // textures (they differ from interpolating decoded values at sharp edges).
  bool srgb_ = false;
  int channels_ = 3;    // stored: 1 or 3
  ByteBuffer bytes_;    // 8-bit storage, or
  FloatBuffer floats_;  // float storage, or
  HalfBuffer halfs_;    // half-float storage (half OpenEXR files)
  ImageAlpha alpha_mode_ = ImageAlpha::Ignore;
  std::vector<uint8_t> alpha_bytes_;  // the alpha plane at the colours' precision, or empty
  std::vector<float> alpha_floats_;
  void store(int channels, FloatBuffer pixels);
  void store(int channels, ByteBuffer pixels);
  void store(int channels, HalfBuffer pixels);
  Vec3 fetch(size_t i) const;
  template <class T, class F>
  T filtered(Vec2 uv, F fetch) const;
};

float srgb_to_linear(float c);

}  // namespace lt
