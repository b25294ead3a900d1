#include "core/film.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.h"
#include "core/label_font.h"

namespace lt {

namespace {
constexpr int kFilterTableSize = 1024;
constexpr int kGuidePerBin = 8;  // guide cells per bin: the walk after the lookup is short even in the tails

// IEEE half floats for the published image (what a display needs, as Cycles' display buffer):
// round to nearest even, finite values beyond the range clamped to +-65504.
uint16_t float_to_half(float f) {
  uint32_t x;
  std::memcpy(&x, &f, 4);
  const uint16_t sign = uint16_t((x >> 16) & 0x8000u);
  x &= 0x7fffffffu;
  if (x >= 0x477ff000u)
    return uint16_t(sign | (x > 0x7f800000u ? 0x7e00u : 0x7bffu));  // >= 65520 (rounds past max); NaN
  if (x < 0x38800000u) {                                            // subnormal half (or zero)
    if (x < 0x33000000u) return sign;
    const uint32_t m = (x & 0x7fffffu) | 0x800000u;
    const int shift = 126 - int(x >> 23);  // the value in units of 2^-24: (1.m * 2^23) >> shift
    const uint32_t r = m >> shift, rem = m & ((1u << shift) - 1u), half = 1u << (shift - 1);
    return uint16_t(sign | (r + (rem > half || (rem == half && (r & 1u)))));
  }
  const uint32_t r = ((x - 0x38000000u) >> 13), rem = x & 0x1fffu;
  return uint16_t(sign | (r + (rem > 0x1000u || (rem == 0x1000u && (r & 1u)))));
}

float half_to_float(uint16_t h) {
  const uint32_t sign = uint32_t(h & 0x8000u) << 16, e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
  float f;
  if (e == 0) {
    f = std::ldexp(float(m), -24);
  } else if (e == 31) {
    f = m ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
  } else {
    const uint32_t x = ((e + 112u) << 23) | (m << 13);
    std::memcpy(&f, &x, 4);
  }
  return sign ? -f : f;
}
}  // namespace

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
      f = [width](float x) {
        float v = x * 2.0f / width;
        return std::exp(-2.0f * v * v);
      };
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
  guide_.resize(size_t(n) * kGuidePerBin);
  for (int i = 0; i <= n; ++i) cdf_[i] = float(cdf[i] / total);
  cdf_[n] = 1.0f;
  for (int i = 0; i < n; ++i) {
    const float w = cdf_[i + 1] - cdf_[i];
    inv_width_[i] = w > 0 ? 1.0f / w : 0.0f;
    // Density per pixel of offset: the bin's probability spread over its width, split by sign.
    density_[i] = float(v[i] / total * n * 0.5 / half_range_);
  }
  const int g = int(guide_.size());
  for (int k = 0, i = 0; k < g; ++k) {
    while (i + 1 < n && cdf_[i + 1] <= float(k) / g) ++i;
    guide_[k] = uint32_t(i);
  }
}

float FilterSampler::sample(float u) const {
  // The profile is symmetric: the first half of u picks the sign.
  const float sign = u < 0.5f ? -1.0f : 1.0f;
  const float r = std::min(u < 0.5f ? 2 * u : 2 * u - 1, kOneMinusEpsilon);
  const int n = int(inv_width_.size()), g = int(guide_.size());
  int i = int(guide_[std::min(g - 1, int(r * g))]);
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
    case Pass::Combined:
    case Pass::NoisyImage:
      return 4;
    case Pass::Depth:
    case Pass::DenoisingDepth:
    case Pass::SampleCount:
    case Pass::Mist:
    case Pass::ObjectIndex:
    case Pass::MaterialIndex:
      return 1;
    case Pass::Vector:
      return 4;
    case Pass::Count:
      return 0;
    default:
      return 3;
  }
}

Pass light_pass_color(Pass p) {
  switch (p) {
    case Pass::DiffuseDirect:
    case Pass::DiffuseIndirect:
      return Pass::DiffuseColor;
    case Pass::GlossyDirect:
    case Pass::GlossyIndirect:
      return Pass::GlossyColor;
    case Pass::TransmissionDirect:
    case Pass::TransmissionIndirect:
      return Pass::TransmissionColor;
    default:
      return Pass::Count;
  }
}

namespace {
bool is_colour_pass(Pass p) {
  return p == Pass::DiffuseColor || p == Pass::GlossyColor || p == Pass::TransmissionColor;
}
// The passes a layout keeps for these: a Direct or Indirect pass needs its Colour to be read.
unsigned with_dependencies(unsigned passes) {
  for (int p = kFirstSummedPass; p < int(Pass::Count); ++p)
    if ((passes & pass_bit(Pass(p))) && light_pass_color(Pass(p)) != Pass::Count)
      passes |= pass_bit(light_pass_color(Pass(p)));
  return passes;
}
}  // namespace

namespace {
// Floats a summed pass keeps per pixel: its channels, and the Vector pass its weight besides.
int summed_floats(Pass p) { return pass_channels(p) + (p == Pass::Vector ? 1 : 0); }
}  // namespace

