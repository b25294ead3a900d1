// Piecewise-constant distributions in 1D and 2D, sampled by inverting their CDFs (pbrt 3,
// section 13.6.7). Used for light selection, the pixel filter and environment maps.
#pragma once

#include <vector>

#include "core/sampling.h"

namespace lt {

class Distribution1D {
 public:
  Distribution1D() = default;
  explicit Distribution1D(std::vector<float> f) : func_(std::move(f)), cdf_(func_.size() + 1) {
    cdf_[0] = 0;
    size_t n = func_.size();
    for (size_t i = 0; i < n; ++i) {
      float v = std::isfinite(func_[i]) ? std::max(0.0f, func_[i]) : 0.0f;
      func_[i] = v;
      cdf_[i + 1] = cdf_[i] + double(v) / double(n);
    }
    integral_ = cdf_[n];
    if (integral_ == 0) {  // all zero: sample uniformly
      for (size_t i = 1; i <= n; ++i) cdf_[i] = double(i) / double(n);
    } else {
      for (size_t i = 1; i <= n; ++i) cdf_[i] /= integral_;
    }
    // Guide table: for each of n equal slices of u, the bin where the search can start, so that
    // inverting the CDF is exact and O(1) on average instead of a binary search.
    guide_.resize(n);
    size_t i = 0;
    for (size_t k = 0; k < n; ++k) {
      double u = double(k) / double(n);
      while (i + 1 < n && cdf_[i + 1] <= u) ++i;
      guide_[k] = uint32_t(i);
    }
  }
  size_t size() const { return func_.size(); }
  double integral() const { return integral_; }
  // Continuous sample in [0,1); pdf with respect to [0,1).
  float sample_continuous(float u, float* pdf, int* offset = nullptr) const {
    int i = find(u);
    if (offset) *offset = i;
    double du = u - cdf_[i];
    double w = cdf_[i + 1] - cdf_[i];
    if (w > 0) du /= w;
    *pdf = integral_ > 0 ? float(func_[i] / integral_) : 1.0f;
    return std::min(kOneMinusEpsilon, float((i + du) / double(size())));
  }
  // Discrete sample; pdf is the probability of the returned index.
  int sample_discrete(float u, float* pmf, float* u_remapped = nullptr) const {
    int i = find(u);
    double w = cdf_[i + 1] - cdf_[i];
    *pmf = float(w);
    if (u_remapped) *u_remapped = w > 0 ? std::min(kOneMinusEpsilon, float((u - cdf_[i]) / w)) : 0.0f;
    return i;
  }
  float discrete_pmf(int i) const { return float(cdf_[i + 1] - cdf_[i]); }
  float func(int i) const { return func_[i]; }

 private:
  int find(float u) const {
    // Largest i with cdf_[i] <= u, restricted to [0, n-1].
    const size_t n = func_.size();
    size_t lo = guide_[std::min(n - 1, size_t(double(u) * double(n)))];
    while (lo + 1 < n && cdf_[lo + 1] <= u) ++lo;
    // Skip zero-width bins so a sample never lands where the function is zero.
    while (lo + 1 < func_.size() && cdf_[lo + 1] - cdf_[lo] <= 0) ++lo;
    return int(lo);
  }
  std::vector<float> func_;
  std::vector<double> cdf_;
  std::vector<uint32_t> guide_;
  double integral_ = 0;
};

// 2D distribution over [0,1)^2 as a marginal in v and conditionals in u.
class Distribution2D {
 public:
  Distribution2D() = default;
  Distribution2D(const std::vector<float>& f, int nu, int nv) : nu_(nu), nv_(nv) {
    std::vector<float> marginal(nv);
    conditional_.reserve(nv);
    for (int v = 0; v < nv; ++v) {
      conditional_.emplace_back(std::vector<float>(f.begin() + size_t(v) * nu, f.begin() + size_t(v + 1) * nu));
      marginal[v] = float(conditional_.back().integral());
    }
    marginal_ = Distribution1D(marginal);
  }
  Vec2 sample(Vec2 u, float* pdf) const {
    float pdf_v, pdf_u;
    int v;
    float y = marginal_.sample_continuous(u.y, &pdf_v, &v);
    float x = conditional_[v].sample_continuous(u.x, &pdf_u);
    *pdf = pdf_u * pdf_v;
    return {x, y};
  }
  float pdf(Vec2 p) const {
    int iu = clamp(int(p.x * nu_), 0, nu_ - 1), iv = clamp(int(p.y * nv_), 0, nv_ - 1);
    double integral = marginal_.integral();
    if (integral <= 0) return 1.0f;
    return float(conditional_[iv].func(iu) / integral);
  }

 private:
  int nu_ = 0, nv_ = 0;
  std::vector<Distribution1D> conditional_;
  Distribution1D marginal_;
};

}  // namespace lt
