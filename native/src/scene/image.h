// Images for textures and environment maps: float RGB, rows bottom to top as Blender stores them,
// looked up like Cycles (pixel centres at (i + 0.5) / width).
#pragma once

#include <vector>

#include "core/math.h"
#include "core/sampling.h"

namespace lt {

enum class Interpolation { Linear, Closest };
enum class Extension { Repeat, Extend, Clip };

class Image {
 public:
  // channels 1, 3 or 4; srgb: decode the sRGB transfer function to linear.
  Image(int width, int height, int channels, const float* pixels, bool srgb, Interpolation interp,
        Extension ext);
  int width() const { return width_; }
  int height() const { return height_; }
  Vec3 lookup(Vec2 uv) const;            // RGB
  float lookup_value(Vec2 uv) const;     // first channel, for scalar inputs
  Vec3 texel(int x, int y) const;  // linear

 private:
  int width_, height_;
  Interpolation interp_;
  Extension ext_;
  // sRGB images stay encoded and are decoded after interpolation, as Cycles does for 8-bit sRGB
  // textures (they differ from interpolating decoded values at sharp edges).
  bool srgb_ = false;
  std::vector<Vec3> texels_;
  std::vector<float> first_;  // first channel
  template <class T, class F> T filtered(Vec2 uv, F fetch) const;
};

float srgb_to_linear(float c);

}  // namespace lt