size_t FilmLayout::bytes_per_pixel() const {
  auto has = [&](Pass p) { return (passes & pass_bit(p)) != 0; };
  size_t floats = 3 + 1 + 3 + 1;  // mean, alpha, half, count
  floats += 2;                    // the published Combined, RGBA in half floats
  if (has(Pass::Depth)) floats += 1;
  if (has(Pass::Normal)) floats += 3;
  if (has(Pass::Albedo)) floats += 3;
  const bool features = (passes & kDenoisingFeatures) != 0;
  if (features) floats += 2 * kFeatureChannels + 3 + (splats ? 6 : 0);  // and the halves' squares
  if (squares || features || has(Pass::Variance)) floats += 3;
  if (splats) floats += 6;
  floats += size_t(strategy_cells) * 6;
  for (int t = 0; t < kCryptoTypes; ++t)
    if ((cryptomatte >> t) & 1u) floats += 2 * size_t(cryptomatte_slots());
  floats += size_t(lightgroups) * (splats ? 6 : 3) + size_t(aovs) * 4;
  if (shadow_catcher) floats += 3 + 4 + 1 + 3;
  const unsigned kept = with_dependencies(passes);
  for (int p = kFirstSummedPass; p < int(Pass::Count); ++p)
    if ((kept & pass_bit(Pass(p))) && Pass(p) != Pass::ShadowCatcher) {
      floats += summed_floats(Pass(p));
      if (splats && is_light_pass(Pass(p)) && !is_colour_pass(Pass(p))) floats += 3;
    }
  return floats * sizeof(float);
}

Film::Film(int width, int height, const FilmLayout& layout) : width_(width), height_(height), layout_(layout) {
  layout_.passes |= pass_bit(Pass::Combined) | pass_bit(Pass::SampleCount);
  // The Variance pass and the half images' variances (denoising) need the sum of squares.
  if (has(Pass::Variance) || (layout_.passes & kDenoisingFeatures)) layout_.squares = true;
  const size_t n = size_t(width) * height;
  mean_.assign(3 * n, 0.0f);
  half_.assign(3 * n, 0.0f);
  alpha_.assign(n, 0.0f);
  count_.assign(n, 0u);
  published_.assign(4 * n, 0);
  if (layout_.squares) m2_.assign(3 * n, 0.0f);
  if (has(Pass::Depth)) depth_.assign(n, 1e10f);
  if (has(Pass::Normal)) normal_.assign(3 * n, 0.0f);
  if (has(Pass::Albedo)) albedo_.assign(3 * n, 0.0f);
  if (layout_.passes & kDenoisingFeatures) {
    layout_.passes |= kDenoisingFeatures;  // one accumulator holds the three
    feature_.assign(kFeatureChannels * n, 0.0f);
    feature_half_.assign(kFeatureChannels * n, 0.0f);
    m2_half_.assign(3 * n, 0.0f);
  }
  if (layout_.splats) {
    splat_.assign(3 * n, 0.0f);
    splat_half_.assign(3 * n, 0.0f);
    if (!feature_.empty()) splat_sq_.assign(6 * n, 0.0f);
  }
  layout_.passes = with_dependencies(layout_.passes);
  if (layout_.shadow_catcher) {
    catcher_.assign(3 * n, 0.0f);
    matte_.assign(4 * n, 0.0f);
    splits_.assign(n, 0.0f);
    background_.assign(3 * n, 0.0f);
  }
  for (int p = kFirstSummedPass; p < int(Pass::Count); ++p) {
    if (!has(Pass(p)) || Pass(p) == Pass::ShadowCatcher) continue;
    sums_[p - kFirstSummedPass].assign(summed_floats(Pass(p)) * n, 0.0f);
    summed_kept_.push_back(p - kFirstSummedPass);
    if (layout_.splats && is_light_pass(Pass(p)) && !is_colour_pass(Pass(p)))
      light_splat_[p - kFirstSummedPass].assign(3 * n, 0.0f);
  }
  for (int t = 0; t < kCryptoTypes; ++t)
    if (has_cryptomatte(t)) crypto_[t].assign(2 * size_t(layout_.cryptomatte_slots()) * n, 0.0f);
  if (layout_.lightgroups > 0) {
    lightgroup_.assign(size_t(layout_.lightgroups) * 3 * n, 0.0f);
    if (layout_.splats) lightgroup_splat_.assign(lightgroup_.size(), 0.0f);
  }
  if (layout_.aovs > 0) aov_.assign(size_t(layout_.aovs) * 4 * n, 0.0f);
  if (layout_.strategy_cells > 0) {
    strategies_.assign(n * layout_.strategy_cells * 3, 0.0f);
    strategy_splats_.assign(strategies_.size(), 0.0f);
  }
}

bool Film::accepts(const SampleValue& s) const {
  bool ok = true;  // bitwise &: no branch per value
  const auto check = [&ok](float v) { ok &= in_range(v); };
  const auto check3 = [&ok](const Vec3& v) { ok &= in_range(v); };
  check3(s.radiance);
  check(s.alpha);
  check(s.depth);  // (the denoising features derive from it and the normal)
  check3(s.normal);
  check3(s.albedo);
  constexpr unsigned kLightPasses = (pass_bit(Pass::Environment) << 1) - pass_bit(Pass::DiffuseDirect);
  if (layout_.passes & kLightPasses)
    for (const Spectrum& v : s.light) check3(v);
  if (has(Pass::Position)) check3(s.position);
  if (has(Pass::UV)) check3(s.uv);
  if (has(Pass::Mist)) check(s.mist);
  if (has(Pass::ObjectIndex)) check(s.object_index);
  if (has(Pass::MaterialIndex)) check(s.material_index);
  if (has(Pass::AO)) check3(s.ao);
  if (has(Pass::Vector))
    for (float v : {s.vector[0], s.vector[1], s.vector[2], s.vector[3], s.vector_weight}) check(v);
  if (layout_.cryptomatte) {
    check(s.crypto_weight);
    for (float c : s.crypto_id) ok &= std::isfinite(c);  // hashes: any finite float
  }
  if (layout_.shadow_catcher) {
    for (const Vec3& v : {s.catcher, s.matte, s.background}) check3(v);
    check(s.matte_transparent);
    check(s.catcher_split);
  }
  for (int i = 0; s.lightgroups && i < layout_.lightgroups; ++i) check3(s.lightgroups[i]);
  for (int i = 0; s.aovs && i < 4 * layout_.aovs; ++i) check(s.aovs[i]);
  return ok;
}

