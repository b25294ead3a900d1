#include "media/phase.h"

#include <string>

#include "core/error.h"

namespace lt {

namespace {
inline double clamp_g(float g) { return clamp(double(g), -double(PhaseHG::kMaxG), double(PhaseHG::kMaxG)); }
}  // namespace

float hg_phase(float cos_theta, float g_in) {
  // Double: for |g| -> 1 the denominator 1 + g^2 + 2 g cos cancels to (1 - |g|)^2 near the peak.
  double g = clamp_g(g_in), c = clamp(double(cos_theta), -1.0, 1.0);
  double denom = 1 + g * g + 2 * g * c;
  return float((1 - g * g) / (4 * double(kPi) * denom * std::sqrt(denom)));
}

float PhaseHG::eval(const Vec3& wo, const Vec3& wi) const { return hg_phase(dot(wo, wi), g); }

bool PhaseHG::sample(const Vec3& wo, Vec2 u, Vec3* wi, float* pdf) const {
  if (!is_finite(wo)) return false;
  const double gd = clamp_g(g);
  // cos of the angle between wo and wi: the HG cdf in cos inverted in closed form.
  double cos_theta;
  if (std::abs(gd) < 1e-3) {
    cos_theta = 1 - 2 * double(u.x);
  } else {
    double s = (1 - gd * gd) / (1 + gd - 2 * gd * double(u.x));
    cos_theta = -(1 + gd * gd - s * s) / (2 * gd);
  }
  cos_theta = clamp(cos_theta, -1.0, 1.0);
  double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
  double phi = 2 * double(kPi) * double(u.y);
  Frame frame(wo);
  *wi = normalize(
      frame.to_world(Vec3(float(sin_theta * std::cos(phi)), float(sin_theta * std::sin(phi)), float(cos_theta))));
  // The pdf of the direction actually returned (after rounding), so that pdf == eval exactly.
  *pdf = eval(wo, *wi);
  return true;
}

Phase Phase::hg(float g) {
  Phase p;
  p.g[0] = float(clamp_g(g));
  return p;
}

Phase Phase::mixture(const float* g, const float* weight, int n) {
  Phase p;
  p.count = 0;
  double total = 0;
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(weight[i]) || weight[i] < 0 || !std::isfinite(g[i]))
      throw InvalidArgument("phase lobe " + std::to_string(i) + ": weight must be finite and >= 0, g finite");
    if (weight[i] == 0) continue;
    const float gi = float(clamp_g(g[i]));
    int k = 0;
    while (k < p.count && p.g[k] != gi) ++k;  // equal anisotropy: one lobe (as Cycles merges them)
    if (k == p.count) {
      if (p.count == kMaxLobes)
        throw InvalidArgument("a volume mixes more than " + std::to_string(kMaxLobes) +
                              " scattering lobes of different anisotropy");
      p.g[k] = gi;
      p.weight[k] = 0;
      ++p.count;
    }
    p.weight[k] += weight[i];
    total += weight[i];
  }
  if (p.count == 0) throw InvalidArgument("a phase mixture needs a lobe with weight > 0");
  for (int k = 0; k < p.count; ++k) p.weight[k] = float(p.weight[k] / total);
  if (p.count == 1) p.weight[0] = 1;
  return p;
}

float Phase::eval_mixture(float cos_theta) const {
  float v = 0;
  for (int k = 0; k < count; ++k) v += weight[k] * hg_phase(cos_theta, g[k]);
  return v;
}

bool Phase::sample(const Vec3& wo, Vec2 u, Vec3* wi, float* pdf) const {
  int k = 0;
  if (count > 1) {
    // Pick lobe k with probability weight[k]; rescale u.x into [0, 1) for the lobe's own sample.
    float c = 0;
    for (; k < count - 1; ++k) {
      if (u.x < c + weight[k]) break;
      c += weight[k];
    }
    u.x = std::min((u.x - c) / weight[k], 0.99999994f);
    if (!(u.x >= 0)) u.x = 0;
  }
  float lobe_pdf;
  if (!PhaseHG{g[k]}.sample(wo, u, wi, &lobe_pdf)) return false;
  *pdf = count == 1 ? lobe_pdf : eval(wo, *wi);
  return true;
}

}  // namespace lt
