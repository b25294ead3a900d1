#include "scene/image.h"

namespace lt {

float srgb_to_linear(float c) {
  if (c <= 0.04045f) return c * (1.0f / 12.92f);
  return std::pow((c + 0.055f) * (1.0f / 1.055f), 2.4f);
}

Image::Image(int width, int height, int channels, const float* pixels, bool srgb, Interpolation interp,
             Extension ext)
    : width_(width), height_(height), interp_(interp), ext_(ext), srgb_(srgb) {
  size_t n = size_t(width) * height;
  texels_.resize(n);
  first_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const float* px = pixels + i * channels;
    Vec3 c = channels >= 3 ? Vec3(px[0], px[1], px[2]) : Vec3(px[0]);
    for (int k = 0; k < 3; ++k) c[k] = std::isfinite(c[k]) ? c[k] : 0.0f;  // never let a bad texel poison the image
    texels_[i] = c;
    first_[i] = c.x;
  }
}


template <class T, class F>
T Image::filtered(Vec2 uv, F get) const {
  auto wrap = [&](int i, int n, bool* inside) {
    switch (ext_) {
      case Extension::Repeat: { int r = i % n; return r < 0 ? r + n : r; }
      case Extension::Extend: return clamp(i, 0, n - 1);
      case Extension::Clip: *inside = *inside && i >= 0 && i < n; return clamp(i, 0, n - 1);
    }
    return 0;
  };
  float x = uv.x * width_ - 0.5f, y = uv.y * height_ - 0.5f;
  if (!std::isfinite(x) || !std::isfinite(y)) return T(0.0f);
  if (interp_ == Interpolation::Closest) {
    bool inside = true;
    int ix = wrap(int(std::floor(x + 0.5f)), width_, &inside), iy = wrap(int(std::floor(y + 0.5f)), height_, &inside);
    return inside ? get(ix, iy) : T(0.0f);
  }
  float fx = std::floor(x), fy = std::floor(y);
  float tx = x - fx, ty = y - fy;
  int x0 = int(fx), y0 = int(fy);
  T sum(0.0f);
  const float w[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
  for (int k = 0; k < 4; ++k) {
    bool inside = true;
    int ix = wrap(x0 + (k & 1), width_, &inside), iy = wrap(y0 + (k >> 1), height_, &inside);
    if (inside) sum = sum + get(ix, iy) * w[k];
  }
  return sum;
}

Vec3 Image::texel(int x, int y) const {
  Vec3 c = texels_[size_t(y) * width_ + x];
  return srgb_ ? Vec3(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)) : c;
}

Vec3 Image::lookup(Vec2 uv) const {
  Vec3 c = filtered<Vec3>(uv, [&](int x, int y) { return texels_[size_t(y) * width_ + x]; });
  return srgb_ ? Vec3(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)) : c;
}

float Image::lookup_value(Vec2 uv) const {
  float v = filtered<float>(uv, [&](int x, int y) { return first_[size_t(y) * width_ + x]; });
  return srgb_ ? srgb_to_linear(v) : v;
}

}  // namespace lt