void Film::add(int x, int y, const SampleValue& s) {
  const size_t i = size_t(y) * width_ + x;
  const uint32_t n = count_[i] + 1;
  const bool half = n % 2 == 0;  // the pixel's 2nd, 4th, ... sample
  // Running means (Welford): a pixel whose samples are all equal keeps exactly that value and a
  // zero sum of squared deviations, which float sums (n * v rounded) would not.
  float* mean = &mean_[3 * i];
  const float inv_n = 1.0f / float(n);
  for (int k = 0; k < 3; ++k) {
    const float v = s.radiance[k], delta = v - mean[k];
    mean[k] += delta * inv_n;
    if (!m2_.empty()) m2_[3 * i + k] += delta * (v - mean[k]);
  }
  if (half) {
    const float inv_b = 1.0f / float(n / 2);
    for (int k = 0; k < 3; ++k) {
      const float v = s.radiance[k], delta = v - half_[3 * i + k];
      half_[3 * i + k] += delta * inv_b;
      if (!m2_half_.empty()) m2_half_[3 * i + k] += delta * (v - half_[3 * i + k]);
    }
  }
  if (!normal_.empty())
    for (int k = 0; k < 3; ++k) normal_[3 * i + k] += s.normal[k];
  if (!albedo_.empty())
    for (int k = 0; k < 3; ++k) albedo_[3 * i + k] += s.albedo[k];
  if (!feature_.empty()) {
    const float f[kFeatureChannels] = {s.feature_normal.x, s.feature_normal.y, s.feature_normal.z, s.albedo[0],
                                       s.albedo[1],        s.albedo[2],        s.feature_distance};
    float* sum = &feature_[kFeatureChannels * i];
    for (int k = 0; k < kFeatureChannels; ++k) sum[k] += f[k];
    if (half)
      for (int k = 0; k < kFeatureChannels; ++k) feature_half_[kFeatureChannels * i + k] += f[k];
  }
  for (const int j : summed_kept_) {
    std::vector<float>& a = sums_[j];
    const Pass p = Pass(j + kFirstSummedPass);
    if (j < kLightParts) {
      for (int k = 0; k < 3; ++k) a[3 * i + k] += s.light[j][k];
    } else if (p == Pass::UV) {
      for (int k = 0; k < 3; ++k) a[3 * i + k] += s.uv[k];
    } else if (p == Pass::Mist) {
      a[i] += s.mist;
    } else if (p == Pass::AO) {
      for (int k = 0; k < 3; ++k) a[3 * i + k] += s.ao[k];
    } else if (p == Pass::Vector) {
      for (int k = 0; k < 4; ++k) a[5 * i + k] += s.vector[k];
      a[5 * i + 4] += s.vector_weight;
    } else if (n == 1) {  // Position and the indices: the first sample's, as Cycles' sample 0
      if (p == Pass::Position)
        for (int k = 0; k < 3; ++k) a[3 * i + k] = s.position[k];
      else
        a[i] = p == Pass::ObjectIndex ? s.object_index : s.material_index;
    }
  }
  for (int t = 0; t < kCryptoTypes; ++t)
    if (!crypto_[t].empty()) {
      const int slots = layout_.cryptomatte_slots();
      cryptomatte_add(&crypto_[t][2 * slots * i], slots, s.crypto_id[t], s.crypto_weight);
    }
  if (!lightgroup_.empty() && s.lightgroups) {
    float* g = &lightgroup_[size_t(layout_.lightgroups) * 3 * i];
    for (int j = 0; j < layout_.lightgroups; ++j)
      for (int k = 0; k < 3; ++k) g[3 * j + k] += s.lightgroups[j][k];
  }
  if (!aov_.empty() && s.aovs) {
    float* a = &aov_[size_t(layout_.aovs) * 4 * i];
    for (int j = 0; j < 4 * layout_.aovs; ++j) a[j] += s.aovs[j];
  }
  if (!catcher_.empty()) {
    for (int k = 0; k < 3; ++k) {
      catcher_[3 * i + k] += s.catcher[k];
      matte_[4 * i + k] += s.matte[k];
      background_[3 * i + k] += s.background[k];
    }
    matte_[4 * i + 3] += s.matte_transparent;
    splits_[i] += s.catcher_split;
  }
  alpha_[i] += s.alpha;
  if (!depth_.empty()) depth_[i] = std::min(depth_[i], s.depth);
  count_[i] = n;
}

Film::SplatScales Film::splat_scales() const {
  SplatScales s;
  s.on = !splat_.empty() && light_paths_half_ > 0 && light_paths_ > light_paths_half_;
  if (s.on) {
    s.inv_la = 1.0 / double(light_paths_ - light_paths_half_);
    s.inv_lb = 1.0 / double(light_paths_half_);
    s.inv_l = 1.0 / double(light_paths_);
  }
  return s;
}

void Film::half_means(size_t i, const SplatScales& sc, double* a, double* b, double* mean) const {
  const double n = count_[i], nb = double(count_[i] / 2), na = n - nb;
  for (int k = 0; k < 3; ++k) {
    double m = mean_[3 * i + k], mb = half_[3 * i + k];
    double ma = (m * n - mb * nb) / na;
    if (sc.on) {
      const double s = splat_[3 * i + k], sb = splat_half_[3 * i + k];
      ma += (s - sb) * sc.inv_la;
      mb += sb * sc.inv_lb;
      m += s * sc.inv_l;
    }
    a[k] = ma;
    b[k] = mb;
    mean[k] = m;
  }
}

