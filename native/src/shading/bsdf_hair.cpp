// Hair lobes (bsdf.h: PrincipledHair, HairReflection, HairTransmission) in the local frame of the
// shading point (+Z the curve's normal facing wo, lobe.hair_tangent the curve's direction).
//
// Principled Hair: Chiang, Bitterli, Tappan and Burley, "A Practical and Controllable Hair and Fur
// Model for Production Path Tracing" (EGSR 2016), as Cycles 3.4 implements it
// (kernel/closure/bsdf_hair_principled.h): the longitudinal Mp of d'Eon et al. 2011, a trimmed
// logistic azimuthal Np, R, TT, TRT and a residual TRRT+ lobe, the cuticle tilt alpha shifting
// the first three. Its h (the offset across the fibre) comes from wo, as Cycles' from sd->I.
// Hair BSDF: Cycles' older Marschner-style reflection and transmission (kernel/closure/bsdf_hair.h),
// whose value is its (approximate) pdf.
//
// Cycles' closures return f cos; Lantern's f excludes the cosine (the integrator multiplies
// |wi.z|), so each value here is divided by |wi.z|.
#include <cmath>
#include <cstring>

#include "shading/bsdf.h"

namespace lt {

namespace {

inline float cos_from_sin(float s) { return safe_sqrt(1 - s * s); }
inline float safe_asin(float x) { return std::asin(clamp(x, -1.0f, 1.0f)); }
inline float safe_acos(float x) { return std::acos(clamp(x, -1.0f, 1.0f)); }
inline float sqr(float x) { return x * x; }

float delta_phi(int p, float gamma_o, float gamma_t) { return 2.0f * p * gamma_t - 2.0f * gamma_o + p * kPi; }
float wrap_angle(float a) { return (a + kPi) - 2 * kPi * std::floor((a + kPi) / (2 * kPi)) - kPi; }
float logistic(float x, float s) {
  const float v = std::exp(-std::abs(x) / s);
  return v / (s * sqr(1 + v));
}
float logistic_cdf(float x, float s) {
  const float arg = -x / s;
  return arg > 88.0f ? 0.0f : 1.0f / (1.0f + std::exp(arg));
}
float bessel_I0(float x) {
  x = x * x;
  float val = 1 + 0.25f * x, pow_x_2i = x * x;
  uint64_t i_fac_2 = 1;
  int pow_4_i = 16;
  for (int i = 2; i < 10; ++i) {
    i_fac_2 *= uint64_t(i * i);
    const float next = val + pow_x_2i / (float(pow_4_i) * float(i_fac_2));
    if (val == next) return val;
    val = next;
    pow_x_2i *= x;
    pow_4_i *= 4;
  }
  return val;
}
float log_bessel_I0(float x) {
  if (x > 12.0f) return x + 0.5f * (1.0f / (8.0f * x) - std::log(2 * kPi) - std::log(x));
  return std::log(bessel_I0(x));
}
// The logistic restricted to [-pi, pi] and renormalised; c = logistic_cdf(-pi, s).
float trimmed_logistic(float x, float s, float c) {
  const float scale = 1 - 2 * c;
  return scale > 0 ? logistic(x, s) / scale : 0.0f;
}
float sample_trimmed_logistic(float u, float s, float c) {
  const float x = -s * std::log(1 / (u * (1 - 2 * c) + c) - 1);
  return clamp(x, -kPi, kPi);
}
// What d'Eon et al.'s Mp needs of a variance v alone (kept per lobe parameters: HairTerms).
struct MpTerms {
  float v, inv_v, tail;      // tail: log(1 / (2 v)) for v <= 0.1, else 2 v sinh(1 / v)
  float exp_m2v;             // exp(-2 / v), for sampling
  double inv_v_exact, norm;  // longitudinal_exact's 1 / v and 1 / (v (1 - exp(-2 / v)))
};
MpTerms mp_terms(float v) {
  MpTerms t;
  t.v = v;
  t.inv_v = 1 / v;
  t.tail = v <= 0.1f ? std::log(0.5f * t.inv_v) : std::sinh(t.inv_v) * 2 * v;
  t.exp_m2v = std::exp(-2 / v);
  t.inv_v_exact = 1 / double(v);
  t.norm = 1 / (double(v) * -std::expm1(-2 / double(v)));
  return t;
}
// d'Eon et al.'s Mp for variance v (the log form for small v avoids overflow).
float longitudinal(float sin_i, float cos_i, float sin_o, float cos_o, const MpTerms& m) {
  const float cos_arg = cos_i * cos_o * m.inv_v, sin_arg = sin_i * sin_o * m.inv_v;
  if (m.v <= 0.1f) return std::exp(log_bessel_I0(cos_arg) - sin_arg - m.inv_v + 0.6931f + m.tail);
  return std::exp(-sin_arg) * bessel_I0(cos_arg) / m.tail;
}
// I0(|x|) exp(-s) for s >= |x| (to rounding), with I0 to 5e-7 relative (Abramowitz and Stegun
// 9.8.1 and 9.8.2; measured against std::cyl_bessel_i over 0 .. 700, which took 15 times as
// long: 14 % of a hair render). The large-x form keeps exp(|x| - s) whole, so it cannot overflow.
double bessel_I0_times_exp(double x, double s) {
  x = std::abs(x);  // I0 is even
  if (x <= 3.75) {
    const double t = (x / 3.75) * (x / 3.75);
    return (1 +
            t * (3.5156229 + t * (3.0899424 + t * (1.2067492 + t * (0.2659732 + t * (0.0360768 + t * 0.0045813)))))) *
           std::exp(-s);
  }
  const double t = 3.75 / x;
  const double p =
      0.39894228 +
      t * (0.01328592 +
           t * (0.00225319 +
                t * (-0.00157565 +
                     t * (0.00916281 + t * (-0.02057706 + t * (0.02635537 + t * (-0.01647633 + t * 0.00392377)))))));
  return p / std::sqrt(x) * std::exp(x - s);
}
// The same Mp with an accurate I0 (Cycles' series stops after 10 terms, a few percent low near
// its switch to the asymptotic form at 12): the density d'Eon's sampling draws exactly, for pdfs.
// x - b - 1 / v = (cos(theta_i + theta_o) - 1) / v <= 0 in double: no cancellation to float.
float longitudinal_exact(float sin_i, float cos_i, float sin_o, float cos_o, const MpTerms& m) {
  const double x = double(cos_i) * cos_o / m.v, b = double(sin_i) * sin_o / m.v;
  return float(bessel_I0_times_exp(x, b + m.inv_v_exact) * m.norm);
}
// The density over solid angle of the elevation principled_sample draws for a lobe: theta' from
// Mp cos theta', then theta' + delta, folded back over the pole (sin kept, |cos|). Each theta'
// that lands on theta_i (elevation e, sin_i and cos_i) adds Mp(theta') cos theta'; the solid angle
// divides by cos theta_i.
float tilted_density(float e, float cos_i, float sin_o, float cos_o, const MpTerms& m, float delta) {
  if (!(cos_i > 0)) return 0;
  float sum = 0;
  for (float t : {e - delta, kPi - e - delta, -kPi - e - delta}) {
    if (std::abs(t) > 0.5f * kPi) continue;
    const float c = std::cos(t);
    sum += longitudinal_exact(std::sin(t), c, sin_o, cos_o, m) * c;
  }
  return sum / cos_i;
}
// sin and cos of the cuticle angle alpha, 2 alpha and 4 alpha.
struct Tilt {
  float s1, c1, s2, c2, s4, c4;
};
Tilt tilt_terms(float alpha) {
  Tilt t;
  t.s1 = std::sin(alpha);
  t.c1 = cos_from_sin(t.s1);
  t.s2 = 2 * t.s1 * t.c1;
  t.c2 = t.c1 * t.c1 - t.s1 * t.s1;
  t.s4 = 2 * t.s2 * t.c2;
  t.c4 = t.c2 * t.c2 - t.s2 * t.s2;
  return t;
}
// sin and cos of theta_i tilted by the cuticle angle for R (2 alpha), TT (-alpha), TRT (-4 alpha).
void alpha_angles(float sin_i, float cos_i, const Tilt& a, float out[6]) {
  const float s1 = a.s1, c1 = a.c1, s2 = a.s2, c2 = a.c2, s4 = a.s4, c4 = a.c4;
  out[0] = sin_i * c2 + cos_i * s2;
  out[1] = std::abs(cos_i * c2 - sin_i * s2);
  out[2] = sin_i * c1 - cos_i * s1;
  out[3] = std::abs(cos_i * c1 + sin_i * s1);
  out[4] = sin_i * c4 - cos_i * s4;
  out[5] = std::abs(cos_i * c4 + sin_i * s4);
}

// The fibre frame of Cycles' bsdf_principled_hair_setup: X along the curve, Y normal to X and wo,
// Z = X x Y; h the sine of the angle between the normal and Z seen along X.
struct HairFrame {
  Vec3 x, y, z;
  float h;
};
bool hair_frame(const Lobe& l, const Vec3& wo, HairFrame* f) {
  f->x = l.hair_tangent;
  const Vec3 y = cross(f->x, wo);
  const float ly = length(y);
  if (!(ly > 1e-7f) || !is_finite(f->x)) return false;
  f->y = y / ly;
  f->z = normalize(cross(f->x, f->y));
  f->h = clamp(dot(cross(Vec3(0, 0, 1), f->x), f->z), -1.0f, 1.0f);
  return true;
}

// The angles of wo in the fibre frame and what depends on them alone.
struct HairOut {
  float sin_o, cos_o, phi_o, gamma_o, gamma_t;
  Spectrum ap[4];
  float ap_energy[4];
};
void hair_out(const Lobe& l, const HairFrame& f, const Vec3& wo, HairOut* o) {
  const float eta = l.eta;
  o->sin_o = dot(wo, f.x);
  o->cos_o = cos_from_sin(o->sin_o);
  o->phi_o = std::atan2(dot(wo, f.z), dot(wo, f.y));
  const float sin_t = o->sin_o / eta, cos_t = cos_from_sin(sin_t);
  const float sin_gamma_o = f.h, cos_gamma_o = cos_from_sin(sin_gamma_o);
  o->gamma_o = safe_asin(sin_gamma_o);
  const float sin_gamma_t = sin_gamma_o * o->cos_o / std::sqrt(eta * eta - o->sin_o * o->sin_o);
  const float cos_gamma_t = cos_from_sin(sin_gamma_t);
  o->gamma_t = safe_asin(sin_gamma_t);
  Spectrum T;
  for (int k = 0; k < 3; ++k) T[k] = std::exp(-l.hair_sigma[k] * (2 * cos_gamma_t / cos_t));
  // Attenuations of R, TT, TRT and the TRRT+ geometric series (Chiang et al. eq. 3-4).
  const float fr = fresnel_dielectric(o->cos_o * cos_gamma_o, eta);
  o->ap[0] = Spectrum(fr);
  Spectrum col = (1 - fr) * (1 - fr) * T;
  o->ap[1] = col;
  col = col * T * fr;
  o->ap[2] = col;
  Spectrum tf = T * fr, rest;
  for (int k = 0; k < 3; ++k) rest[k] = tf[k] < 1 ? tf[k] / (1 - tf[k]) : 0.0f;
  o->ap[3] = col * rest;
  float total = 0;
  for (int p = 0; p < 4; ++p) total += (o->ap_energy[p] = luminance(o->ap[p]));
  for (int p = 0; p < 4; ++p) o->ap_energy[p] = total > 0 ? o->ap_energy[p] / total : 0.0f;
}

// What a lobe's parameters determine: the Mp terms of each variance, the logistic's trim and the
// tilt. Kept per thread for the last parameters (the same for every vertex of a material without
// textured inputs), compared bit for bit: a pure function of them, so renders stay the same bits.
struct HairTerms {
  MpTerms tt, r, trt, coat;  // variances v / 4, v, 4 v and the R lobe's m0
  float cdf_pi;              // logistic_cdf(-pi, s)
  Tilt tilt, untilt;         // alpha and -alpha
};
const HairTerms& hair_terms(const Lobe& l) {
  thread_local struct {
    float key[4];
    bool valid = false;
    HairTerms t;
  } last;
  const float key[4] = {l.hair_roughness, l.hair_m0, l.hair_radial, l.hair_tilt};
  if (last.valid && std::memcmp(key, last.key, sizeof key) == 0) return last.t;
  std::memcpy(last.key, key, sizeof key);
  last.valid = true;
  HairTerms& t = last.t;
  const float v = l.hair_roughness;
  t.tt = mp_terms(0.25f * v);
  t.r = mp_terms(v);
  t.trt = mp_terms(4 * v);
  t.coat = mp_terms(l.hair_m0);
  t.cdf_pi = logistic_cdf(-kPi, l.hair_radial);
  t.tilt = tilt_terms(l.hair_tilt);
  t.untilt = tilt_terms(-l.hair_tilt);
  return t;
}

// What a lobe and wo determine: the fibre frame, wo's angles and attenuations. A vertex asks three
// times (the light's eval, the sample, the sampled direction's eval): the last is kept per thread,
// as hair_terms.
struct HairSetup {
  bool ok;
  HairFrame f;
  HairOut o;
};
const HairSetup& hair_setup(const Lobe& l, const Vec3& wo) {
  thread_local struct {
    float key[10];
    bool valid = false;
    HairSetup s;
  } last;
  const float key[10] = {wo.x,
                         wo.y,
                         wo.z,
                         l.hair_tangent.x,
                         l.hair_tangent.y,
                         l.hair_tangent.z,
                         l.eta,
                         l.hair_sigma[0],
                         l.hair_sigma[1],
                         l.hair_sigma[2]};
  if (last.valid && std::memcmp(key, last.key, sizeof key) == 0) return last.s;
  std::memcpy(last.key, key, sizeof key);
  last.valid = true;
  HairSetup& s = last.s;
  s.ok = hair_frame(l, wo, &s.f);
  if (s.ok) hair_out(l, s.f, wo, &s.o);
  return s;
}

// The share of uniform-sphere samples in principled_sample: F, whose tilted Mp lacks the
// Jacobian, is not proportional to the d'Eon sampling density where the untilted angle nears the
// fibre's axis (F / pdf grows like 1 / cos theta', a variance without bound: fireflies in hair);
// a defensive mixture (Hesterberg 1995) bounds it.
constexpr float kDefensive = 0.05f;

// F = sum of Ap Mp Np (Cycles' f cos) and the density of principled_sample: the lobe choice by
// ap_energy times each lobe's Mp (sampled with variance v, also for R) and Np. Cycles 3.4 returns
// F's own energy weights as the pdf, which is not the density it samples when the R lobe has the
// coat's roughness or the cuticle tilts the lobes; the ratio f / pdf then biases it by a few
// percent. Here the pdf is the density, so the estimate of F is unbiased.
Spectrum principled_eval(const Lobe& l, const Vec3& wo, const Vec3& wi, float* pdf) {
  *pdf = 0;
  const HairSetup& s = hair_setup(l, wo);
  if (!s.ok) return Spectrum(0.0f);
  const HairFrame& f = s.f;
  const HairOut& o = s.o;
  const HairTerms& t = hair_terms(l);
  const float sin_i = dot(wi, f.x), cos_i = cos_from_sin(sin_i);
  const float phi = std::atan2(dot(wi, f.z), dot(wi, f.y)) - o.phi_o;
  float ang[6];
  alpha_angles(sin_i, cos_i, t.tilt, ang);
  const float e = std::asin(clamp(sin_i, -1.0f, 1.0f));  // theta_i
  const MpTerms* sampled[3] = {&t.r, &t.tt, &t.trt};
  const MpTerms* valued[3] = {&t.coat, &t.tt, &t.trt};
  Spectrum F(0.0f);
  float p_total = 0;
  for (int p = 0; p < 3; ++p) {
    const float np = trimmed_logistic(wrap_angle(phi - delta_phi(p, o.gamma_o, o.gamma_t)), l.hair_radial, t.cdf_pi);
    const float mp = longitudinal(ang[2 * p], ang[2 * p + 1], o.sin_o, o.cos_o, *valued[p]);
    F += o.ap[p] * (mp * np);
    const float delta = p == 0 ? -2 * l.hair_tilt : p == 1 ? l.hair_tilt : 4 * l.hair_tilt;
    p_total += o.ap_energy[p] * tilted_density(e, cos_i, o.sin_o, o.cos_o, *sampled[p], delta) * np;
  }
  F += o.ap[3] * (longitudinal(sin_i, cos_i, o.sin_o, o.cos_o, t.trt) * (0.5f * kInvPi));
  p_total += o.ap_energy[3] * longitudinal_exact(sin_i, cos_i, o.sin_o, o.cos_o, t.trt) * (0.5f * kInvPi);
  *pdf = kDefensive * (0.25f * kInvPi) + (1 - kDefensive) * p_total;
  return F;
}

bool principled_sample(const Lobe& l, const Vec3& wo, Vec2 u, float u_extra, Vec3* wi) {
  const HairSetup& s = hair_setup(l, wo);
  if (!s.ok) return false;
  const HairFrame& f = s.f;
  const HairOut& o = s.o;
  const HairTerms& t = hair_terms(l);
  if (u_extra < kDefensive) {
    *wi = sample_uniform_sphere(u);
    return true;
  }
  // u_extra picks the lobe; what is left of it, rescaled, is the azimuthal sample.
  int p = 0;
  float ux = (u_extra - kDefensive) / (1 - kDefensive);
  for (; p < 3; ++p) {
    if (ux < o.ap_energy[p]) break;
    ux -= o.ap_energy[p];
  }
  const float u_phi = clamp(o.ap_energy[p] > 0 ? ux / o.ap_energy[p] : 0.5f, 0.0f, kOneMinusEpsilon);
  const MpTerms& m = p == 0 ? t.r : p == 1 ? t.tt : t.trt;
  // d'Eon et al.'s Mp sampling (as Cycles).
  const float u1 = std::max(u.x, 1e-5f);
  const float fac = 1 + m.v * std::log(u1 + (1 - u1) * m.exp_m2v);
  float sin_i = -fac * o.sin_o + cos_from_sin(fac) * std::cos(2 * kPi * u.y) * o.cos_o;
  float cos_i = cos_from_sin(sin_i);
  if (p < 3) {
    float ang[6];
    alpha_angles(sin_i, cos_i, t.untilt, ang);
    sin_i = ang[2 * p];
    cos_i = ang[2 * p + 1];
  }
  const float phi = p < 3 ? delta_phi(p, o.gamma_o, o.gamma_t) + sample_trimmed_logistic(u_phi, l.hair_radial, t.cdf_pi)
                          : 2 * kPi * u_phi;
  const float phi_i = o.phi_o + phi;
  *wi = f.x * sin_i + f.y * (cos_i * std::cos(phi_i)) + f.z * (cos_i * std::sin(phi_i));
  return is_finite(*wi);
}

// Cycles' bsdf_hair.h: theta measured from the normal plane of the tangent, the azimuth about it.
struct OldHair {
  float theta_r, theta_i, cos_phi, a, b;
  bool ok;
};
OldHair old_hair_angles(const Lobe& l, const Vec3& wo, const Vec3& wi) {
  OldHair h{};
  const Vec3& T = l.hair_tangent;
  const float iz = dot(T, wo), wz = dot(T, wi);
  const Vec3 locy = normalize(wo - T * iz), wy = normalize(wi - T * wz);
  h.theta_r = 0.5f * kPi - safe_acos(iz);
  h.theta_i = 0.5f * kPi - safe_acos(wz);
  h.cos_phi = dot(wy, locy);
  const float r1 = l.hair_roughness;
  h.a = std::atan(((0.5f * kPi + h.theta_r) * 0.5f - l.hair_tilt) / r1);
  h.b = std::atan(((-0.5f * kPi + h.theta_r) * 0.5f - l.hair_tilt) / r1);
  h.ok = is_finite(locy) && is_finite(wy) && 0.5f * kPi - std::abs(h.theta_i) >= 0.001f;
  return h;
}
float old_theta_pdf(const Lobe& l, const OldHair& h) {
  const float t = (h.theta_i + h.theta_r) * 0.5f - l.hair_tilt, r1 = l.hair_roughness;
  return r1 / (2 * (t * t + r1 * r1) * (h.a - h.b) * std::cos(h.theta_i));
}
// Cycles' hair reflection and transmission: the value (Cycles' eval, which it also calls its
// pdf) and the density old_hair_sample draws. They differ only for transmission: Cycles samples
// the azimuth on |pi - phi| <= pi/2 but evaluates it on all of [0, pi] (more than 1 in all);
// here the azimuth is sampled over the whole range, with the same Cauchy shape renormalised.
float old_hair_value(const Lobe& l, const Vec3& wo, const Vec3& wi, float* pdf) {
  *pdf = 0;
  const bool reflect = l.type == LobeType::HairReflection;
  if ((wi.z >= 0) != reflect || (reflect && wi.z == 0)) return 0;
  const OldHair h = old_hair_angles(l, wo, wi);
  if (!h.ok) return 0;
  const float r2 = l.hair_radial, theta_pdf = old_theta_pdf(l, h);
  float value;
  if (reflect) {
    if (h.cos_phi < 0) return 0;
    float phi = safe_acos(h.cos_phi) / r2;
    phi = std::abs(phi) < kPi ? phi : kPi;
    value = std::cos(phi * 0.5f) * 0.25f / r2 * theta_pdf;
    *pdf = value;
  } else {
    const float p = kPi - safe_acos(h.cos_phi), cauchy = r2 / (p * p + r2 * r2);
    value = cauchy / (2 * std::atan(0.5f * kPi / r2)) * theta_pdf;
    *pdf = cauchy / (2 * std::atan(kPi / r2)) * theta_pdf;
  }
  if (!(std::isfinite(value) && value > 0 && std::isfinite(*pdf))) *pdf = value = 0;
  return value;
}
// Cycles' sampling of theta; the azimuth sampled from the density old_hair_value states.
// (Cycles' reflection sampler draws phi = 2 r2 asin(1 - 2 u) but states its pdf for r2 = 1.)
bool old_hair_sample(const Lobe& l, const Vec3& wo, Vec2 u, Vec3* wi) {
  const Vec3& T = l.hair_tangent;
  const float iz = dot(T, wo);
  const Vec3 locy = normalize(wo - T * iz), locx = cross(locy, T);
  if (!is_finite(locy)) return false;
  const float theta_r = 0.5f * kPi - safe_acos(iz), r1 = l.hair_roughness, r2 = l.hair_radial;
  const float a = std::atan(((0.5f * kPi + theta_r) * 0.5f - l.hair_tilt) / r1);
  const float b = std::atan(((-0.5f * kPi + theta_r) * 0.5f - l.hair_tilt) / r1);
  const float t = r1 * std::tan(u.x * (a - b) + b);
  const float theta_i = 2 * (t + l.hair_tilt) - theta_r;
  float phi;
  if (l.type == LobeType::HairReflection) {
    // Density cos(phi / (2 r2)) / (4 r2) on |phi| <= pi r2, kept where the value is (|phi| <= pi/2).
    phi = 2 * r2 * safe_asin(1 - 2 * u.y);
    if (std::abs(phi) > 0.5f * kPi) return false;
  } else {
    phi = r2 * std::tan(2 * std::atan(kPi / r2) * (u.y - 0.5f)) + kPi;
  }
  const float ct = std::cos(theta_i), st = std::sin(theta_i);
  *wi = locy * (std::cos(phi) * ct) - locx * (std::sin(phi) * ct) + T * st;
  return is_finite(*wi);
}

}  // namespace

Spectrum hair_eval(const Lobe& l, const Vec3& wo, const Vec3& wi, float* pdf) {
  *pdf = 0;
  // A direction in the normal's plane has no cosine to divide by (a set of measure zero).
  if (!(std::abs(wi.z) > 1e-7f)) return Spectrum(0.0f);
  if (l.type == LobeType::PrincipledHair) {
    const Spectrum F = principled_eval(l, wo, wi, pdf);
    return l.weight * F / std::abs(wi.z);
  }
  return l.weight * (old_hair_value(l, wo, wi, pdf) / std::abs(wi.z));
}

bool hair_sample(const Lobe& l, const Vec3& wo, Vec2 u, float u_extra, Vec3* wi) {
  if (l.type == LobeType::PrincipledHair) return principled_sample(l, wo, u, u_extra, wi);
  return old_hair_sample(l, wo, u, wi);
}

}  // namespace lt
