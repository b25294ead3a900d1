#include "shading/image.h"

#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <new>

namespace lt {

float srgb_to_linear(float c) {
  if (c <= 0.04045f) return c * (1.0f / 12.92f);
  return std::pow((c + 0.055f) * (1.0f / 1.055f), 2.4f);
}

namespace {
// The value Blender gives for byte b of a byte image (Image.pixels: b * (1.0f / 255.0f)).
inline float byte_value(uint8_t b) { return float(b) * (1.0f / 255.0f); }
}  // namespace

Image::Image(int width, int height, int channels, const float* pixels, bool srgb, Interpolation interp, Extension ext,
             ImageAlpha alpha)
    : width_(width), height_(height), interp_(interp), ext_(ext), srgb_(srgb), alpha_mode_(alpha) {
  const size_t n = size_t(width) * height * channels;
  FloatBuffer copy(n);
  std::copy(pixels, pixels + n, copy.data());
  store(channels, std::move(copy));
}

Image::Image(int width, int height, int channels, FloatBuffer pixels, bool srgb, Interpolation interp, Extension ext,
             ImageAlpha alpha)
    : width_(width), height_(height), interp_(interp), ext_(ext), srgb_(srgb), alpha_mode_(alpha) {
  store(channels, std::move(pixels));
}

Image::Image(int width, int height, int channels, ByteBuffer pixels, bool srgb, Interpolation interp, Extension ext,
             ImageAlpha alpha)
    : width_(width), height_(height), interp_(interp), ext_(ext), srgb_(srgb), alpha_mode_(alpha) {
  store(channels, std::move(pixels));
}

Image::Image(int width, int height, int channels, HalfBuffer pixels, Interpolation interp, Extension ext,
             ImageAlpha alpha)
    : width_(width), height_(height), interp_(interp), ext_(ext), srgb_(false), alpha_mode_(alpha) {
  store(channels, std::move(pixels));
}

namespace {
inline float half_value(uint16_t h) { return imath_half_to_float(h); }
}  // namespace

void Image::store(int channels, HalfBuffer pixels) {
  // As store(FloatBuffer) does with the same values (its byte-value test aside: a half image that
  // holds only byte values is kept as halves, the same texels).
  const size_t n = size_t(width_) * height_;
  channels_ = channels >= 3 ? 3 : 1;
  uint16_t* p = pixels.data();
  if (channels == 4 && alpha_mode_ != ImageAlpha::Ignore) {
    bool opaque = true;
    for (size_t i = 0; i < n && opaque; ++i) opaque = half_value(p[4 * i + 3]) == 1.0f;
    if (!opaque) {
      alpha_floats_.resize(n);
      for (size_t i = 0; i < n; ++i) {
        const float a = half_value(p[4 * i + 3]);
        alpha_floats_[i] = std::isfinite(a) ? clamp(a, 0.0f, 1.0f) : 0.0f;
      }
    }
  }
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < channels_; ++k) {
      const uint16_t v = p[i * channels + k];
      p[i * channels_ + k] = std::isfinite(half_value(v)) ? v : uint16_t(0);  // never a bad texel
    }
  pixels.shrink(n * channels_);
  halfs_ = std::move(pixels);
}

void Image::store(int channels, ByteBuffer pixels) {
  const size_t n = size_t(width_) * height_;
  const bool has_alpha = channels == 2 || channels == 4;
  channels_ = channels >= 3 ? 3 : 1;
  uint8_t* p = pixels.data();
  // The alpha plane, kept when used and not all 255 (as store(FloatBuffer) keeps it).
  if (has_alpha && alpha_mode_ != ImageAlpha::Ignore) {
    bool opaque = true;
    for (size_t i = 0; i < n && opaque; ++i) opaque = p[i * channels + channels - 1] == 255;
    if (!opaque) {
      alpha_bytes_.resize(n);
      for (size_t i = 0; i < n; ++i) alpha_bytes_[i] = p[i * channels + channels - 1];
    }
  }
  // In place: the write index never passes the read index.
  if (channels != channels_)
    for (size_t i = 0; i < n; ++i)
      for (int k = 0; k < channels_; ++k) p[i * channels_ + k] = p[i * channels + k];
  // Cycles associates straight byte images in integers, before any decoding: c a / 255.
  if (!alpha_bytes_.empty() && alpha_mode_ == ImageAlpha::Straight)
    for (size_t i = 0; i < n * channels_; ++i) p[i] = uint8_t(unsigned(p[i]) * alpha_bytes_[i / channels_] / 255u);
  pixels.shrink(n * channels_);
  bytes_ = std::move(pixels);
}