ErrorEstimate Film::error_estimate(int passes) const {
  ErrorEstimate e;
  if (passes < 2) return e;
  const SplatScales sc = splat_scales();
  // Per-row sums in parallel, added in row order: the same bits for any thread count.
  std::vector<double> row_var(height_, 0.0), row_sq(height_, 0.0);
  std::vector<uint64_t> row_skipped(height_, 0);
  tbb::parallel_for(0, height_, [&](int y) {
    double var_sum = 0, square_sum = 0;
    for (size_t i = size_t(y) * width_; i < size_t(y + 1) * width_; ++i) {
      const uint32_t count = count_[i];
      if (count < 2) {
        ++row_skipped[y];
        continue;
      }
      const double n = count, nb = double(count / 2), na = n - nb;
      double a[3], b[3], mean[3];
      half_means(i, sc, a, b, mean);
      for (int k = 0; k < 3; ++k) {
        const double d = a[k] - b[k];
        var_sum += d * d * na * nb / (n * n);
        square_sum += mean[k] * mean[k];
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
  const uint64_t n_pixels = count_.size() - e.unestimated_pixels;
  if (!n_pixels) return e;
  const double signal = square_sum - var_sum;
  e.mean_square = std::max(0.0, signal) / double(n_pixels);
  e.variance = var_sum;
  if (var_sum <= 0)
    e.rel_error = 0;
  else
    e.rel_error = signal > 0 ? std::sqrt(var_sum / signal) : std::numeric_limits<double>::infinity();
  return e;
}

void Film::half_variances(size_t i, const SplatScales& sc, const double* a, const double* b, double (*var)[3]) const {
  const double n = count_[i], nb = double(count_[i] / 2), na = n - nb, nh[2] = {na, nb};
  for (int k = 0; k < 3; ++k) {
    // Each half's sum of squared deviations: B's kept, A's from the total's by Chan et al.'s
    // pairwise update, M2 = M2_A + M2_B + (m_A - m_B)^2 n_A n_B / n, over the camera samples.
    const double mb = half_[3 * i + k], ma = (double(mean_[3 * i + k]) * n - mb * nb) / na, d = ma - mb;
    const double m2b = m2_half_[3 * i + k], m2a = double(m2_[3 * i + k]) - m2b - d * d * na * nb / n;
    const double m2[2] = {std::max(0.0, m2a), std::max(0.0, m2b)};
    // A half of one sample has no sample variance: the halves' difference, unbiased for
    // Var A + Var B = sigma^2 (1/n_A + 1/n_B), as before (its guide then depends on both halves).
    const double dh = a[k] - b[k], sigma2 = dh * dh / (1.0 / na + 1.0 / nb);
    for (int j = 0; j < 2; ++j) var[j][k] = nh[j] >= 2 ? m2[j] / ((nh[j] - 1.0) * nh[j]) : sigma2 / nh[j];
    if (!sc.on || splat_sq_.empty()) continue;
    // The splats' part, light paths as samples (one splat per path and pixel assumed): each half's
    // S_h / L_h has variance (Q_h - S_h^2 / L_h) / ((L_h - 1) L_h), Q_h its sum of squared splats.
    const double s = splat_[3 * i + k], sb = splat_half_[3 * i + k], sum[2] = {s - sb, sb};
    const double paths[2] = {1.0 / sc.inv_la, 1.0 / sc.inv_lb};
    for (int j = 0; j < 2; ++j) {
      const double q = splat_sq_[(2 * i + j) * 3 + k], l = paths[j];
      if (l >= 2) var[j][k] += std::max(0.0, q - sum[j] * sum[j] / l) / ((l - 1.0) * l);
    }
  }
}

HalfImages Film::half_images() const {
  if (feature_.empty()) throw StateError("this render does not keep the denoising features");
  HalfImages h;
  h.width = width_;
  h.height = height_;
  const size_t n = count_.size();
  for (int j = 0; j < 2; ++j) {  // zero (fresh pages), written in parallel below
    h.color[j].resize(3 * n);
    h.variance[j].resize(3 * n);
    h.feature[j].resize(kFeatureChannels * n);
  }
  h.valid.resize(n);
  const SplatScales sc = splat_scales();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      if (count_[i] < 2) continue;
      const double nb = double(count_[i] / 2), na = double(count_[i]) - nb;
      double a[3], b[3], mean[3];
      half_means(i, sc, a, b, mean);
      bool finite = true;
      double var[2][3];
      half_variances(i, sc, a, b, var);
      for (int k = 0; k < 3; ++k) {
        h.color[0][3 * i + k] = float(a[k]);
        h.color[1][3 * i + k] = float(b[k]);
        for (int j = 0; j < 2; ++j) {
          h.variance[j][3 * i + k] = float(var[j][k]);
          finite = finite && std::isfinite(float(var[j][k]));
        }
        finite = finite && std::isfinite(float(a[k])) && std::isfinite(float(b[k]));
      }
      for (int k = 0; k < kFeatureChannels; ++k) {
        const double sum = feature_[kFeatureChannels * i + k], sum_b = feature_half_[kFeatureChannels * i + k];
        h.feature[0][kFeatureChannels * i + k] = float((sum - sum_b) / na);
        h.feature[1][kFeatureChannels * i + k] = float(sum_b / nb);
      }
      h.valid[i] = finite;
    }
  });
  return h;
}

void Film::set_denoised(std::vector<float> rgb) {
  if (rgb.size() != 3 * count_.size()) throw InvalidArgument("denoised image of the wrong size");
  std::lock_guard<std::mutex> lock(mutex_);
  denoised_ = std::move(rgb);
}

double Film::pixel_variance(int x, int y) const {
  const size_t i = size_t(y) * width_ + x;
  if (count_[i] < 2) return 0;
  const double n = count_[i];
  double v = 0;
  for (int k = 0; k < 3; ++k) v += std::max(0.0, double(m2_[3 * i + k])) / ((n - 1.0) * n);
  return v;
}

void catcher_pass(const CatcherPixel& m, double* o) {
  o[0] = o[1] = o[2] = 1.0;
  if (m.split == 0) return;
  // The catchers' light with the other objects (Combined less the matte) over their light without
  // them, each channel 1 where the divisor is 0 (Cycles' safe_divide_shadow_catcher); then over
  // white by Combined's alpha, which hides the edges of catchers against a transparent film.
  const double alpha = std::clamp(m.alpha, 0.0, 1.0);
  for (int k = 0; k < 3; ++k) {
    const double ratio = m.catcher[k] != 0 ? (m.combined[k] - m.matte[k]) / m.catcher[k] : 1.0;
    o[k] = (1 - alpha) + alpha * ratio;
  }
}

void catcher_combined(const CatcherPixel& m, bool approximate, bool transparent, float* o) {
  const double alpha = std::clamp(1.0 - m.matte[3], 0.0, 1.0);
  for (int k = 0; k < 3; ++k) o[k] = float(m.matte[k] + m.splat[k]);
  o[3] = float(alpha);
  if (!approximate) return;
  // The shadow is 1 - the pass's average, the coverage of what the matte does not cover.
  double sc[3];
  catcher_pass(m, sc);
  const double alpha_matte = (1.0 - alpha) * (1.0 - std::clamp((sc[0] + sc[1] + sc[2]) / 3.0, 0.0, 1.0)) + alpha;
  if (transparent) {
    o[3] = float(alpha_matte);
    return;
  }
  for (int k = 0; k < 3; ++k) o[k] = float(m.matte[k] + m.splat[k] + m.background[k] * (1.0 - alpha_matte));
  o[3] = 1.0f;
}

const char* catcher_part_name(int part) {
  static const char* const kNames[] = {"CatcherCombined", "CatcherLight", "CatcherMatte", "CatcherSplit",
                                       "CatcherBackground"};
  return part >= 0 && part < kCatcherParts ? kNames[part] : nullptr;
}

const char* catcher_part_letters(int part) {
  static const char* const kLetters[] = {"RGBA", "RGB", "RGBA", "X", "RGB"};
  return part >= 0 && part < kCatcherParts ? kLetters[part] : nullptr;
}

CatcherPixel Film::catcher_pixel(size_t i) const {
  CatcherPixel m;
  const double inv = count_[i] ? 1.0 / count_[i] : 0.0;
  for (int k = 0; k < 3; ++k) {
    m.combined[k] = mean_[3 * i + k];
    m.catcher[k] = catcher_[3 * i + k] * inv;
    m.background[k] = background_[3 * i + k] * inv;
  }
  for (int k = 0; k < 4; ++k) m.matte[k] = matte_[4 * i + k] * inv;
  if (light_paths_ && !splat_.empty())
    for (int k = 0; k < 3; ++k) m.splat[k] = splat_[3 * i + k] / double(light_paths_);
  m.alpha = alpha_[i] * inv;
  m.split = splits_[i] * inv;
  return m;
}

bool Film::read_catcher_part(int part, float* out) const {
  std::unique_lock<std::mutex> lock = lock_accumulators();
  if (catcher_.empty() || part < 0 || part >= kCatcherParts) return false;
  const size_t n = count_.size();
  for (size_t i = 0; i < n; ++i) {
    const CatcherPixel m = catcher_pixel(i);
    const double* src[] = {m.combined, m.catcher, m.matte, &m.split, m.background};
    const int c = int(std::strlen(catcher_part_letters(part)));
    for (int k = 0; k < c; ++k) out[c * i + k] = float(part == kCatcherCombined && k == 3 ? m.alpha : src[part][k]);
  }
  return true;
}

void Film::resolve_combined(size_t i, float* o) const {
  const double inv = count_[i] ? 1.0 / count_[i] : 0.0;
  if (!catcher_.empty()) {
    if (count_[i])
      catcher_combined(catcher_pixel(i), layout_.catcher_approximate, layout_.transparent, o);
    else
      o[0] = o[1] = o[2] = o[3] = 0.0f;
    return;
  }
  const double splat_scale = light_paths_ && !splat_.empty() ? 1.0 / double(light_paths_) : 0.0;
  for (int k = 0; k < 3; ++k)
    o[k] = splat_scale > 0 ? float(double(mean_[3 * i + k]) + splat_[3 * i + k] * splat_scale) : mean_[3 * i + k];
  o[3] = float(alpha_[i] * inv);
}

void Film::publish(const std::vector<float>* denoised) {
  if (denoised && denoised->size() != 3 * count_.size()) throw InvalidArgument("denoised image of the wrong size");
  std::lock_guard<std::mutex> lock(mutex_);
  const size_t n = count_.size();
  // As read(Combined) once denoised: a matte (shadow catchers) is shown as rendered.
  const float* rgb = denoised && catcher_.empty() ? denoised->data() : nullptr;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      float o[4];
      resolve_combined(i, o);
      if (rgb)
        for (int k = 0; k < 3; ++k) o[k] = rgb[3 * i + k];
      for (int k = 0; k < 4; ++k) published_[4 * i + k] = float_to_half(o[k]);
    }
  });
  published_light_paths_ = light_paths_;
  published_valid_ = true;
  published_denoised_ = denoised != nullptr;  // as denoised() for the final image
}

