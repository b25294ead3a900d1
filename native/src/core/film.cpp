#include "core/film.h"

#include "core/label_font.h"

#include <tbb/parallel_for.h>

#include <limits>

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
  const int n = kFilterTableSize;
  std::vector<double> v(n), cdf(n + 1, 0.0);
  for (int i = 0; i < n; ++i) {
    v[i] = std::max(0.0f, f(half_range_ * (i + 0.5f) / n));
    cdf[i + 1] = cdf[i] + v[i];
  }
  const double total = cdf[n] > 0 ? cdf[n] : 1.0;
  cdf_.resize(n + 1);
  inv_width_.resize(n);
  density_.resize(n);
  guide_.resize(n);
  for (int i = 0; i <= n; ++i) cdf_[i] = float(cdf[i] / total);
  cdf_[n] = 1.0f;
  for (int i = 0; i < n; ++i) {
    const float w = cdf_[i + 1] - cdf_[i];
    inv_width_[i] = w > 0 ? 1.0f / w : 0.0f;
    // Density per pixel of offset: the bin's probability spread over its width, split by sign.
    density_[i] = float(v[i] / total * n * 0.5 / half_range_);
  }
  for (int k = 0, i = 0; k < n; ++k) {
    while (i + 1 < n && cdf_[i + 1] <= float(k) / n) ++i;
    guide_[k] = uint32_t(i);
  }
}

float FilterSampler::sample(float u) const {
  // The profile is symmetric: the first half of u picks the sign.
  const float sign = u < 0.5f ? -1.0f : 1.0f;
  const float r = std::min(u < 0.5f ? 2 * u : 2 * u - 1, kOneMinusEpsilon);
  const int n = int(guide_.size());
  int i = int(guide_[std::min(n - 1, int(r * n))]);
  while (i + 1 < n && cdf_[i + 1] <= r) ++i;  // also skips empty bins
  const float t = std::min((r - cdf_[i]) * inv_width_[i], kOneMinusEpsilon);
  return sign * half_range_ * (i + t) / n;
}

float FilterSampler::pdf(float offset) const {
  const float a = std::abs(offset) / half_range_;
  if (!(a < 1)) return 0;
  const int n = int(density_.size());
  return density_[std::min(int(a * n), n - 1)];
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
  const bool half = a.count & 1u;
  for (int k = 0; k < 3; ++k) {
    double v = s.radiance[k];
    a.rgb[k] += v;
    a.rgb2[k] += v * v;
    if (half) a.half[k] += v;
    a.normal[k] += s.normal[k];
    a.albedo[k] += s.albedo[k];
  }
  a.alpha += s.alpha;
  a.depth = std::min(a.depth, s.depth);
  a.count += 1;
}

ErrorEstimate Film::error_estimate(int passes) const {
  ErrorEstimate e;
  if (passes < 2) return e;
  const bool splats = !splat_.empty() && light_paths_half_ > 0 && light_paths_ > light_paths_half_;
  const double inv_la = splats ? 1.0 / double(light_paths_ - light_paths_half_) : 0.0;
  const double inv_lb = splats ? 1.0 / double(light_paths_half_) : 0.0;
  const double inv_l = splats ? 1.0 / double(light_paths_) : 0.0;
  // Per-row sums in parallel, added in row order: the same bits for any thread count.
  std::vector<double> row_var(height_, 0.0), row_sq(height_, 0.0);
  std::vector<uint64_t> row_skipped(height_, 0);
  tbb::parallel_for(0, height_, [&](int y) {
    double var_sum = 0, square_sum = 0;
    for (size_t i = size_t(y) * width_; i < size_t(y + 1) * width_; ++i) {
      const PixelAccum& a = accum_[i];
      if (a.count < 2) {
        ++row_skipped[y];
        continue;
      }
      const double n = a.count, nb = double(a.count / 2), na = n - nb;
      for (int k = 0; k < 3; ++k) {
        double mean_a = (a.rgb[k] - a.half[k]) / na, mean_b = a.half[k] / nb, mean = a.rgb[k] / n;
        if (splats) {
          const double s = splat_[3 * i + k], sb = splat_half_[3 * i + k];
          mean_a += (s - sb) * inv_la;
          mean_b += sb * inv_lb;
          mean += s * inv_l;
        }
        const double d = mean_a - mean_b;
        var_sum += d * d * na * nb / (n * n);
        square_sum += mean * mean;
      }
    }
    row_var[y] = var_sum;
    row_sq[y] = square_sum;
  });
  double var_sum = 0, square_sum = 0;
  for (int y = 0; y < height_; ++y) {
    var_sum += row_var[y];
    square_sum += row_sq[y];
    e.unestimated_pixels += row_skipped[y];
  }
  const uint64_t n_pixels = accum_.size() - e.unestimated_pixels;
  if (!n_pixels) return e;
  const double signal = square_sum - var_sum;
  e.mean_square = std::max(0.0, signal) / double(n_pixels);
  e.variance = var_sum;
  if (var_sum <= 0) e.rel_error = 0;
  else e.rel_error = signal > 0 ? std::sqrt(var_sum / signal) : std::numeric_limits<double>::infinity();
  return e;
}

double Film::pixel_variance(int x, int y) const {
  const PixelAccum& a = accum_[size_t(y) * width_ + x];
  if (a.count < 2) return 0;
  const double n = a.count;
  double v = 0;
  for (int k = 0; k < 3; ++k) {
    const double mean = a.rgb[k] / n;
    v += std::max(0.0, a.rgb2[k] / n - mean * mean) / (n - 1.0);
  }
  return v;
}

void Film::publish() {
  std::lock_guard<std::mutex> lock(mutex_);
  published_ = accum_;
  published_splat_ = splat_;
  published_light_paths_ = light_paths_;
}

bool Film::read_light_tracing(float* out) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!published_light_paths_) return false;
  const double scale = 1.0 / double(published_light_paths_);
  for (size_t i = 0; i < published_splat_.size(); ++i) out[i] = float(published_splat_[i] * scale);
  return true;
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
  const double splat_scale =
      published_light_paths_ && !published_splat_.empty() ? 1.0 / double(published_light_paths_) : 0.0;
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
        for (int k = 0; k < 3; ++k)
          o[k] = float(a.rgb[k] * inv + (splat_scale > 0 ? published_splat_[3 * i + k] * splat_scale : 0.0));
        o[3] = float(a.alpha * inv);
        break;
      case Pass::Depth: o[0] = a.depth; break;
      case Pass::Normal:
        // The mean of the samples' normals, as in Cycles (not renormalised: shorter at edges), so
        // that sample-split parts average into the full render's pass.
        for (int k = 0; k < 3; ++k) o[k] = float(a.normal[k] * inv);
        break;
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
