#include "core/film.h"

#include "core/label_font.h"

namespace lt {

namespace {
constexpr int kFilterTableSize = 1024;
}

FilterSampler::FilterSampler(FilterType type, float width) {
  width = std::max(width, 1e-3f);
  std::function<float(float)> f;
  switch (type) {
    case FilterType::Box:
      half_range_ = 0.5f * width;
      f = [](float) { return 1.0f; };
      break;
    case FilterType::Gaussian:
      half_range_ = 1.5f * width;
      f = [width](float x) { float v = x * 2.0f / width; return std::exp(-2.0f * v * v); };
      break;
    case FilterType::BlackmanHarris:
      half_range_ = width;
      f = [width](float x) {
        float a = 2 * kPi * (x / (2 * width) + 0.5f);
        return 0.35875f - 0.48829f * std::cos(a) + 0.14128f * std::cos(2 * a) - 0.01168f * std::cos(3 * a);
      };
      break;
  }
  std::vector<float> v(kFilterTableSize);
  for (int i = 0; i < kFilterTableSize; ++i) v[i] = std::max(0.0f, f(half_range_ * (i + 0.5f) / kFilterTableSize));
  table_ = Distribution1D(v);
}

float FilterSampler::sample(float u) const {
  // The profile is symmetric: the first half of u picks the sign.
  float sign = u < 0.5f ? -1.0f : 1.0f;
  float r = u < 0.5f ? 2 * u : 2 * u - 1;
  float pdf;
  return sign * half_range_ * table_.sample_continuous(std::min(r, kOneMinusEpsilon), &pdf);
}

float FilterSampler::pdf(float offset) const {
  float a = std::abs(offset) / half_range_;
  if (!(a < 1)) return 0;
  int bin = std::min(int(a * table_.size()), int(table_.size()) - 1);
  double integral = table_.integral();
  return integral > 0 ? float(table_.func(bin) / integral) * 0.5f / half_range_ : 0.0f;
}

int pass_channels(Pass pass) {
  switch (pass) {
    case Pass::Combined: return 4;
    case Pass::Depth: return 1;
    case Pass::SampleCount: return 1;
    case Pass::Count: return 0;
    default: return 3;
  }
}

void Film::add(int x, int y, const SampleValue& s) {
  PixelAccum& a = accum_[size_t(y) * width_ + x];
  for (int k = 0; k < 3; ++k) {
    double v = s.radiance[k];
    a.rgb[k] += v;
    a.rgb2[k] += v * v;
    a.normal[k] += s.normal[k];
    a.albedo[k] += s.albedo[k];
  }
  a.alpha += s.alpha;
  a.depth = std::min(a.depth, s.depth);
  a.count += 1;
}

void Film::publish() {
  std::lock_guard<std::mutex> lock(mutex_);
  published_ = accum_;
  published_splat_ = splat_;
  published_light_paths_ = light_paths_;
}

uint64_t Film::total_samples() const {
  std::lock_guard<std::mutex> lock(mutex_);
  uint64_t n = 0;
  for (const PixelAccum& a : published_) n += a.count;
  return n;
}

void Film::read(Pass pass, float* out, bool labels) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const int c = pass_channels(pass);
  const size_t n = size_t(width_) * height_;
  const double splat_scale = published_light_paths_ ? 1.0 / double(published_light_paths_) : 0.0;
  for (size_t i = 0; i < n; ++i) {
    float* o = out + i * c;
    if (published_.empty()) {
      for (int k = 0; k < c; ++k) o[k] = pass == Pass::Depth ? 1e10f : 0.0f;
      continue;
    }
    const PixelAccum& a = published_[i];
    const double inv = a.count ? 1.0 / a.count : 0.0;
    switch (pass) {
      case Pass::Combined:
        for (int k = 0; k < 3; ++k) o[k] = float(a.rgb[k] * inv + published_splat_[3 * i + k] * splat_scale);
        o[3] = float(a.alpha * inv);
        break;
      case Pass::Depth: o[0] = a.depth; break;
      case Pass::Normal: {
        Vec3 nrm(float(a.normal[0]), float(a.normal[1]), float(a.normal[2]));
        float len = length(nrm);
        nrm = len > 0 ? nrm / len : Vec3(0.0f);
        for (int k = 0; k < 3; ++k) o[k] = nrm[k];
        break;
      }
      case Pass::Albedo:
        for (int k = 0; k < 3; ++k) o[k] = float(a.albedo[k] * inv);
        break;
      case Pass::Variance:
        // Variance of the pixel mean: the unbiased sample variance over n.
        for (int k = 0; k < 3; ++k) {
          double var = 0;
          if (a.count > 1) {
            double mean = a.rgb[k] * inv;
            var = std::max(0.0, (a.rgb2[k] * inv - mean * mean)) * a.count / (a.count - 1.0) * inv;
          }
          o[k] = float(var);
        }
        break;
      case Pass::SampleCount: o[0] = float(a.count); break;
      case Pass::Count: break;
    }
  }
  if (pass != Pass::Combined || !labels || labels_.empty()) return;
  for (size_t i = 0; i < n; ++i)
    if (labels_[i] != kLabelNone) {
      const float v = labels_[i] == kLabelWhite ? 1.0f : 0.0f;
      out[4 * i] = out[4 * i + 1] = out[4 * i + 2] = v;
      out[4 * i + 3] = 1.0f;
    }
}

}  // namespace lt

namespace lt {

void Film::read_strategy_grid(int columns, int rows, float* out) const {
  const int gw = columns * width_;
  const double splat_scale = light_paths_ ? 1.0 / double(light_paths_) : 0.0;
  for (int d = 0; d < rows; ++d)
    for (int s = 0; s < columns; ++s) {
      const int cell = d * columns + s;
      const int oy = (rows - 1 - d) * height_, ox = s * width_;
      for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x) {
          const size_t i = size_t(y) * width_ + x;
          const uint32_t n = accum_[i].count;
          float* o = out + (size_t(oy + y) * gw + ox + x) * 3;
          for (int k = 0; k < 3; ++k) {
            double v = strategy_splats_[(i * strategy_cells_ + cell) * 3 + k] * splat_scale;
            if (n) v += strategies_[(i * strategy_cells_ + cell) * 3 + k] / double(n);
            o[k] = float(v);
          }
        }
    }
}

}  // namespace lt