void Film::read_published(float* out) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (size_t j = 0; j < published_.size(); ++j) out[j] = published_valid_ ? half_to_float(published_[j]) : 0.0f;
}

void Film::begin_writing() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return readers_waiting_ == 0; });
  writing_ = true;
}

void Film::end_writing() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    writing_ = false;
  }
  changed_.notify_all();
}

void Film::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    published_light_paths_ = light_paths_;
    finished_ = true;
    writing_ = false;
  }
  changed_.notify_all();
}

std::unique_lock<std::mutex> Film::lock_accumulators() const {
  std::unique_lock<std::mutex> lock(mutex_);
  if (writing_) {
    ++readers_waiting_;
    changed_.wait(lock, [&] { return !writing_; });
    --readers_waiting_;
    if (!readers_waiting_) changed_.notify_all();  // the next pass may start (after this read)
  }
  return lock;
}

const char* exr_pass_name(Pass p) {
  static const char* const kNames[] = {"DiffDir",  "DiffInd",  "DiffCol",      "GlossDir",  "GlossInd",  "GlossCol",
                                       "TransDir", "TransInd", "TransCol",     "VolumeDir", "VolumeInd", "Emit",
                                       "Env",      "Position", "UV",           "Mist",      "IndexOB",   "IndexMA",
                                       "AO",       "Vector",   "ShadowCatcher"};
  static_assert(sizeof(kNames) / sizeof(kNames[0]) == size_t(kSummedPasses), "a name per pass");
  return int(p) >= kFirstSummedPass && p < Pass::Count ? kNames[int(p) - kFirstSummedPass] : nullptr;
}