void Image::store(int channels, FloatBuffer pixels) {
  const size_t n = size_t(width_) * height_;
  channels_ = channels >= 3 ? 3 : 1;
  float* p = pixels.data();
  // The alpha plane, before the colours are packed over it: kept when used and not all 1.
  std::vector<float> alpha;
  if (channels == 4 && alpha_mode_ != ImageAlpha::Ignore) {
    bool opaque = true;
    for (size_t i = 0; i < n && opaque; ++i) opaque = p[4 * i + 3] == 1.0f;
    if (!opaque) {
      alpha.resize(n);
      for (size_t i = 0; i < n; ++i) alpha[i] = std::isfinite(p[4 * i + 3]) ? clamp(p[4 * i + 3], 0.0f, 1.0f) : 0.0f;
    }
  }
  // In place: RGB(A) to RGB (the write index never passes the read index), non-finite values to 0
  // (never let a bad texel poison the image), and whether every value is an exact byte value.
  bool bytes = true;
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < channels_; ++k) {
      float v = p[i * channels + k];
      if (!std::isfinite(v)) v = 0.0f;
      p[i * channels_ + k] = v;
      if (bytes) {
        const float b = std::nearbyint(v * 255.0f);
        bytes = b >= 0.0f && b <= 255.0f && byte_value(uint8_t(b)) == v;
      }
    }
  for (size_t i = 0; bytes && i < alpha.size(); ++i)
    bytes = byte_value(uint8_t(std::nearbyint(alpha[i] * 255.0f))) == alpha[i];
  const bool associate = !alpha.empty() && alpha_mode_ == ImageAlpha::Straight;
  if (bytes) {
    bytes_ = ByteBuffer(n * channels_);
    for (size_t i = 0; i < bytes_.size(); ++i) bytes_[i] = uint8_t(std::nearbyint(p[i] * 255.0f));
    if (!alpha.empty()) {
      alpha_bytes_.resize(n);
      for (size_t i = 0; i < n; ++i) alpha_bytes_[i] = uint8_t(std::nearbyint(alpha[i] * 255.0f));
    }
    // Cycles associates straight byte images in integers, before any decoding: c a / 255.
    if (associate)
      for (size_t i = 0; i < bytes_.size(); ++i)
        bytes_[i] = uint8_t(unsigned(bytes_[i]) * alpha_bytes_[i / channels_] / 255u);
    return;  // `pixels` is freed here
  }
  if (associate)
    for (size_t i = 0; i < n * channels_; ++i) p[i] *= alpha[i / channels_];
  pixels.shrink(n * channels_);
  floats_ = std::move(pixels);
  alpha_floats_ = std::move(alpha);
}

float Image::lookup_alpha(Vec2 uv) const {
  if (!alpha_bytes_.empty())
    return filtered<float>(uv, [&](int x, int y) { return byte_value(alpha_bytes_[size_t(y) * width_ + x]); });
  if (!alpha_floats_.empty())
    return filtered<float>(uv, [&](int x, int y) { return alpha_floats_[size_t(y) * width_ + x]; });
  return 1.0f;
}

Vec3 Image::fetch(size_t i) const {
  if (!bytes_.empty()) {
    if (channels_ == 1) return Vec3(byte_value(bytes_[i]));
    const uint8_t* b = &bytes_[3 * i];
    return Vec3(byte_value(b[0]), byte_value(b[1]), byte_value(b[2]));
  }
  if (!halfs_.empty()) {
    if (channels_ == 1) return Vec3(half_value(halfs_[i]));
    const uint16_t* h = &halfs_[3 * i];
    return Vec3(half_value(h[0]), half_value(h[1]), half_value(h[2]));
  }
  const float* f = floats_.data();
  if (channels_ == 1) return Vec3(f[i]);
  return Vec3(f[3 * i], f[3 * i + 1], f[3 * i + 2]);
}

