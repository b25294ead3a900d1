#include "scene/phase.h"

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
  *wi = normalize(frame.to_world(
      Vec3(float(sin_theta * std::cos(phi)), float(sin_theta * std::sin(phi)), float(cos_theta))));
  // The pdf of the direction actually returned (after rounding), so that pdf == eval exactly.
  *pdf = eval(wo, *wi);
  return true;
}

}  // namespace lt