const char* exr_channel_letters(Pass p) {
  if (is_light_pass(p) || p == Pass::ShadowCatcher) return "RGB";
  switch (p) {
    case Pass::Position:
      return "XYZ";
    case Pass::UV:
      return "UVA";
    case Pass::Mist:
      return "Z";
    case Pass::AO:
      return "RGB";
    case Pass::Vector:
      return "XYZW";
    case Pass::ObjectIndex:
    case Pass::MaterialIndex:
      return "X";
    default:
      return nullptr;
  }
}

bool Film::has_light_passes() const {
  for (int j = 0; j < kLightParts; ++j)
    if (!sums_[j].empty()) return true;
  return false;
}

// Cycles' safe_divide_even_color (util/math.h): a channel whose divisor is zero takes the others'
// ratio, so that a colour with a zero channel still gives a grey light pass.
void divide_even_color(const double* a, const double* b, float* o) {
  double r[3];
  for (int k = 0; k < 3; ++k) r[k] = b[k] != 0 ? a[k] / b[k] : 0.0;
  const bool z[3] = {b[0] == 0, b[1] == 0, b[2] == 0};
  if (z[0] && z[1])
    r[0] = r[1] = r[2];
  else if (z[0] && z[2])
    r[0] = r[2] = r[1];
  else if (z[1] && z[2])
    r[1] = r[2] = r[0];
  else if (z[0])
    r[0] = 0.5 * (r[1] + r[2]);
  else if (z[1])
    r[1] = 0.5 * (r[0] + r[2]);
  else if (z[2])
    r[2] = 0.5 * (r[0] + r[1]);
  // A ratio past float range (a splat over a denormal Colour) stays the largest float, never inf.
  for (int k = 0; k < 3; ++k) o[k] = float(std::clamp(r[k], -double(FLT_MAX), double(FLT_MAX)));
}

void Film::read_summed(Pass pass, size_t i, float* o) const {
  const int j = int(pass) - kFirstSummedPass, c = pass_channels(pass);
  const std::vector<float>& a = sums_[j];
  const double inv = count_[i] ? 1.0 / count_[i] : 0.0;
  if (pass == Pass::Position || pass == Pass::ObjectIndex || pass == Pass::MaterialIndex) {
    for (int k = 0; k < c; ++k) o[k] = a[c * i + k];
    return;
  }
  if (pass == Pass::Mist) {
    // Cycles accumulates 1 - mist and negates it when reading (film/data_passes.h).
    o[0] = float(1.0 - a[i] * inv);
    return;
  }
  if (pass == Pass::Vector) {  // the mean over the samples that wrote one (film/read.h)
    const double w = a[5 * i + 4];
    for (int k = 0; k < 4; ++k) o[k] = w > 0 ? float(a[5 * i + k] / w) : 0.0f;
    return;
  }
  double v[3];
  for (int k = 0; k < c; ++k) v[k] = a[c * i + k] * inv;
  if (is_light_pass(pass) && !light_splat_[j].empty() && light_paths_)
    for (int k = 0; k < 3; ++k) v[k] += light_splat_[j][3 * i + k] / double(light_paths_);
  const Pass colour = light_pass_color(pass);
  if (colour == Pass::Count) {
    for (int k = 0; k < c; ++k) o[k] = float(v[k]);
    return;
  }
  // Direct and Indirect are divided by their Colour, as Cycles reads them (film/read.h), so that
  // (Direct + Indirect) x Colour gives the light back.
  const std::vector<float>& col = sums_[int(colour) - kFirstSummedPass];
  const double b[3] = {col[3 * i] * inv, col[3 * i + 1] * inv, col[3 * i + 2] * inv};
  divide_even_color(v, b, o);
}