template <class T, class F>
T Image::filtered(Vec2 uv, F get) const {
  auto wrap = [&](int i, int n, bool* inside) {
    switch (ext_) {
      case Extension::Repeat: {
        int r = i % n;
        return r < 0 ? r + n : r;
      }
      case Extension::Extend:
        return clamp(i, 0, n - 1);
      case Extension::Clip:
        *inside = *inside && i >= 0 && i < n;
        return clamp(i, 0, n - 1);
    }
    return 0;
  };
  float x = uv.x * width_ - 0.5f, y = uv.y * height_ - 0.5f;
  if (!std::isfinite(x) || !std::isfinite(y)) return T(0.0f);
  // Texel coordinates beyond int's range (a mapping scaled to 1e34: fuzz_abi) are first brought
  // into it: Repeat by the period (fmod is exact), Extend and Clip to just past the edge, whose
  // result (the edge texel, or nothing outside a Clip image) is the same.
  auto in_range = [&](float c, int n) {
    if (std::abs(c) < float(1 << 30)) return c;
    if (ext_ == Extension::Repeat) {
      const float r = float(std::fmod(double(c), double(n)));
      return r < 0 ? r + float(n) : r;
    }
    return c < 0 ? -4.0f : float(n) + 4.0f;
  };
  x = in_range(x, width_);
  y = in_range(y, height_);
  if (interp_ == Interpolation::Closest) {
    bool inside = true;
    int ix = wrap(int(std::floor(x + 0.5f)), width_, &inside), iy = wrap(int(std::floor(y + 0.5f)), height_, &inside);
    return inside ? get(ix, iy) : T(0.0f);
  }
  float fx = std::floor(x), fy = std::floor(y);
  float tx = x - fx, ty = y - fy;
  int x0 = int(fx), y0 = int(fy);
  T sum(0.0f);
  if (interp_ == Interpolation::Cubic) {
    // Cycles' CPU interp_cubic: uniform cubic B-spline weights over the 4 x 4 texels around
    // (x0 - 1 .. x0 + 2); texels outside a Clip image are 0.
    float u[4], v[4];
    auto weights = [](float t, float* w) {
      w[0] = (((-1.0f / 6.0f) * t + 0.5f) * t - 0.5f) * t + (1.0f / 6.0f);
      w[1] = ((0.5f * t - 1.0f) * t) * t + (2.0f / 3.0f);
      w[2] = ((-0.5f * t + 0.5f) * t + 0.5f) * t + (1.0f / 6.0f);
      w[3] = (1.0f / 6.0f) * t * t * t;
    };
    weights(tx, u);
    weights(ty, v);
    for (int j = 0; j < 4; ++j) {
      T row(0.0f);
      for (int i = 0; i < 4; ++i) {
        bool inside = true;
        const int ix = wrap(x0 - 1 + i, width_, &inside), iy = wrap(y0 - 1 + j, height_, &inside);
        if (inside) row = row + get(ix, iy) * u[i];
      }
      sum = sum + row * v[j];
    }
    return sum;
  }
  const float w[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
  for (int k = 0; k < 4; ++k) {
    bool inside = true;
    int ix = wrap(x0 + (k & 1), width_, &inside), iy = wrap(y0 + (k >> 1), height_, &inside);
    if (inside) sum = sum + get(ix, iy) * w[k];
  }
  return sum;
}

Vec3 Image::texel(int x, int y) const {
  Vec3 c = fetch(size_t(y) * width_ + x);
  return srgb_ ? Vec3(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)) : c;
}

Vec3 Image::lookup(Vec2 uv, bool unassociate) const {
  Vec3 c = filtered<Vec3>(uv, [&](int x, int y) { return fetch(size_t(y) * width_ + x); });
  if (unassociate && associated()) {
    const float a = lookup_alpha(uv);
    if (a != 0 && a != 1) c *= 1 / a;
  }
  return srgb_ ? Vec3(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)) : c;
}

}  // namespace lt