void Film::read_cryptomatte_rows(int type, int layer, int y0, int rows, float* out) const {
  if (type < 0 || type >= kCryptoTypes || !has_cryptomatte(type))
    throw StateError(std::string("this render does not keep the ") + cryptomatte_type_name(type) +
                     " passes (not enabled when it started)");
  const int slots = layout_.cryptomatte_slots();
  if (layer < 0 || 2 * layer >= slots)
    throw InvalidArgument("Cryptomatte layer " + std::to_string(layer) + " is not within the render's " +
                          std::to_string(slots / 2) + " layers");
  if (y0 < 0 || rows < 0 || y0 > height_ - rows)
    throw InvalidArgument("rows " + std::to_string(y0) + " to " + std::to_string(y0 + rows) +
                          " are not within the film's " + std::to_string(height_) + " rows");
  std::unique_lock<std::mutex> lock = lock_accumulators();
  const size_t first = size_t(y0) * width_, n = size_t(rows) * width_;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<float> pairs(2 * size_t(slots));
    for (size_t j = r.begin(); j < r.end(); ++j) {
      const size_t i = first + j;
      std::copy_n(&crypto_[type][2 * slots * i], 2 * slots, pairs.data());
      cryptomatte_sort(pairs.data(), slots);
      // Weights are sums over the samples: their mean is the coverage (Cycles' film_get_pass_pixel_cryptomatte).
      const float inv = count_[i] ? 1.0f / float(count_[i]) : 0.0f;
      float* o = out + 4 * j;
      o[0] = pairs[4 * layer];
      o[1] = pairs[4 * layer + 1] * inv;
      o[2] = pairs[4 * layer + 2];
      o[3] = pairs[4 * layer + 3] * inv;
    }
  });
}

bool Film::read_light_tracing(float* out) const {
  std::unique_lock<std::mutex> lock = lock_accumulators();
  if (!light_paths_ || splat_.empty()) return false;
  const double scale = 1.0 / double(light_paths_);
  for (size_t i = 0; i < splat_.size(); ++i) out[i] = float(splat_[i] * scale);
  return true;
}

bool Film::read_light_tracing(Pass pass, float* out) const {
  std::unique_lock<std::mutex> lock = lock_accumulators();
  if (!is_light_pass(pass) || !light_paths_) return false;
  const std::vector<float>& a = light_splat_[int(pass) - kFirstSummedPass];
  if (a.empty()) return false;
  const double scale = 1.0 / double(light_paths_);
  for (size_t i = 0; i < a.size(); ++i) out[i] = float(a[i] * scale);
  return true;
}

bool Film::read_vector_coverage(float* out) const {
  std::unique_lock<std::mutex> lock = lock_accumulators();
  const std::vector<float>& a = sums_[int(Pass::Vector) - kFirstSummedPass];
  if (a.empty()) return false;
  for (size_t i = 0; i < count_.size(); ++i) out[i] = count_[i] ? float(double(a[5 * i + 4]) / count_[i]) : 0.0f;
  return true;
}

void Film::read_lightgroup_rows(int group, int y0, int rows, float* out) const {
  if (group < 0 || group >= layout_.lightgroups)
    throw InvalidArgument("light group " + std::to_string(group) + " is not one of the render's " +
                          std::to_string(layout_.lightgroups));
  if (y0 < 0 || rows < 0 || y0 > height_ - rows)
    throw InvalidArgument("rows " + std::to_string(y0) + " to " + std::to_string(y0 + rows) +
                          " are not within the film's " + std::to_string(height_) + " rows");
  std::unique_lock<std::mutex> lock = lock_accumulators();
  const size_t first = size_t(y0) * width_, n = size_t(rows) * width_, g = size_t(layout_.lightgroups);
  const double per_path = light_paths_ && !lightgroup_splat_.empty() ? 1.0 / double(light_paths_) : 0.0;
  for (size_t j = 0; j < n; ++j) {
    const size_t i = first + j, at = (i * g + size_t(group)) * 3;
    const double inv = count_[i] ? 1.0 / count_[i] : 0.0;
    for (int k = 0; k < 3; ++k)
      out[3 * j + k] = float(lightgroup_[at + k] * inv + (per_path > 0 ? lightgroup_splat_[at + k] * per_path : 0.0));
  }
}

void Film::read_aov_rows(int index, int channels, int y0, int rows, float* out) const {
  if (index < 0 || index >= layout_.aovs || channels < 1 || channels > 4)
    throw InvalidArgument("AOV " + std::to_string(index) + " is not one of the render's " +
                          std::to_string(layout_.aovs));
  if (y0 < 0 || rows < 0 || y0 > height_ - rows)
    throw InvalidArgument("rows " + std::to_string(y0) + " to " + std::to_string(y0 + rows) +
                          " are not within the film's " + std::to_string(height_) + " rows");
  std::unique_lock<std::mutex> lock = lock_accumulators();
  const size_t first = size_t(y0) * width_, n = size_t(rows) * width_, per = size_t(layout_.aovs) * 4;
  for (size_t j = 0; j < n; ++j) {
    const size_t i = first + j;
    const double inv = count_[i] ? 1.0 / count_[i] : 0.0;
    for (int k = 0; k < channels; ++k)
      out[size_t(channels) * j + k] = float(aov_[i * per + 4 * size_t(index) + k] * inv);
  }
}

bool Film::read_lightgroup_light_tracing(int group, float* out) const {
  std::unique_lock<std::mutex> lock = lock_accumulators();
  if (lightgroup_splat_.empty() || !light_paths_ || group < 0 || group >= layout_.lightgroups) return false;
  const size_t n = size_t(width_) * height_, g = size_t(layout_.lightgroups);
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
      out[3 * i + k] = float(lightgroup_splat_[(i * g + size_t(group)) * 3 + k] / double(light_paths_));
  return true;
}

uint64_t Film::total_samples() const {
  std::unique_lock<std::mutex> lock = lock_accumulators();
  uint64_t n = 0;
  for (uint32_t c : count_) n += c;
  return n;
}

namespace {
const char* pass_name(Pass p) {
  static const char* const kNames[] = {"Combined",
                                       "Depth",
                                       "Normal",
                                       "Albedo",
                                       "Variance",
                                       "Sample Count",
                                       "Noisy Image",
                                       "Denoising Normal",
                                       "Denoising Albedo",
                                       "Denoising Depth",
                                       "DiffDir",
                                       "DiffInd",
                                       "DiffCol",
                                       "GlossDir",
                                       "GlossInd",
                                       "GlossCol",
                                       "TransDir",
                                       "TransInd",
                                       "TransCol",
                                       "VolumeDir",
                                       "VolumeInd",
                                       "Emit",
                                       "Env",
                                       "Position",
                                       "UV",
                                       "Mist",
                                       "IndexOB",
                                       "IndexMA",
                                       "AO",
                                       "Vector",
                                       "Shadow Catcher"};
  static_assert(sizeof(kNames) / sizeof(kNames[0]) == size_t(Pass::Count), "a name per pass");
  return unsigned(p) < unsigned(Pass::Count) ? kNames[int(p)] : "?";
}
}  // namespace

void Film::read_rows(Pass pass, int y0, int rows, float* out, bool labels) const {
  if (!has(pass))
    throw StateError(std::string("this render does not keep the ") + pass_name(pass) +
                     " pass (not enabled when it started)");
  if (y0 < 0 || rows < 0 || y0 > height_ - rows)
    throw InvalidArgument("rows " + std::to_string(y0) + " to " + std::to_string(y0 + rows) +
                          " are not within the film's " + std::to_string(height_) + " rows");
  const int c = pass_channels(pass);
  // Pixels [first, first + n) of the film; out[j * c] is pixel first + j.
  const size_t first = size_t(y0) * width_, n = size_t(rows) * width_;
  std::unique_lock<std::mutex> lock(mutex_);
  const bool published = !finished_ && pass == Pass::Combined;
  if (!published) {
    lock.unlock();
    lock = lock_accumulators();
  }
  if (published) {
    const uint16_t* p = published_.data() + 4 * first;
    for (size_t j = 0; j < 4 * n; ++j) out[j] = published_valid_ ? half_to_float(p[j]) : 0.0f;
  } else {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t j = r.begin(); j < r.end(); ++j) {
        const size_t i = first + j;
        float* o = out + j * c;
        const double inv = count_[i] ? 1.0 / count_[i] : 0.0;
        switch (pass) {
          case Pass::Combined:
            resolve_combined(i, o);
            // The denoiser sees the full image: a matte (shadow catchers) is read as rendered.
            if (!denoised_.empty() && catcher_.empty())
              for (int k = 0; k < 3; ++k) o[k] = denoised_[3 * i + k];
            break;
          case Pass::NoisyImage:
            resolve_combined(i, o);
            break;
          case Pass::DenoisingNormal:
          case Pass::DenoisingAlbedo:
          case Pass::DenoisingDepth: {
            const int first_channel = pass == Pass::DenoisingNormal ? 0 : pass == Pass::DenoisingAlbedo ? 3 : 6;
            for (int k = 0; k < c; ++k) o[k] = float(feature_[kFeatureChannels * i + first_channel + k] * inv);
            break;
          }
          case Pass::Depth:
            o[0] = depth_[i];
            break;
          case Pass::Normal:
            // The mean of the samples' normals, as in Cycles (not renormalised: shorter at edges), so
            // that sample-split parts average into the full render's pass.
            for (int k = 0; k < 3; ++k) o[k] = float(normal_[3 * i + k] * inv);
            break;
          case Pass::Albedo:
            for (int k = 0; k < 3; ++k) o[k] = float(albedo_[3 * i + k] * inv);
            break;
          case Pass::Variance:
            // Variance of the pixel mean: the unbiased sample variance over n.
            for (int k = 0; k < 3; ++k)
              o[k] =
                  count_[i] > 1 ? float(std::max(0.0, double(m2_[3 * i + k])) / ((count_[i] - 1.0) * count_[i])) : 0.0f;
            break;
          case Pass::SampleCount:
            o[0] = float(count_[i]);
            break;
          case Pass::ShadowCatcher: {
            double sc[3] = {1, 1, 1};
            if (!catcher_.empty()) catcher_pass(catcher_pixel(i), sc);
            for (int k = 0; k < 3; ++k) o[k] = float(sc[k]);
            break;
          }
          case Pass::Count:
            break;
          default:
            read_summed(pass, i, o);
            break;
        }
      }
    });
  }
  if ((pass != Pass::Combined && pass != Pass::NoisyImage) || !labels || labels_.empty()) return;
  for (size_t j = 0; j < n; ++j)
    if (labels_[first + j] != kLabelNone) {
      const float v = labels_[first + j] == kLabelWhite ? 1.0f : 0.0f;
      out[4 * j] = out[4 * j + 1] = out[4 * j + 2] = v;
      out[4 * j + 3] = 1.0f;
    }
}

}  // namespace lt

namespace lt {

void Film::read_strategy_grid(int columns, int rows, float* out, int y0, int count) const {
  const int gw = columns * width_;
  if (count < 0) count = rows * height_ - y0;
  const double splat_scale = light_paths_ ? 1.0 / double(light_paths_) : 0.0;
  for (int gy = y0; gy < y0 + count; ++gy) {
    // Grid row gy: cell row d (depth 0 at the top: the last rows), pixel row y of each cell.
    const int d = rows - 1 - gy / height_, y = gy % height_;
    for (int s = 0; s < columns; ++s) {
      const int cell = d * columns + s;
      for (int x = 0; x < width_; ++x) {
        const size_t i = size_t(y) * width_ + x;
        const uint32_t n = count_[i];
        float* o = out + (size_t(gy - y0) * gw + size_t(s) * width_ + x) * 3;
        for (int k = 0; k < 3; ++k) {
          const size_t at = (i * layout_.strategy_cells + cell) * 3 + k;
          double v = strategy_splats_[at] * splat_scale;
          if (n) v += strategies_[at] / double(n);
          o[k] = float(v);
        }
      }
    }
  }
}

}  // namespace lt
