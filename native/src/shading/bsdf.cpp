// BSDF lobes and their mixture (see bsdf.h). Formulas follow Cycles 3.4's closures so that the same
// material renders to the same mean image:
//   Diffuse      bsdf_diffuse (Lambert) / bsdf_oren_nayar (Fujii's improved Oren-Nayar, as Cycles)
//   GlossyGGX    bsdf_microfacet_ggx, no Fresnel, separable Smith G = G1(wo) G1(wi); anisotropic
//                D and G1 (Heitz 2014) with alpha_x along +X
//   Dielectric   Cycles' Glass BSDF node: a GGX reflection closure weighted by F(wo.n) and a GGX
//                refraction closure (Walter et al. 2007) weighted by 1 - F(wo.n), F the exact
//                dielectric Fresnel at the macro normal; no 1/eta^2 radiance scaling. The
//                Principled glass's refraction takes refraction_tint (the base colour) and its
//                reflection interpolate_fresnel_color towards glass_f0, as Cycles' two closures.
//                glass_part keeps one closure: the Principled glass's reflection (x F) or
//                refraction (x max(1e-4, 1 - F), Cycles' refraction_fresnel) when the refraction
//                has a roughness of its own, or the Refraction BSDF node (refraction alone, no
//                Fresnel factor: bsdf_refraction, bsdf_microfacet_{ggx,beckmann} REFRACTION_ID)
//   SpecularGGX  bsdf_microfacet_ggx_fresnel_setup as the Principled BSDF sets it up: GGX
//                reflection times interpolate_fresnel_color, f0 (1 - FH) + FH with
//                FH = (F(wi.m, eta) - F(1, eta)) / (1 - F(1, eta)), F the dielectric Fresnel
//   Transparent  bsdf_transparent
//   PrincipledDiffuse  bsdf_principled_diffuse (Burley 2012), its components (DiffusePart)
//   Subsurface   a BSSRDF: no value here; Bsdf::sample hands it to the walk (integrators/subsurface.h)
//   GlossyBeckmann, DielectricBeckmann  bsdf_microfacet_beckmann: Beckmann D, f with Cycles'
//                rational G1 (bsdf_beckmann_G1); sampled from the exact visible normals, so the pdf
//                carries the exact (erf) G1
//   AshikhminShirley  bsdf_ashikhmin_shirley (half-vector sampling of cos^n, Cycles' "pump")
//   Clearcoat    bsdf_microfacet_ggx with CLEARCOAT_ID: D_GTR1(alpha), G1 of GGX at alpha 0.25,
//                interpolate_fresnel_color at IOR 1.5, cspec0 0.04; sampled from GTR1 D cos
//   Sheen        bsdf_principled_sheen: f = schlick_fresnel(wi.h) (Cycles' eval is that times cos)
//   Velvet       bsdf_ashikhmin_velvet, sampled uniformly over the hemisphere as Cycles does
//   Translucent  bsdf_translucent
//   DiffuseToon, GlossyToon  bsdf_toon: a uniform cone of half angle min(size + smooth, pi/2) (x pi/2)
//                about the normal or the mirror direction, intensity 1 to size, a ramp to
//                size + smooth
//   MultiGGX     bsdf_microfacet_multi_ggx (glossy, no Fresnel): f is mf_eval's estimate (analytic
//                single scattering + one random walk seeded by the direction pair); sampled from a
//                known mixture, as Cycles' own walk has no pdf. Cycles' sample weight is the walk's
//                escape probability (1 for white), its eval's mean lower at high roughness (0.85 at
//                alpha 1, normal incidence): Lantern follows eval's mean for both strategies.
//                With ms_fresnel the Principled specular (..._multi_ggx_fresnel).
//   MultiGGXGlass  bsdf_microfacet_multi_ggx_glass(_fresnel): the walk with a dielectric phase
//                function, sampled from a known mixture; where Cycles' evaluation departs from
//                its walk (eta^2, the reversed walk's IOR) Lantern follows the walk.
// Cycles' closures return f cos(wi); here f excludes it. Where Cycles' sample() disagrees with its
// eval() (clearcoat sampled from GGX, anisotropic Beckmann sampled isotropically, toon's ramp read
// at a random angle), f is eval()'s and the sampling is exact for the pdf reported.
// Microfacet normals are sampled from the distribution of visible normals (Heitz 2018, "Sampling
// the GGX Distribution of Visible Normals"), so the sampling weight is G1(wi) (times Fresnel).
//
// Every lobe is defined relative to the hemisphere wo lies in: when wo is below the surface
// (wo.z < 0: a reverse evaluation from the far side, or a bent shading normal) the frame is
// mirrored (z -> -z), so that reflection stays on wo's side and refraction goes to the other one,
// and glass sees the inverse relative IOR 1/eta from there. Cycles instead returns black for
// microfacet closures below the shading normal; mirroring keeps every routine finite and BDPT's
// reverse pdfs consistent with sampling from the other side.
#include "shading/bsdf.h"

#include <cstring>
#include <optional>

namespace lt {

namespace {

// Below |eta - 1| the refraction lobe is narrower than anything the float maths can resolve; the
// interface is then treated as smooth (Cycles uses 1e-4 the same way).
constexpr float kEtaDeltaEpsilon = 1e-3f;
// The narrow axis of an anisotropic lobe is kept at least this wide, so D stays finite in float.
constexpr float kMinAxisAlpha = 1e-6f;
constexpr float kInvSqrtPi = 0.56418958354775628f;

inline Vec3 flip_z(const Vec3& v) { return {v.x, v.y, -v.z}; }

inline float clamp_alpha(float a) { return a >= 0 ? std::min(a, 1.0f) : 0.0f; }  // NaN -> 0
inline float lobe_alpha(const Lobe& l) { return clamp_alpha(l.alpha); }
inline float lobe_alpha_y(const Lobe& l) { return l.alpha_y >= 0 ? std::min(l.alpha_y, 1.0f) : lobe_alpha(l); }
inline float lobe_eta(const Lobe& l) { return (l.eta > 0 && std::isfinite(l.eta)) ? l.eta : 1.0f; }
inline float lobe_sigma(const Lobe& l) { return l.roughness > 0 ? std::min(l.roughness, 1.0f) : 0.0f; }

inline bool is_glass(const Lobe& l) { return lobe_is_glass(l.type); }

// The lobe as seen from below (-Z): the frame is mirrored, and glass's relative IOR inverts, since
// eta is the IOR of the -Z side over the +Z side. This is what a reverse evaluation needs (BDPT's
// pdf of the opposite direction through glass), and it keeps bent shading normals finite.
// tmp is only made for glass: a Lobe's defaults are some 40 stores, on every sample and evaluation.
const Lobe& lobe_from_below(const Lobe& l, std::optional<Lobe>* tmp) {
  if (!is_glass(l)) return l;
  tmp->emplace(l);
  (*tmp)->eta = 1 / lobe_eta(l);
  return **tmp;
}

// Microfacet alphas below which the lobe is a mirror: the isotropic threshold kSmoothAlpha, and
// for anisotropic lobes the same area alpha_x alpha_y (Cycles tests alpha_x alpha_y <= 1e-7).
bool microfacet_smooth(const Lobe& l) {
  const float ax = lobe_alpha(l), ay = lobe_alpha_y(l);
  if (ax == ay) return !(ax >= kSmoothAlpha);
  return !(ax * ay >= kSmoothAlpha * kSmoothAlpha);
}

// Ashikhmin-Shirley's alphas as bsdf_ashikhmin_shirley_setup clamps them.
inline float as_alpha(float a) { return clamp(a, 1e-4f, 1.0f); }
bool as_smooth(const Lobe& l) { return !(std::max(as_alpha(lobe_alpha(l)), as_alpha(lobe_alpha_y(l))) > 1e-4f); }

// Multiscatter GGX's alphas as bsdf_microfacet_multi_ggx_common_setup clamps them.
inline float ms_alpha(float a) { return clamp(a, 1e-4f, 1.0f); }
struct MsAlpha {
  float x, y;
};
MsAlpha ms_alphas(const Lobe& l) { return {ms_alpha(lobe_alpha(l)), ms_alpha(lobe_alpha_y(l))}; }
inline float ms_glass_alpha(const Lobe& l) { return ms_alpha(lobe_alpha(l)); }  // isotropic, as Cycles
bool ms_smooth(const Lobe& l) {
  const MsAlpha a = ms_alphas(l);
  return a.x * a.y < 1e-7f;
}

// Toon: the half angles of full intensity and of the ramp's end, and of the sampled cone.
struct Toon {
  float max_angle, smooth, cone, cos_cone, one_minus_cos_cone;
};
Toon toon_params(const Lobe& l) {
  Toon t;
  t.max_angle = (l.toon_size > 0 ? std::min(l.toon_size, 1.0f) : 0.0f) * (kPi / 2);
  t.smooth = (l.toon_smooth > 0 ? std::min(l.toon_smooth, 1.0f) : 0.0f) * (kPi / 2);
  t.cone = std::min(t.max_angle + t.smooth, kPi / 2);
  t.cos_cone = std::cos(t.cone);
  const float h = std::sin(t.cone / 2);
  t.one_minus_cos_cone = 2 * h * h;  // accurate for narrow cones
  return t;
}
// bsdf_toon_get_intensity.
float toon_intensity(const Toon& t, float angle) {
  if (angle < t.max_angle) return 1;
  if (angle < t.max_angle + t.smooth && t.smooth != 0) return 1 - (angle - t.max_angle) / t.smooth;
  return 0;
}
inline bool toon_black(const Lobe& l) { return !(toon_params(l).cone > 0); }

bool lobe_is_delta(const Lobe& l) {
  switch (l.type) {
    case LobeType::Diffuse:
    case LobeType::PrincipledDiffuse:
    case LobeType::Sheen:
    case LobeType::Velvet:
    case LobeType::Translucent:
    case LobeType::DiffuseToon:
    case LobeType::GlossyToon:
    case LobeType::PrincipledHair:
    case LobeType::HairReflection:
    case LobeType::HairTransmission:
    case LobeType::Subsurface:
      return false;
    case LobeType::GlossyGGX:
    case LobeType::SpecularGGX:
    case LobeType::GlossyBeckmann:
    case LobeType::Clearcoat:
      return microfacet_smooth(l);
    case LobeType::AshikhminShirley:
      return as_smooth(l);
    case LobeType::MultiGGX:
      return ms_smooth(l);
    case LobeType::MultiGGXGlass: {
      const float a = ms_glass_alpha(l), eta = lobe_eta(l);
      return a * a < 1e-7f || std::abs(eta - 1) < kEtaDeltaEpsilon || std::abs(1 / eta - 1) < kEtaDeltaEpsilon;
    }
    case LobeType::Dielectric:
    case LobeType::DielectricBeckmann: {
      float eta = lobe_eta(l);  // symmetric in eta and 1/eta, so both sides agree
      return microfacet_smooth(l) || std::abs(eta - 1) < kEtaDeltaEpsilon || std::abs(1 / eta - 1) < kEtaDeltaEpsilon;
    }
    case LobeType::Transparent:
      return true;
  }
  return true;
}

// ---- microfacet distributions ------------------------------------------------------------------

// GGX's G1(w) / |w.z|, finite down to w.z = 0 (then 2 / (alpha_w sin)).
inline float ggx_G1_over_cos(const Vec3& w, float alpha) {
  float c = std::abs(w.z);
  float s2 = w.x * w.x + w.y * w.y;
  float d = c + std::sqrt(alpha * alpha * s2 + c * c);
  return d > 0 ? 2 / d : 0;
}
inline float ggx_G1_over_cos(const Vec3& w, float ax, float ay) {
  if (ax == ay) return ggx_G1_over_cos(w, ax);
  float c = std::abs(w.z);
  float r2 = sqr(ax * w.x) + sqr(ay * w.y);
  float d = c + std::sqrt(r2 + c * c);
  return d > 0 ? 2 / d : 0;
}

// Beckmann's exact G1(w) / |w.z| = 1 / ((1 + Lambda) c), with (1 + Lambda) c = c (1 + erf mu) / 2
// + r exp(-mu^2) / (2 sqrt(pi)), r = alpha_w sin, mu = c / r: finite at grazing angles.
inline float beckmann_G1_over_cos(const Vec3& w, float ax, float ay) {
  float c = std::abs(w.z);
  float r = std::sqrt(sqr(ax * w.x) + sqr(ay * w.y));
  if (!(r > 0)) return c > 0 ? 1 / c : 0;
  float mu = c / r;
  float d = 0.5f * c * (1 + std::erf(mu)) + 0.5f * kInvSqrtPi * r * std::exp(-mu * mu);
  return d > 0 ? 1 / d : 0;
}
// Cycles 3.4's bsdf_beckmann_G1 / bsdf_beckmann_aniso_G1 (Walter et al. 2007, eq. 27) over |w.z|:
// 1 for a = c / r >= 1.6, else (3.535 a + 2.181 a^2) / (1 + 2.276 a + 2.577 a^2).
inline float beckmann_G1_cycles_over_cos(const Vec3& w, float ax, float ay) {
  float c = std::abs(w.z);
  float r = std::sqrt(sqr(ax * w.x) + sqr(ay * w.y));
  if (r < 0.625f * c) return 1 / c;
  if (!(r > 0)) return 0;
  float a = c / r;
  return (2.181f * a + 3.535f) / (r * ((2.577f * a + 2.276f) * a + 1));
}

struct Micro {
  bool beckmann;
  float ax, ay;
};
Micro lobe_micro(const Lobe& l) {
  Micro mf{l.type == LobeType::GlossyBeckmann || l.type == LobeType::DielectricBeckmann, lobe_alpha(l),
           lobe_alpha_y(l)};
  if (mf.ax != mf.ay) {
    mf.ax = std::max(mf.ax, kMinAxisAlpha);
    mf.ay = std::max(mf.ay, kMinAxisAlpha);
  }
  return mf;
}
inline float micro_D(const Micro& mf, const Vec3& m) {
  if (mf.beckmann) return beckmann_D(m, mf.ax, mf.ay);
  return mf.ax == mf.ay ? ggx_D(m, mf.ax) : ggx_D(m, mf.ax, mf.ay);
}
// G1 / cos of the sampling routine (exact Smith), which the pdf needs.
inline float micro_g1_pdf(const Micro& mf, const Vec3& w) {
  return mf.beckmann ? beckmann_G1_over_cos(w, mf.ax, mf.ay) : ggx_G1_over_cos(w, mf.ax, mf.ay);
}
// G1 / cos of Cycles' f (the same for GGX; Cycles' rational fit for Beckmann).
inline float micro_g1_f(const Micro& mf, const Vec3& w) {
  return mf.beckmann ? beckmann_G1_cycles_over_cos(w, mf.ax, mf.ay) : ggx_G1_over_cos(w, mf.ax, mf.ay);
}
inline Vec3 micro_sample(const Micro& mf, const Vec3& o, Vec2 u) {
  return mf.beckmann ? beckmann_sample_visible_normal(o, mf.ax, mf.ay, u)
                     : ggx_sample_visible_normal(o, mf.ax, mf.ay, u);
}

// The inverse of the visible-slope CDF of the unit-roughness Beckmann distribution seen from
// (sin s, 0, cos c): the density of the slope x is (c - s x) exp(-x^2) on x < c / s, whose CDF
// is c sqrt(pi) (1 + erf x) / 2 + s exp(-x^2) / 2. (c, s) = (1, 0) gives erf^-1 (2u - 1) scaled
// for exp(-x^2). Safeguarded Newton in double precision.
double beckmann_slope(double c, double s, double u) {
  constexpr double kHalfSqrtPi = 0.88622692545275801;
  constexpr double kBound = 6;  // exp(-36): no mass beyond
  auto cdf = [&](double x) { return c * kHalfSqrtPi * (1 + std::erf(x)) + 0.5 * s * std::exp(-x * x); };
  double lo = -kBound, hi = s > 0 ? std::min(c / s, kBound) : kBound;
  const double target = u * cdf(hi);
  double x = std::min(0.0, 0.5 * hi);
  for (int k = 0; k < 100 && hi - lo > 1e-12; ++k) {
    const double f = cdf(x) - target;
    if (f > 0)
      hi = x;
    else
      lo = x;
    const double d = (c - s * x) * std::exp(-x * x);
    double next = x - f / d;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - x) < 1e-13) {
      x = next;
      break;
    }
    x = next;
  }
  return x;
}

// ---- Diffuse ---------------------------------------------------------------------------------
// o and i with o.z > 0. Cycles' bsdf_oren_nayar_get_intensity (Fujii 2012's improved Oren-Nayar
// with sigma = roughness): f = A + B s / t, s = i.o - cos_i cos_o, t = max(cos_i, cos_o) if s > 0
// else 1, A = 1 / (pi + (pi/2 - 2/3) sigma), B = sigma A. sigma = 0 gives Lambert's 1/pi.
Spectrum diffuse_eval(const Lobe& l, const Vec3& o, const Vec3& i) {
  if (i.z <= 0) return Spectrum(0.0f);
  float sigma = lobe_sigma(l);
  if (sigma == 0) return l.weight * kInvPi;
  float a = 1 / (kPi + (kPi / 2 - 2.0f / 3.0f) * sigma);
  float b = sigma * a;
  float s = dot(i, o) - i.z * o.z;
  if (s > 0) s /= std::max(std::max(i.z, o.z), 1e-7f);  // Cycles adds FLT_MIN; this bounds f at grazing
  return l.weight * std::max(0.0f, a + b * s);
}

// Schlick's weight (1 - c)^5 with c clamped to [0, 1] (Cycles' schlick_fresnel).
inline float schlick_weight(float c) {
  const float m = clamp(1 - c, 0.0f, 1.0f);
  return (m * m) * (m * m) * m;
}

// Burley 2012 ("Physically Based Shading at Disney", eq. 4 with its retro-reflection), as Cycles
// 3.4's bsdf_principled_diffuse with PRINCIPLED_DIFFUSE_FULL: f = (1/pi) [(1 - FV/2)(1 - FL/2)
// + RR (FL + FV + FL FV (RR - 1))], FL = (1 - cos_i)^5, FV = (1 - cos_o)^5, RR = roughness (1 + i.o)
// (= 2 roughness (i.h)^2). Equal to Burley's (1 + (Fd90 - 1) FL)(1 + (Fd90 - 1) FV) with Fd90 =
// 1/2 + RR. o.z > 0.
Spectrum principled_diffuse_eval(const Lobe& l, const Vec3& o, const Vec3& i) {
  if (i.z <= 0) return Spectrum(0.0f);
  const float r = lobe_sigma(l);  // the roughness, clamped to [0, 1] as Cycles' node does
  const float fl = schlick_weight(i.z), fv = schlick_weight(o.z);
  const float rr = r * (1 + dot(i, o));
  const float lambert = l.diffuse_part == DiffusePart::LambertExit ? 1 - 0.5f * fl : (1 - 0.5f * fv) * (1 - 0.5f * fl);
  const float retro = rr * (fl + fv + fl * fv * (rr - 1));
  // Cycles' bsdf_principled_diffuse_compute_brdf by component.
  float f = lambert + retro;
  if (l.diffuse_part == DiffusePart::Lambert || l.diffuse_part == DiffusePart::LambertExit) f = lambert;
  if (l.diffuse_part == DiffusePart::RetroReflection) f = retro;
  return l.weight * (kInvPi * f);
}

// ---- microfacet reflection (GGX / Beckmann glossy, SpecularGGX, glass's reflection) ------------
// f = D G1(o) G1(i) / (4 cos_o cos_i) (Cycles' separable Smith G), pdf = D_o(m) / (4 o.m)
// = G1(o) D / (4 cos_o). Both from the half vector of (o, i) so sample() and pdf() agree.
// below: also for i under the shading normal (Cycles' sampling extension, Bsdf::sample_below_shading).
float micro_reflect(const Vec3& o, const Vec3& i, const Micro& mf, float* pdf, float* cos_oh, bool below = false) {
  *pdf = 0;
  if ((i.z <= 0 && !(below && i.z < 0)) || o.z <= 0) return 0;
  Vec3 h = o + i;
  float len = length(h);
  if (!(len > 0)) return 0;
  Vec3 m = h / len;
  float d = micro_D(mf, m);
  *pdf = 0.25f * micro_g1_pdf(mf, o) * d;
  if (cos_oh) *cos_oh = clamp(dot(o, m), 0.0f, 1.0f);
  return 0.25f * d * micro_g1_f(mf, o) * micro_g1_f(mf, i);
}

// o mirrored about the microfacet m (c = o.m > 0).
bool reflect_about(const Vec3& o, const Vec3& m, float c, Vec3* i, bool below = false) {
  *i = normalize(m * (2 * c) - o);
  return (i->z > 0 || (below && i->z < 0)) && is_finite(*i);
}
bool micro_sample_reflect(const Vec3& o, const Micro& mf, Vec2 u, Vec3* i, bool below = false) {
  Vec3 m = micro_sample(mf, o, u);
  float c = dot(o, m);
  if (!(c > 0)) return false;
  return reflect_about(o, m, c, i, below);
}

// ---- microfacet refraction (Walter et al. 2007, eq. 21 without Fresnel and without 1/eta^2) ---
// o.z > 0 on the side of relative IOR 1, i.z < 0 inside (relative IOR eta). The generalised half
// vector is m = +-normalize(o + eta i), oriented to m.z > 0; the pair is valid only if o.m > 0 and
// i.m < 0. f = D G1(o) G1(i) eta^2 |o.m| |i.m| / (cos_o cos_i (o.m + eta i.m)^2),
// pdf = D_o(m) eta^2 |i.m| / (o.m + eta i.m)^2 (the Jacobian of the refraction map).
float micro_refract(const Vec3& o, const Vec3& i, const Micro& mf, float eta, float* pdf, float* cos_om = nullptr) {
  *pdf = 0;
  if (i.z >= 0 || o.z <= 0) return 0;
  Vec3 ht = o + i * eta;
  float len2 = length_squared(ht);
  if (!(len2 > 0)) return 0;
  Vec3 m = ht / std::sqrt(len2);
  if (m.z < 0) m = -m;
  float om = dot(o, m), im = dot(i, m);
  if (!(om > 0) || !(im < 0)) return 0;
  if (cos_om) *cos_om = om;
  float d = micro_D(mf, m);
  float jac = eta * eta * -im / len2;
  *pdf = micro_g1_pdf(mf, o) * om * d * jac;
  return d * micro_g1_f(mf, o) * micro_g1_f(mf, i) * om * jac;
}

// o refracted through the microfacet m (c = o.m > 0) into the side of relative IOR eta.
bool refract_through(const Vec3& o, const Vec3& m, float c, float eta, Vec3* i) {
  float sin2_t = (1 - c * c) / (eta * eta);
  if (sin2_t >= 1) return false;  // total internal reflection at this microfacet: Cycles drops it
  float cos_t = std::sqrt(1 - sin2_t);
  *i = normalize(-o / eta + m * (c / eta - cos_t));
  return i->z < 0 && is_finite(*i);
}
bool micro_sample_refract(const Vec3& o, const Micro& mf, float eta, Vec2 u, Vec3* i) {
  Vec3 m = micro_sample(mf, o, u);
  float c = dot(o, m);
  if (!(c > 0)) return false;
  return refract_through(o, m, c, eta, i);
}

// ---- Ashikhmin-Shirley (bsdf_ashikhmin_shirley) ------------------------------------------------
// Half vectors from p_h = sqrt((nx + 1)(ny + 1)) / (2 pi) cos^e, e = nx cos^2 phi + ny sin^2 phi,
// n = 2 / alpha^2 - 2; f = p_h / (4 h.o max(cos_i, cos_o)) (the paper's "pump"), pdf =
// p_h / (4 h.o), with Cycles' clamps.
struct AsExp {
  float nx, ny;
};
AsExp as_exponents(const Lobe& l) {
  const float ax = as_alpha(lobe_alpha(l)), ay = as_alpha(lobe_alpha_y(l));
  return {2 / (ax * ax) - 2, 2 / (ay * ay) - 2};
}
float as_eval(const Lobe& l, const Vec3& o, const Vec3& i, float* pdf) {
  *pdf = 0;
  if (!(o.z > 0 && i.z > 0)) return 0;
  const AsExp n = as_exponents(l);
  const float ci = std::max(i.z, 1e-6f), co = std::max(o.z, 1e-6f);
  const Vec3 h = normalize(o + i);
  const float hdoto = std::max(std::abs(dot(h, o)), 1e-6f);
  const float hn = std::max(h.z, 1e-6f);
  const float pump = 1 / std::max(1e-6f, hdoto * std::max(ci, co));
  float lobe, norm;
  if (n.nx == n.ny) {
    lobe = std::pow(hn, n.nx);
    norm = (n.nx + 1) / (8 * kPi);
  } else {
    const float s2 = h.x * h.x + h.y * h.y;  // = 1 - hn^2, without its cancellation
    lobe = s2 > 0 ? std::pow(hn, (n.nx * h.x * h.x + n.ny * h.y * h.y) / s2) : 1.0f;
    norm = std::sqrt((n.nx + 1) * (n.ny + 1)) / (8 * kPi);
  }
  *pdf = norm * lobe / hdoto;
  return norm * lobe * pump;
}
// Ashikhmin and Shirley 2000, eq. 9 in the first quadrant, mirrored into the others as Cycles.
bool as_sample(const Lobe& l, const Vec3& o, Vec2 u, Vec3* i) {
  const AsExp n = as_exponents(l);
  float phi, cos_theta;
  if (n.nx == n.ny) {
    phi = 2 * kPi * u.x;
    cos_theta = std::pow(u.y, 1 / (n.nx + 1));
  } else {
    const int quadrant = std::min(3, int(u.x * 4));
    float v = u.x * 4 - float(quadrant);
    if (quadrant & 1) v = 1 - v;  // keeps the map continuous across quadrants
    float p = std::atan(std::sqrt((n.nx + 1) / (n.ny + 1)) * std::tan(0.5f * kPi * v));
    const float cp = std::cos(p), sp = std::sin(p);
    cos_theta = std::pow(u.y, 1 / (n.nx * cp * cp + n.ny * sp * sp + 1));
    phi = quadrant == 0 ? p : quadrant == 1 ? kPi - p : quadrant == 2 ? kPi + p : 2 * kPi - p;
  }
  const float sin_theta = safe_sqrt(1 - cos_theta * cos_theta);
  const Vec3 h(sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta);
  const float c = dot(h, o);
  if (!(c > 0)) return false;
  *i = normalize(h * (2 * c) - o);
  return i->z > 0 && is_finite(*i);
}

// ---- Clearcoat (Cycles 3.4's CLOSURE_BSDF_MICROFACET_GGX_CLEARCOAT_ID) -------------------------
// f = D_GTR1(h.z, alpha) G1(o; 0.25) G1(i; 0.25) F(i.h) / (4 cos_o cos_i); sampled from
// D_GTR1(m) m.z (Burley 2012, appendix B), pdf = D m.z / (4 o.m).
constexpr float kClearcoatGAlpha = 0.25f;
const Spectrum kClearcoatF0{0.04f};
constexpr float kClearcoatIor = 1.5f;

float clearcoat_eval(const Lobe& l, const Vec3& o, const Vec3& i, float* pdf) {
  *pdf = 0;
  if (i.z <= 0 || o.z <= 0) return 0;
  Vec3 h = o + i;
  float len = length(h);
  if (!(len > 0)) return 0;
  h = h / len;
  const float d = gtr1_D(h.z, lobe_alpha(l));
  const float oh = dot(o, h);
  if (!(oh > 0)) return 0;
  *pdf = d * h.z / (4 * oh);
  const float f = fresnel_principled(kClearcoatF0, kClearcoatIor, dot(i, h)).x;
  return 0.25f * d * ggx_G1_over_cos(o, kClearcoatGAlpha) * ggx_G1_over_cos(i, kClearcoatGAlpha) * f;
}
bool clearcoat_sample(const Lobe& l, const Vec3& o, Vec2 u, Vec3* i) {
  const float a = lobe_alpha(l), a2 = a * a;
  const float cos2 = a < 1 ? (1 - std::pow(a2, 1 - u.x)) / (1 - a2) : 1 - u.x;
  const float cos_t = safe_sqrt(cos2), sin_t = safe_sqrt(1 - cos2), phi = 2 * kPi * u.y;
  const Vec3 m(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
  const float c = dot(o, m);
  if (!(c > 0)) return false;
  *i = normalize(m * (2 * c) - o);
  return i->z > 0 && is_finite(*i);
}

// ---- Velvet (bsdf_ashikhmin_velvet) -------------------------------------------------------------
// f = D G / (4 cos_o cos_i), D = exp(-cot^2 / sigma^2) / (pi sigma^2 sin^4) of the half vector,
// G = min(1, 2 (n.h / o.h) cos_o, 2 (n.h / o.h) cos_i), with Cycles' guards.
float velvet_eval(const Lobe& l, const Vec3& o, const Vec3& i) {
  if (!(o.z > 0 && i.z > 0)) return 0;
  const float sigma = std::max(lobe_sigma(l), 0.01f), inv_s2 = 1 / (sigma * sigma);
  const Vec3 h = normalize(o + i);
  const float cnh = h.z, cho = std::abs(dot(o, h));
  if (!(std::abs(cnh) < 1 - 1e-5f && cho > 1e-5f)) return 0;
  const float r = std::max(cnh / cho, 1e-5f);
  const float g = std::min(1.0f, std::min(2 * r * o.z, 2 * r * i.z));
  const float sin2 = 1 - cnh * cnh, cot2 = cnh * cnh / sin2;
  const float d = std::exp(-cot2 * inv_s2) * inv_s2 * kInvPi / (sin2 * sin2);
  return 0.25f * d * g / (o.z * i.z);
}

// ---- Toon (bsdf_toon) ----------------------------------------------------------------------------
// f cos_i = cone pdf x intensity(angle to the axis); pdf the uniform cone about the axis.
float toon_eval(const Lobe& l, const Vec3& axis, const Vec3& i, float* pdf) {
  *pdf = 0;
  if (!(i.z > 0)) return 0;
  const Toon t = toon_params(l);
  if (!(t.cone > 0)) return 0;
  const float c = dot(axis, i);
  const float pc = 1 / (2 * kPi * t.one_minus_cos_cone);
  if (c >= t.cos_cone) *pdf = pc;
  const float intensity = toon_intensity(t, std::acos(clamp(c, 0.0f, 1.0f)));
  return intensity > 0 ? pc * intensity / i.z : 0.0f;
}
bool toon_sample(const Lobe& l, const Vec3& axis, Vec2 u, Vec3* i) {
  const Toon t = toon_params(l);
  if (!(t.cone > 0)) return false;
  const float cos_t = 1 - u.x * t.one_minus_cos_cone;
  const float sin_t = safe_sqrt(1 - cos_t * cos_t), phi = 2 * kPi * u.y;
  *i = normalize(Frame(axis).to_world(Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t)));
  return i->z > 0 && is_finite(*i);
}
inline Vec3 mirror_dir(const Vec3& o) { return {-o.x, -o.y, o.z}; }

// ---- Multiscatter GGX (Cycles 3.4's bsdf_microfacet_multi.h, glossy, no Fresnel) -------------
// Heitz et al. 2016: the microsurface as a random medium of heights (uniform height distribution,
// C1(h) = (h + 1) / 2) and GGX normals; a walk from wo bounces on sampled microfacets and each
// bounce past the first adds its next-event estimate towards wi. The helpers keep Cycles'
// thresholds so that the estimate is Cycles' own.

// Cycles' D_ggx / D_ggx_aniso with their floor on the denominator.
float ms_D(const Vec3& m, const MsAlpha& a) {
  if (a.x == a.y) {
    const float z2 = m.z * m.z, a2 = a.x * a.x;
    const float t = (1 - z2) + a2 * z2;
    return a2 / std::max(kPi * t * t, 1e-7f);
  }
  const float sx = -m.x / a.x, sy = -m.y / a.y;
  const float t = m.z * m.z + sx * sx + sy * sy;
  return 1 / std::max(kPi * t * t * a.x * a.y, 1e-7f);
}
// Smith Lambda, negative for downward directions (mf_lambda).
float ms_lambda(const Vec3& w, const MsAlpha& a) {
  if (w.z > 0.9999f) return 0;
  if (w.z < -0.9999f) return -0.9999f;
  const float inv_z2 = 1 / std::max(w.z * w.z, 1e-7f);
  const float wx = w.x * a.x, wy = w.y * a.y;
  float v = std::sqrt(1 + (wx * wx + wy * wy) * inv_z2);
  if (w.z <= 0) v = -v;
  return 0.5f * (v - 1);
}
inline float ms_C1(float h) { return clamp(0.5f * (h + 1), 0.0f, 1.0f); }
inline float ms_invC1(float c) { return 2 * clamp(c, 0.0f, 1.0f) - 1; }
inline float ms_G1(const Vec3& w, float c1, float lambda) {
  if (w.z > 0.9999f) return 1;
  if (w.z < 1e-5f) return 0;
  return std::pow(c1, lambda);
}
// The next height along w, or false if the walk leaves the surface (mf_sample_height).
bool ms_sample_height(const Vec3& w, float* h, float* c1, float* g1, float* lambda, float u) {
  if (w.z > 0.9999f) return false;
  if (w.z < -0.9999f) {
    *c1 *= u;
    *h = ms_invC1(*c1);
    *g1 = ms_G1(w, *c1, *lambda);
  } else if (std::abs(w.z) >= 0.0001f) {
    if (u > 1 - *g1) return false;
    *c1 = *lambda >= 0 ? 1.0f : *c1 * std::pow(1 - u, -1 / *lambda);
    *h = ms_invC1(*c1);
    *g1 = ms_G1(w, *c1, *lambda);
  }
  return true;
}
// Heitz and d'Eon 2014's visible slopes of unit-roughness GGX with its rational fit for y
// (mf_sampleP22_11), and the stretched normal (mf_sample_vndf).
Vec2 ms_sample_p22(float cos_i, float ux, float uy) {
  if (cos_i > 0.9999f || std::abs(cos_i) < 1e-6f) {
    const float r = std::sqrt(ux / std::max(1 - ux, 1e-7f)), phi = 2 * kPi * uy;
    return {r * std::cos(phi), r * std::sin(phi)};
  }
  const float sin_i = safe_sqrt(1 - cos_i * cos_i), tan_i = sin_i / cos_i;
  const float proj = 0.5f * (cos_i + 1);
  if (proj < 0.0001f) return {0, 0};
  const float a = 2 * ux * proj / cos_i - 1;
  float t = a * a - 1;
  if (std::abs(t) < 1e-7f) return {0, 0};
  t = 1 / t;
  const float d = safe_sqrt(tan_i * tan_i * t * t - (a * a - tan_i * tan_i) * t);
  const float x2 = tan_i * t + d;
  const float x = (a < 0 || x2 > 1 / tan_i) ? tan_i * t - d : x2;
  const float u2 = uy >= 0.5f ? 2 * (uy - 0.5f) : 2 * (0.5f - uy);
  const float z =
      (u2 * (u2 * (u2 * 0.27385f - 0.73369f) + 0.46341f)) / (u2 * (u2 * (u2 * 0.093073f + 0.309420f) - 1) + 0.597999f);
  const float y = z * std::sqrt(1 + x * x);
  return {x, uy >= 0.5f ? y : -y};
}
Vec3 ms_sample_vndf(const Vec3& w, const MsAlpha& a, float ux, float uy) {
  const Vec3 w11 = normalize(Vec3(a.x * w.x, a.y * w.y, w.z));
  const Vec2 s = ms_sample_p22(w11.z, ux, uy);
  const float pl = std::sqrt(w11.x * w11.x + w11.y * w11.y);
  const float cp = pl > 0 ? w11.x / pl : 0, sp = pl > 0 ? w11.y / pl : 0;  // Cycles' safe_normalize
  const float sx = a.x * (cp * s.x - sp * s.y), sy = a.y * (sp * s.x + cp * s.y);
  return normalize(Vec3(-sx, -sy, 1));
}
// The glossy phase function of a walk direction w (pointing into the surface) towards wi.
float ms_phase_glossy(const Vec3& w, float lambda, const Vec3& wi, const MsAlpha& a) {
  if (w.z > 0.9999f) return 0;
  const Vec3 wh = normalize(wi - w);
  if (wh.z < 0) return 0;
  const float area = w.z < -0.9999f ? 1.0f : lambda * w.z;
  const float c = dot(-w, wh);
  if (c < 0) return 0;
  return std::max(0.0f, c) * 0.25f / std::max(area * c, 1e-7f) * ms_D(wh, a);
}

// A small LCG seeded from the direction pair, so that eval() of one pair is one fixed estimate.
struct MsRng {
  uint32_t state;
  float next() {
    state = 1103515245u * state + 12345u;
    return float(state) * (1.0f / 4294967296.0f);
  }
};
uint32_t ms_seed(const Vec3& o, const Vec3& i) {
  uint32_t b[6];
  std::memcpy(b, &o.x, 4);
  std::memcpy(b + 1, &o.y, 4);
  std::memcpy(b + 2, &o.z, 4);
  std::memcpy(b + 3, &i.x, 4);
  std::memcpy(b + 4, &i.y, 4);
  std::memcpy(b + 5, &i.z, 4);
  uint32_t h = 0x9e3779b9u;
  for (uint32_t v : b) h = hash_u32(h ^ v);
  return h;
}

// What colours a walk (Cycles' mf_eval arguments): the bounce colour, and with fresnel the
// Principled's interpolate_fresnel_color towards cspec0 at IOR eta.
struct MsColors {
  Spectrum color, cspec0;
  bool fresnel;
  float eta;
};
MsColors ms_colors(const Lobe& l, bool glass) {
  return {vmin(vmax(l.ms_color, Spectrum(0.0f)), Spectrum(1.0f)), glass ? l.glass_f0 : l.f0, l.ms_fresnel,
          glass ? lobe_eta(l) : l.eta};  // the specular IOR may be infinite (a mirror's Fresnel)
}

// mf_eval_glossy: f cos_i for view o and light i, both above. As in Cycles 3.4 the walk's
// throughput enters its estimate twice (phase x throughput x throughput); with fresnel the first
// order is coloured at the half vector and later reflections at their microfacets.
Spectrum ms_eval_cos(const MsAlpha& a, const MsColors& c, Vec3 o, Vec3 i) {
  bool swapped = false;
  if (i.z < o.z) {  // walk from the shallower direction (less noise; the BSDF is reciprocal)
    std::swap(o, i);
    swapped = true;
  }
  MsRng rng{ms_seed(o, i)};  // after the swap: f(o, i) and f(i, o) are the same estimate
  if (o.z < 1e-5f || i.z < 1e-5f) return Spectrum(0.0f);
  float lambda_r = ms_lambda(-o, a);
  const float shadowing_lambda = ms_lambda(i, a);
  const Vec3 wh = normalize(o + i);
  const float g2 = 1 / (1 - (lambda_r + 1) + shadowing_lambda);
  Spectrum throughput(1.0f);
  if (c.fresnel) throughput = fresnel_principled(c.cspec0, c.eta, dot(o, wh));
  Spectrum eval = throughput * (g2 * 0.25f / o.z * ms_D(wh, a));
  Vec3 wr = -o;
  float hr = 1, c1_r = 1, g1_r = 0;
  for (int order = 0; order < 10; ++order) {
    if (!ms_sample_height(wr, &hr, &c1_r, &g1_r, &lambda_r, rng.next())) break;
    const float uy = rng.next(), ux = rng.next();
    const Vec3 wm = ms_sample_vndf(-wr, a, ux, uy);
    if (order > 0) {
      const Spectrum phase = throughput * ms_phase_glossy(wr, lambda_r, i, a);
      eval += throughput * phase * ms_G1(i, ms_C1(hr), shadowing_lambda);
    }
    if (order + 1 < 10) {
      if (c.fresnel && order > 0) throughput *= fresnel_principled(c.cspec0, c.eta, std::abs(dot(-wr, wm)));
      wr = wr - wm * (2 * dot(wr, wm));
      lambda_r = ms_lambda(wr, a);
      if (!c.fresnel) throughput *= c.color;
      c1_r = ms_C1(hr);
      g1_r = ms_G1(wr, c1_r, lambda_r);
    }
  }
  if (swapped) eval *= std::abs(o.z / i.z);
  return eval;
}

// Sampling (not Cycles' walk, whose density is unknown): the single-scattering visible normals
// with probability A (Cycles' mf_ggx_albedo of the mean alpha), else the cosine hemisphere; the
// pdf is that mixture's exactly.
float ms_single_albedo(const MsAlpha& a) {
  const float r = std::sqrt(a.x * a.y);
  float v = 0.806495f * std::exp(-1.98712f * r * r) + 0.199531f;
  v -= ((((((1.76741f * r - 8.43891f) * r + 15.784f) * r - 14.398f) * r + 6.45221f) * r - 1.19722f) * r + 0.027803f) *
           r +
       0.00568739f;
  return clamp(v, 0.05f, 0.95f);  // keep both strategies alive
}
Spectrum ms_eval(const Lobe& l, const Vec3& o, const Vec3& i, float* pdf) {
  *pdf = 0;
  if (!(o.z > 0 && i.z > 0)) return Spectrum(0.0f);
  const MsAlpha a = ms_alphas(l);
  const float p_single = ms_single_albedo(a);
  const Micro mf{false, a.x, a.y};
  float p_vndf = 0;
  micro_reflect(o, i, mf, &p_vndf, nullptr);
  *pdf = p_single * p_vndf + (1 - p_single) * i.z * kInvPi;
  return l.weight * ms_eval_cos(a, ms_colors(l, false), o, i) / i.z;
}
bool ms_sample(const Lobe& l, const Vec3& o, Vec2 u, float u_extra, Vec3* i) {
  const MsAlpha a = ms_alphas(l);
  if (u_extra < ms_single_albedo(a)) return micro_sample_reflect(o, Micro{false, a.x, a.y}, u, i);
  *i = sample_cosine_hemisphere(u);
  return i->z > 0;
}

// ---- Multiscatter GGX glass (mf_eval_glass: the same walk with a dielectric phase function) ----

// B(x, y) = Gamma(x) Gamma(y) / Gamma(x + y), reentrant (std::lgamma writes the global signgam).
float beta_fn(float x, float y) {
  int sign;
  return std::exp(lgammaf_r(x, &sign) + lgammaf_r(y, &sign) - lgammaf_r(x + y, &sign));
}
// mf_sample_phase_glass: reflect on the microfacet wm with the dielectric Fresnel's probability,
// else refract; *outside says which.
Vec3 ms_sample_phase_glass(const Vec3& wi, float eta, const Vec3& wm, float u, bool* outside) {
  const float c = dot(wi, wm);
  if (u < fresnel_dielectric(std::abs(c), eta)) {
    *outside = true;
    return wm * (2 * c) - wi;
  }
  *outside = false;
  const float inv = 1 / eta;
  const float cos_t = -safe_sqrt(1 - (1 - c * c) * inv * inv);
  return normalize(wm * (c * inv + cos_t) - wi * inv);
}
// mf_eval_phase_glass: the walk direction w (into the surface) scattered towards wo, on wo's
// side (reflection x F) or through (refraction x (1 - F), Walter et al. 2007's with its eta^2,
// which Cycles 3.4 leaves out: see ms_glass_eval_cos).
float ms_phase_glass(const Vec3& w, float lambda, const Vec3& wo, bool wo_outside, float alpha, float eta) {
  if (w.z > 0.9999f) return 0;
  const float area = w.z < -0.9999f ? 1.0f : lambda * w.z;
  const MsAlpha a{alpha, alpha};
  if (wo_outside) {
    const Vec3 wh = normalize(wo - w);
    if (wh.z < 0) return 0;
    const float c = dot(-w, wh), den = area * c;
    if (!(den > 0)) return 0;
    return fresnel_dielectric(c, eta) * c * ms_D(wh, a) * 0.25f / den;
  }
  Vec3 wh = normalize(wo * eta - w);
  if (wh.z < 0) wh = -wh;
  const float c = dot(-w, wh), co = dot(wo, wh);
  if (c < 0) return 0;
  const float t = c + eta * co, den = area * t * t;
  if (!(den > 0)) return 0;
  return eta * eta * (1 - fresnel_dielectric(c, eta)) * c * std::max(0.0f, -co) * ms_D(wh, a) / den;
}

// mf_eval_glass: f |cos_i| for view o (above) and light i on either side. Cycles' reflection
// passes the Principled's fresnel colours, its refraction never does (then every later bounce
// takes the colour). Both walk from the shallower direction.
// Two departures from Cycles 3.4's evaluation, which disagrees with its own walk there (README):
// its refraction phase lacks Walter et al.'s eta^2 (which its single-scattering glass and the
// walk's unit refraction weight imply), and it walks the reverse pair (-i, -o) with the same eta
// where that pair sees the interface from the other side. Here the phase has eta^2 and the
// reverse walk 1 / eta: f(o, i) = eta^2 f(-i, -o) (generalised reciprocity).
Spectrum ms_glass_eval_cos(float alpha, const MsColors& c, Vec3 o, Vec3 i) {
  const bool i_outside = i.z > 0;
  float eta = c.eta, scale = 1;
  bool swapped = false;
  if (!i_outside) {
    if (-i.z < o.z) {
      const Vec3 t = -i;
      i = -o;
      o = t;
      swapped = true;
      scale = eta * eta;
      eta = 1 / eta;
    }
  } else if (i.z < o.z) {
    std::swap(o, i);
    swapped = true;
  }
  MsRng rng{ms_seed(o, i)};
  if (o.z < 1e-5f || (i.z < 1e-5f && i_outside) || (i.z > -1e-5f && !i_outside)) return Spectrum(0.0f);
  const MsAlpha a{alpha, alpha};
  float lambda_r = ms_lambda(-o, a);
  const float shadowing_lambda = ms_lambda(i_outside ? i : -i, a);
  float single = ms_phase_glass(-o, lambda_r, i, i_outside, alpha, eta);
  single *=
      i_outside ? -lambda_r / (shadowing_lambda - lambda_r) : -lambda_r * beta_fn(-lambda_r, shadowing_lambda + 1);
  Spectrum throughput(1.0f);
  if (c.fresnel) throughput = fresnel_principled(c.cspec0, eta, dot(o, normalize(o + i)));
  Spectrum eval = throughput * single;
  Vec3 wr = -o;
  float hr = 1, c1_r = 1, g1_r = 0;
  bool outside = true;
  for (int order = 0; order < 10; ++order) {
    if (!ms_sample_height(wr, &hr, &c1_r, &g1_r, &lambda_r, rng.next())) break;
    const float uy = rng.next(), ux = rng.next();
    const Vec3 wm = ms_sample_vndf(-wr, a, ux, uy);
    if (order > 0) {  // (Cycles' fresnel reflection estimates order 0 too: the analytic is its mean)
      const float phase = outside ? ms_phase_glass(wr, lambda_r, i, i_outside, alpha, eta)
                                  : ms_phase_glass(wr, lambda_r, -i, !i_outside, alpha, 1 / eta);
      eval +=
          throughput * (phase * ms_G1(i_outside ? i : -i, ms_C1(outside == i_outside ? hr : -hr), shadowing_lambda));
    }
    if (order + 1 < 10) {
      const Vec3 wi_prev = -wr;
      bool next_outside;
      wr = ms_sample_phase_glass(-wr, outside ? eta : 1 / eta, wm, rng.next(), &next_outside);
      if (!next_outside) {
        outside = !outside;
        wr = -wr;
        hr = -hr;
      }
      if (c.fresnel && !next_outside)
        throughput *= c.color;
      else if (c.fresnel && order > 0)
        throughput *= fresnel_principled(c.cspec0, eta, std::abs(dot(wi_prev, wm)));
      lambda_r = ms_lambda(wr, a);
      if (!c.fresnel) throughput *= c.color;
      c1_r = ms_C1(hr);
      g1_r = ms_G1(wr, c1_r, lambda_r);
    }
  }
  if (swapped) eval *= scale * std::abs(o.z / i.z);
  return eval;
}

// Sampling: with probability A (as glossy) a visible normal m, reflected with the probability
// F(o.m) and else refracted (Walter et al. 2007: the split at the microfacet, so that a rough
// interface refracts even beyond the critical angle of its macro normal), else a cosine lobe on
// o's side with probability clamp(F(o.z), 0.1, 0.9) or on the far side.
struct MsGlassSplit {
  float p_single, q_reflect;
};
MsGlassSplit ms_glass_split(float alpha, float cos_o, float eta) {
  return {ms_single_albedo({alpha, alpha}), clamp(fresnel_dielectric(cos_o, eta), 0.1f, 0.9f)};
}
// The single-scattering part's density of i: the visible normal's, times its branch's Fresnel.
float ms_glass_single_pdf(const Vec3& o, const Vec3& i, float alpha, float eta) {
  const Micro mf{false, alpha, alpha};
  float p = 0;
  if (i.z > 0) {
    float cos_om = 0;
    micro_reflect(o, i, mf, &p, &cos_om);
    return p * fresnel_dielectric(cos_om, eta);
  }
  float cos_om = 0;
  micro_refract(o, i, mf, eta, &p, &cos_om);
  return p * (1 - fresnel_dielectric(cos_om, eta));
}
Spectrum ms_glass_eval(const Lobe& l, const Vec3& o, const Vec3& i, float* pdf) {
  *pdf = 0;
  if (!(o.z > 0) || i.z == 0) return Spectrum(0.0f);
  const float alpha = ms_glass_alpha(l), eta = lobe_eta(l);
  const MsGlassSplit s = ms_glass_split(alpha, o.z, eta);
  const float q = i.z > 0 ? s.q_reflect : 1 - s.q_reflect;
  *pdf = s.p_single * ms_glass_single_pdf(o, i, alpha, eta) + (1 - s.p_single) * q * std::abs(i.z) * kInvPi;
  MsColors c = ms_colors(l, true);
  Spectrum tint(1.0f);
  if (i.z < 0) {
    // Cycles' refraction eval walks without the fresnel colours; its Principled closure weight
    // lacks the base colour, which its sample() gives each refraction: Lantern keeps it once
    // (refraction_tint), so that rough coloured glass is coloured as in Cycles' images.
    c.fresnel = false;
    tint = l.refraction_tint;
  }
  return l.weight * tint * ms_glass_eval_cos(alpha, c, o, i) / std::abs(i.z);
}
bool ms_glass_sample(const Lobe& l, const Vec3& o, Vec2 u, float u_extra, Vec3* i) {
  const float alpha = ms_glass_alpha(l), eta = lobe_eta(l);
  const MsGlassSplit s = ms_glass_split(alpha, o.z, eta);
  if (u_extra < s.p_single) {
    const Vec3 m = ggx_sample_visible_normal(o, alpha, u);
    const float c = dot(o, m);
    if (!(c > 0)) return false;
    if (u_extra < s.p_single * fresnel_dielectric(c, eta)) return reflect_about(o, m, c, i);
    return refract_through(o, m, c, eta, i);
  }
  *i = sample_cosine_hemisphere(u);
  if (!(i->z > 0)) return false;
  if (u_extra >= s.p_single + (1 - s.p_single) * s.q_reflect) i->z = -i->z;
  return true;
}

// ---- per-lobe evaluation in the frame where o.z > 0 -------------------------------------------
// The glass reflection's colour: Cycles 3.4's Principled glass reflection closure
// (bsdf_microfacet_ggx_fresnel_setup: interpolate_fresnel_color at i.h, cspec0 = glass_f0
// saturated), for eta on either side of 1 (total internal reflection gives 1); exactly 1 for the
// Glass BSDF node (glass_f0 white).
Spectrum glass_reflection_color(const Lobe& l, float eta, float cos_ih) {
  if (l.glass_f0.x == 1 && l.glass_f0.y == 1 && l.glass_f0.z == 1) return Spectrum(1.0f);
  return fresnel_principled(l.glass_f0, eta, cos_ih);
}

// A glass lobe's branch weights at wo's angle cos_o (GlassPart) and the probability with which it
// samples its reflection: Fresnel's split for Both, else the one branch it keeps.
struct GlassSplit {
  float reflect, refract, p_reflect;
};
GlassSplit glass_split(const Lobe& l, float cos_o, float eta) {
  if (l.glass_part == GlassPart::RefractionBsdf) return {0, 1, 0};
  const float fr = fresnel_dielectric(cos_o, eta);
  switch (l.glass_part) {
    case GlassPart::Reflection:
      return {fr, 0, 1};
    case GlassPart::Refraction:
      return {0, std::max(1e-4f, 1 - fr), 0};
    default:
      return {fr, 1 - fr, fr};
  }
}

Spectrum eval_upper(const Lobe& l, const Vec3& o, const Vec3& i, float* pdf) {
  *pdf = 0;
  switch (l.type) {
    case LobeType::Diffuse:
    case LobeType::PrincipledDiffuse:
      if (i.z <= 0) return Spectrum(0.0f);
      *pdf = i.z * kInvPi;
      return l.type == LobeType::Diffuse ? diffuse_eval(l, o, i) : principled_diffuse_eval(l, o, i);
    case LobeType::GlossyGGX:
    case LobeType::GlossyBeckmann:
      return l.weight * micro_reflect(o, i, lobe_micro(l), pdf, nullptr);
    case LobeType::SpecularGGX: {
      float cos_oh = 0;
      float v = micro_reflect(o, i, lobe_micro(l), pdf, &cos_oh);
      return v > 0 ? l.weight * fresnel_principled(l.f0, l.eta, cos_oh) * v : Spectrum(0.0f);
    }
    case LobeType::Dielectric:
    case LobeType::DielectricBeckmann: {
      const Micro mf = lobe_micro(l);
      float eta = lobe_eta(l);
      const GlassSplit g = glass_split(l, o.z, eta);
      float p = 0, v;
      if (i.z > 0) {
        float cos_oh = 1;
        v = g.reflect * micro_reflect(o, i, mf, &p, &cos_oh);
        *pdf = g.p_reflect * p;
        return v > 0 ? l.weight * glass_reflection_color(l, eta, cos_oh) * v : Spectrum(0.0f);
      }
      v = g.refract * micro_refract(o, i, mf, eta, &p);
      *pdf = (1 - g.p_reflect) * p;
      return l.weight * l.refraction_tint * v;
    }
    case LobeType::AshikhminShirley:
      return l.weight * as_eval(l, o, i, pdf);
    case LobeType::MultiGGX:
      return ms_eval(l, o, i, pdf);
    case LobeType::MultiGGXGlass:
      return ms_glass_eval(l, o, i, pdf);
    case LobeType::Clearcoat:
      return l.weight * clearcoat_eval(l, o, i, pdf);
    case LobeType::Sheen:
      if (i.z <= 0) return Spectrum(0.0f);
      *pdf = i.z * kInvPi;
      return l.weight * schlick_weight(dot(i, normalize(o + i)));
    case LobeType::Velvet:
      if (i.z <= 0) return Spectrum(0.0f);
      *pdf = 0.5f * kInvPi;
      return l.weight * velvet_eval(l, o, i);
    case LobeType::Translucent:
      if (i.z >= 0) return Spectrum(0.0f);
      *pdf = -i.z * kInvPi;
      return l.weight * kInvPi;
    case LobeType::DiffuseToon:
      return l.weight * toon_eval(l, Vec3(0, 0, 1), i, pdf);
    case LobeType::GlossyToon:
      return l.weight * toon_eval(l, mirror_dir(o), i, pdf);
    case LobeType::Transparent:
    case LobeType::PrincipledHair:  // hair_eval, without the mirrored frame
    case LobeType::HairReflection:
    case LobeType::HairTransmission:
    case LobeType::Subsurface:  // no value: the walk (integrators/subsurface.h) carries it
      break;
  }
  return Spectrum(0.0f);
}

bool sanitize(BsdfSample* s) {
  if (!(s->pdf > 0) || !std::isfinite(s->pdf) || !is_finite(s->f) || !is_finite(s->wi)) return false;
  for (int k = 0; k < 3; ++k) s->f[k] = std::max(0.0f, s->f[k]);
  return true;
}

// Lobe selection estimate: the average of the weight, times the Fresnel-weighted layers' Fresnel
// at wo (Cycles' sample_weight), but never below its value at 60 degrees, so that a layer black at
// normal incidence (f0 = 0) that reflects at other angles is still sampled; the sheen likewise
// with Cycles' avg_value (1 - cos)^5 cos. Glass with both branches needs no factor (its Fresnel
// split is internal); one branch alone weighs its branch's weight at wo (Cycles' closure weight).
float selection_estimate(const Lobe& l, const Vec3& wo) {
  Spectrum w = vmax(l.weight, Spectrum(0.0f));
  const float c = std::abs(wo.z);
  if (l.type == LobeType::SpecularGGX || (l.type == LobeType::MultiGGX && l.ms_fresnel))
    w *= vmax(fresnel_principled(l.f0, l.eta, c), fresnel_principled(l.f0, l.eta, 0.5f));
  else if (l.type == LobeType::Clearcoat)
    w *= std::max(fresnel_principled(kClearcoatF0, kClearcoatIor, c).x,
                  fresnel_principled(kClearcoatF0, kClearcoatIor, 0.5f).x);
  else if (l.type == LobeType::Sheen)
    w *= std::max(schlick_weight(c) * c, schlick_weight(0.5f) * 0.5f);
  else if (l.type == LobeType::PrincipledDiffuse && l.diffuse_part == DiffusePart::RetroReflection)
    // bsdf_principled_diffuse_retro_reflection_sample_weight: roughness x schlick(N.I).
    w *= lobe_sigma(l) * std::max(schlick_weight(c), schlick_weight(0.5f));
  else if (l.type == LobeType::Subsurface)  // bssrdf_setup: x the channels it scatters
    w *= float((l.sss_radius.x > 0) + (l.sss_radius.y > 0) + (l.sss_radius.z > 0));
  else if ((l.type == LobeType::DiffuseToon || l.type == LobeType::GlossyToon) && toon_black(l))
    return 0;
  else if (lobe_is_glass(l.type) && l.glass_part != GlassPart::Both) {
    const GlassSplit g = glass_split(l, c, wo.z < 0 ? 1 / lobe_eta(l) : lobe_eta(l));
    w = w * g.reflect + w * vmax(l.refraction_tint, Spectrum(0.0f)) * g.refract;
  }
  float e = average(w);
  return std::isfinite(e) && e > 0 ? e : 0.0f;
}

// Normalised selection probabilities; returns false if no lobe can be picked.
bool selection_probabilities(const Bsdf& b, const Vec3& wo, float* p) {
  float total = 0;
  for (int k = 0; k < b.count(); ++k) total += (p[k] = selection_estimate(b.lobe(k), wo));
  if (!(total > 0) || !std::isfinite(total)) return false;
  for (int k = 0; k < b.count(); ++k) p[k] /= total;
  return true;
}

}  // namespace

// ---- distributions and Fresnel ------------------------------------------------------------------

// D(m) = alpha^2 / (pi cos^4 (alpha^2 + tan^2)^2) written as alpha^2 / (pi (sin^2 + alpha^2 cos^2)^2)
// for unit m, which stays accurate as m approaches the normal for small alpha.
float ggx_D(const Vec3& m, float alpha) {
  if (m.z <= 0 || !(alpha > 0)) return 0;
  float a2 = alpha * alpha;
  float d = m.x * m.x + m.y * m.y + a2 * m.z * m.z;
  return d > 0 ? a2 / (kPi * d * d) : 0;
}

// Anisotropic: 1 / (pi ax ay (x^2/ax^2 + y^2/ay^2 + z^2)^2).
float ggx_D(const Vec3& m, float ax, float ay) {
  if (m.z <= 0 || !(ax > 0) || !(ay > 0)) return 0;
  float d = sqr(m.x / ax) + sqr(m.y / ay) + m.z * m.z;
  return d > 0 ? 1 / (kPi * ax * ay * d * d) : 0;
}

// Smith masking 2 / (1 + sqrt(1 + alpha^2 tan^2)) (Walter et al. 2007, eq. 34).
float ggx_G1(const Vec3& w, float alpha) { return std::abs(w.z) * ggx_G1_over_cos(w, alpha); }
float ggx_G1(const Vec3& w, float ax, float ay) { return std::abs(w.z) * ggx_G1_over_cos(w, ax, ay); }

Vec3 ggx_sample_visible_normal(const Vec3& wo, float alpha, Vec2 u) {
  return ggx_sample_visible_normal(wo, alpha, alpha, u);
}

// Heitz 2018: stretch wo to the unit-roughness configuration, sample the projected hemisphere
// seen from it, unstretch. Works for wo on either side (mirrored into z >= 0); returns m.z >= 0.
Vec3 ggx_sample_visible_normal(const Vec3& wo, float ax, float ay, Vec2 u) {
  Vec3 vh(ax * wo.x, ay * wo.y, std::abs(wo.z));
  float vlen = length(vh);
  if (!(vlen > 0)) return {0, 0, 1};
  vh = vh / vlen;
  float lensq = vh.x * vh.x + vh.y * vh.y;
  Vec3 t1 = lensq > 0 ? Vec3(-vh.y, vh.x, 0) / std::sqrt(lensq) : Vec3(1, 0, 0);
  Vec3 t2 = cross(vh, t1);
  float r = std::sqrt(u.x), phi = 2 * kPi * u.y;
  float p1 = r * std::cos(phi), p2 = r * std::sin(phi);
  float s = 0.5f * (1 + vh.z);
  p2 = (1 - s) * safe_sqrt(1 - p1 * p1) + s * p2;
  Vec3 nh = t1 * p1 + t2 * p2 + vh * safe_sqrt(1 - p1 * p1 - p2 * p2);
  Vec3 ne(ax * nh.x, ay * nh.y, std::max(0.0f, nh.z));
  float nlen = length(ne);
  return nlen > 0 ? ne / nlen : Vec3(0, 0, 1);
}

// exp(-(x^2/ax^2 + y^2/ay^2) / z^2) / (pi ax ay z^4) (Walter et al. 2007, eq. 25, anisotropic).
float beckmann_D(const Vec3& m, float ax, float ay) {
  if (m.z <= 0 || !(ax > 0) || !(ay > 0)) return 0;
  const float z2 = m.z * m.z;
  const float e = (sqr(m.x / ax) + sqr(m.y / ay)) / z2;
  if (!(e < 80)) return 0;
  return std::exp(-e) / (kPi * ax * ay * z2 * z2);
}

float beckmann_G1(const Vec3& w, float ax, float ay) { return std::abs(w.z) * beckmann_G1_over_cos(w, ax, ay); }
float beckmann_G1_cycles(const Vec3& w, float ax, float ay) {
  return std::abs(w.z) * beckmann_G1_cycles_over_cos(w, ax, ay);
}

// Heitz and d'Eon 2014: stretch wo, sample the unit-roughness visible slopes (x by inverting its
// CDF, y independent as exp(-y^2)), rotate to wo's azimuth, unstretch, m = normalize(-x, -y, 1).
// Works for wo on either side (mirrored into z >= 0).
Vec3 beckmann_sample_visible_normal(const Vec3& wo, float ax, float ay, Vec2 u) {
  double sx = double(ax) * wo.x, sy = double(ay) * wo.y, sz = std::abs(double(wo.z));
  const double len = std::sqrt(sx * sx + sy * sy + sz * sz);
  if (!(len > 0)) return {0, 0, 1};
  sx /= len;
  sy /= len;
  sz /= len;
  const double sin_t = std::sqrt(sx * sx + sy * sy);
  const double cos_p = sin_t > 0 ? sx / sin_t : 1, sin_p = sin_t > 0 ? sy / sin_t : 0;
  const double x = beckmann_slope(sz, sin_t, u.x), y = beckmann_slope(1, 0, u.y);
  const double rx = cos_p * x - sin_p * y, ry = sin_p * x + cos_p * y;
  const Vec3 m(float(-rx * ax), float(-ry * ay), 1.0f);
  return normalize(m);
}

// Cycles' D_GTR1: (alpha^2 - 1) / (pi ln(alpha^2) (1 + (alpha^2 - 1) cos^2)), 1/pi from alpha 1.
float gtr1_D(float cos_m, float alpha) {
  if (!(cos_m > 0)) return 0;
  if (alpha >= 1) return kInvPi;
  if (!(alpha > 0)) return 0;
  const float a2 = alpha * alpha;
  const float t = 1 + (a2 - 1) * cos_m * cos_m;
  return (a2 - 1) / (kPi * std::log(a2) * t);
}

// Exact unpolarised Fresnel reflectance of a dielectric interface; eta = n_inside / n_outside,
// cos_i < 0 means arriving from inside. Returns 1 under total internal reflection.
Vec3 ensure_valid_reflection(const Vec3& Ng, const Vec3& I, const Vec3& N) {
  const float threshold = std::min(0.9f * dot(Ng, I), 0.01f);
  if (dot(Ng, 2 * dot(N, I) * N - I) >= threshold) return N;
  // Frame: Ng as Z, N in the X-Z plane; solve for N'.z so that the reflection's z is the threshold.
  const Vec3 X = normalize(N - dot(N, Ng) * Ng);
  const float ix = dot(I, X), iz = dot(I, Ng);
  const float a = ix * ix + iz * iz;
  const float b = std::sqrt(std::max(ix * ix * (a - threshold * threshold), 0.0f));
  const float c = iz * threshold + a;
  const float fac = 0.5f / a;
  const float z1 = fac * (b + c), z2 = fac * (c - b);
  bool ok1 = z1 > 1e-5f && z1 <= 1 + 1e-5f, ok2 = z2 > 1e-5f && z2 <= 1 + 1e-5f;
  auto root = [](float x) { return std::sqrt(std::max(x, 0.0f)); };
  float nx, nz;
  if (ok1 && ok2) {
    const float x1 = root(1 - z1), y1 = root(z1), x2 = root(1 - z2), y2 = root(z2);
    const float r1 = 2 * (x1 * ix + y1 * iz) * y1 - iz, r2 = 2 * (x2 * ix + y2 * iz) * y2 - iz;
    ok1 = r1 >= 1e-5f;
    ok2 = r2 >= 1e-5f;
    // Both valid: the shallower reflection (closest to N); else the one reflecting upwards.
    const bool first = ok1 && ok2 ? r1 < r2 : r1 > r2;
    nx = first ? x1 : x2;
    nz = first ? y1 : y2;
  } else if (ok1 || ok2) {
    const float z = ok1 ? z1 : z2;
    nx = root(1 - z);
    nz = root(z);
  } else {
    return Ng;
  }
  return nx * X + nz * Ng;
}

float fresnel_dielectric(float cos_i, float eta) {
  if (!(eta > 0)) return 0;
  if (cos_i < 0) {
    eta = 1 / eta;
    cos_i = -cos_i;
  }
  cos_i = std::min(cos_i, 1.0f);
  float sin2_t = (1 - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1) return 1;
  float cos_t = std::sqrt(1 - sin2_t);
  float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  float f = 0.5f * (rs * rs + rp * rp);
  return std::isfinite(f) ? clamp(f, 0.0f, 1.0f) : 1.0f;
}
Spectrum fresnel_principled(const Spectrum& f0, float eta, float cos_i) {
  const Spectrum c0 = vmin(vmax(f0, Spectrum(0.0f)), Spectrum(1.0f));  // saturate(cspec0), as Cycles
  if (eta == 1) return c0;                                             // IOR 1 (Specular 0): F(1) = F(cos) = 0
  if (!(eta < INFINITY)) return Spectrum(1.0f);                        // F(1) = 1: a perfect mirror
  const float r = (eta - 1) / (eta + 1), F0 = r * r;                   // fresnel_dielectric_cos(1, eta)
  // FH <= 1; FH < 0 where the dielectric Fresnel dips below F0 (at Specular 5, not at 2), but the
  // blend stays >= (f0 - F0) / (1 - F0) >= 0 for f0 >= F0 (the Principled BSDF's f0 unless its
  // base colour is below 0.08 specular at metallic > 0), and equals the dielectric Fresnel itself
  // for f0 = F0. The clamp keeps the rest (and rounding) in [0, 1].
  const float fh = (fresnel_dielectric(clamp(cos_i, 0.0f, 1.0f), eta) - F0) / (1 - F0);
  return vmin(vmax(c0 * (1 - fh) + Spectrum(fh), Spectrum(0.0f)), Spectrum(1.0f));
}

float bssrdf_alpha_prime(float albedo, float ior) {
  const float inv = 1 / ior;
  const float f_dr = inv * (-1.440f * inv + 0.710f) + 0.668f + 0.0636f * ior;
  const float a43 = (4.0f / 3.0f) * (1 + f_dr) / (1 - f_dr);
  auto rd = [&](float ap) {  // the dipole's total diffuse reflectance for alpha'
    const float s = std::sqrt(3 * (1 - ap));
    return 0.5f * ap * (1 + std::exp(-a43 * s)) * std::exp(-s);
  };
  if (!(albedo >= 1e-4f)) return 0;
  if (albedo >= 0.995f) return 0.999999f;
  float lo = 0, hi = 1, mid = 0.5f;
  for (int i = 0; i < 12; ++i) {
    mid = 0.5f * (lo + hi);
    (rd(mid) < albedo ? lo : hi) = mid;
  }
  return mid;
}

Spectrum bssrdf_radius(const Spectrum& radius, const Spectrum& albedo, SubsurfaceMethod method, float ior) {
  if (method != SubsurfaceMethod::RandomWalk) return radius * (0.25f * kInvPi);
  Spectrum r;
  for (int k = 0; k < 3; ++k) r[k] = radius[k] * std::sqrt(3 * (1 - bssrdf_alpha_prime(albedo[k], ior)));
  return r;
}

float principled_specular_ior(float specular) {
  const float s = std::sqrt(std::isfinite(specular) ? clamp(0.08f * specular, 0.0f, 1.0f) : 0.0f);
  return s < 1 ? 2 / (1 - s) - 1 : INFINITY;
}

// ---- single lobes -------------------------------------------------------------------------------

uint32_t lobe_flags(const Lobe& l) {
  bool delta = lobe_is_delta(l);
  switch (l.type) {
    case LobeType::Diffuse:
    case LobeType::PrincipledDiffuse:
    case LobeType::Sheen:
    case LobeType::Velvet:
    case LobeType::DiffuseToon:
      return kLobeDiffuse | kLobeReflection;
    case LobeType::Translucent:
      return kLobeDiffuse | kLobeTransmission;
    case LobeType::GlossyToon:
      return kLobeGlossy | kLobeReflection;
    case LobeType::GlossyGGX:
    case LobeType::SpecularGGX:
    case LobeType::GlossyBeckmann:
    case LobeType::AshikhminShirley:
    case LobeType::Clearcoat:
    case LobeType::MultiGGX:
      return (delta ? kLobeSpecular : kLobeGlossy) | kLobeReflection;
    case LobeType::Dielectric:
    case LobeType::DielectricBeckmann:
    case LobeType::MultiGGXGlass:
      return (delta ? kLobeSpecular : kLobeGlossy) | (glass_only_refracts(l) ? 0u : kLobeReflection) |
             (l.glass_part == GlassPart::Reflection ? 0u : kLobeTransmission);
    case LobeType::Transparent:
      return kLobeSpecular | kLobeTransmission;
    case LobeType::PrincipledHair:
    case LobeType::HairReflection:
    case LobeType::HairTransmission:
      return kLobeGlossy | kLobeReflection | kLobeTransmission;
    case LobeType::Subsurface:
      return kLobeSubsurface | kLobeDiffuse;
  }
  return 0;
}

namespace {
// lobe_eval() and lobe_pdf() from one evaluation.
Spectrum lobe_eval_pdf(const Lobe& l, const Vec3& wo, const Vec3& wi, float* pdf_out) {
  *pdf_out = 0;
  if (wo.z == 0 || lobe_is_delta(l)) return Spectrum(0.0f);
  float pdf;
  if (lobe_is_hair(l.type)) {  // a fibre has no inside: no mirrored frame
    Spectrum f = hair_eval(l, wo, wi, &pdf);
    *pdf_out = std::isfinite(pdf) && pdf > 0 ? pdf : 0.0f;
    return is_finite(f) ? vmax(f, Spectrum(0.0f)) : Spectrum(0.0f);
  }
  std::optional<Lobe> tmp;
  Spectrum f =
      wo.z > 0 ? eval_upper(l, wo, wi, &pdf) : eval_upper(lobe_from_below(l, &tmp), flip_z(wo), flip_z(wi), &pdf);
  *pdf_out = std::isfinite(pdf) && pdf > 0 ? pdf : 0.0f;
  return is_finite(f) ? vmax(f, Spectrum(0.0f)) : Spectrum(0.0f);
}
}  // namespace

Spectrum lobe_eval(const Lobe& l, const Vec3& wo, const Vec3& wi) {
  float pdf;
  return lobe_eval_pdf(l, wo, wi, &pdf);
}

float lobe_pdf(const Lobe& l, const Vec3& wo, const Vec3& wi) {
  float pdf;
  lobe_eval_pdf(l, wo, wi, &pdf);
  return pdf;
}

bool lobe_sample(const Lobe& lobe, const Vec3& wo, Vec2 u, float u_extra, BsdfSample* out, bool below_shading) {
  if (wo.z == 0 || !is_finite(wo)) return false;
  if (lobe_is_hair(lobe.type)) {
    BsdfSample s;
    if (!hair_sample(lobe, wo, u, u_extra, &s.wi)) return false;
    s.f = lobe_eval_pdf(lobe, wo, s.wi, &s.pdf);
    s.flags = kLobeGlossy | (s.wi.z > 0 ? kLobeReflection : kLobeTransmission);
    if (!sanitize(&s)) return false;
    *out = s;
    return true;
  }
  const bool flip = wo.z < 0;
  const Vec3 o = flip ? flip_z(wo) : wo;
  std::optional<Lobe> tmp;
  const Lobe& l = flip ? lobe_from_below(lobe, &tmp) : lobe;
  BsdfSample s;
  s.eta = 1;
  if (lobe_is_delta(l)) {
    // f * |wi.z| / pdf equals the lobe's weight times the chosen branch's Fresnel over its
    // probability: the weight itself, or for a glass branch alone the weight times the branch's
    // weight (GlassSplit).
    const Vec3 mirror(-o.x, -o.y, o.z);
    switch (l.type) {
      case LobeType::GlossyGGX:
      case LobeType::GlossyBeckmann:
      case LobeType::AshikhminShirley:
      case LobeType::MultiGGX:
        s.wi = mirror;
        s.pdf = 1;
        s.f = l.weight / o.z;
        if (l.ms_fresnel) s.f *= fresnel_principled(l.f0, l.eta, o.z);
        s.flags = kLobeSpecular | kLobeReflection;
        break;
      case LobeType::SpecularGGX:
        s.wi = mirror;
        s.pdf = 1;
        s.f = l.weight * fresnel_principled(l.f0, l.eta, o.z) / o.z;
        s.flags = kLobeSpecular | kLobeReflection;
        break;
      case LobeType::Clearcoat:
        s.wi = mirror;
        s.pdf = 1;
        s.f = l.weight * fresnel_principled(kClearcoatF0, kClearcoatIor, o.z) / o.z;
        s.flags = kLobeSpecular | kLobeReflection;
        break;
      case LobeType::Dielectric:
      case LobeType::DielectricBeckmann:
      case LobeType::MultiGGXGlass: {
        float eta = lobe_eta(l);
        const GlassSplit g = glass_split(l, o.z, eta);
        if (u_extra < g.p_reflect) {
          s.wi = mirror;
          s.pdf = g.p_reflect;
          s.f = l.weight * glass_reflection_color(l, eta, o.z) * g.reflect / o.z;
          s.flags = kLobeSpecular | kLobeReflection;
        } else {
          float sin2_t = (1 - o.z * o.z) / (eta * eta);
          // Total internal reflection: glass with both branches reaches this only when fr rounds
          // below 1; a refraction alone loses the light there (Cycles' bsdf_refraction_sample).
          if (sin2_t >= 1) return false;
          float cos_t = std::sqrt(1 - sin2_t);
          s.wi = normalize(Vec3(-o.x / eta, -o.y / eta, -cos_t));
          s.pdf = 1 - g.p_reflect;
          s.f = l.weight * l.refraction_tint * g.refract / std::abs(s.wi.z);
          s.flags = kLobeSpecular | kLobeTransmission;
          s.eta = eta;
        }
        break;
      }
      case LobeType::Transparent:
        s.wi = -o;
        s.pdf = 1;
        s.f = l.weight / o.z;
        s.flags = kLobeSpecular | kLobeTransmission;
        break;
      default:
        return false;
    }
  } else {
    s.flags = lobe_flags(l);
    switch (l.type) {
      case LobeType::Diffuse:
      case LobeType::PrincipledDiffuse:
      case LobeType::Sheen:
        s.wi = sample_cosine_hemisphere(u);
        if (!(s.wi.z > 0)) return false;
        break;
      case LobeType::Translucent:
        s.wi = sample_cosine_hemisphere(u);
        if (!(s.wi.z > 0)) return false;
        s.wi.z = -s.wi.z;
        break;
      case LobeType::Velvet: {
        // Uniform over the hemisphere, as Cycles' bsdf_ashikhmin_velvet_sample.
        const float z = u.x, r = safe_sqrt(1 - z * z), phi = 2 * kPi * u.y;
        s.wi = Vec3(r * std::cos(phi), r * std::sin(phi), z);
        if (!(s.wi.z > 0)) return false;
        break;
      }
      case LobeType::DiffuseToon:
        if (!toon_sample(l, Vec3(0, 0, 1), u, &s.wi)) return false;
        break;
      case LobeType::GlossyToon:
        if (!toon_sample(l, mirror_dir(o), u, &s.wi)) return false;
        break;
      case LobeType::AshikhminShirley:
        if (!as_sample(l, o, u, &s.wi)) return false;
        break;
      case LobeType::MultiGGX:
        if (!ms_sample(l, o, u, u_extra, &s.wi)) return false;
        break;
      case LobeType::MultiGGXGlass:
        if (!ms_glass_sample(l, o, u, u_extra, &s.wi)) return false;
        s.flags = kLobeGlossy | (s.wi.z > 0 ? kLobeReflection : kLobeTransmission);
        if (s.wi.z < 0) s.eta = lobe_eta(l);
        break;
      case LobeType::Clearcoat:
        if (!clearcoat_sample(l, o, u, &s.wi)) return false;
        break;
      case LobeType::GlossyGGX:
      case LobeType::SpecularGGX:
      case LobeType::GlossyBeckmann:
        if (!micro_sample_reflect(o, lobe_micro(l), u, &s.wi, below_shading)) return false;
        if (s.wi.z < 0) {  // the sampling routine's f and pdf, which eval() does not have here
          float cos_oh = 0;
          const float v = micro_reflect(o, s.wi, lobe_micro(l), &s.pdf, &cos_oh, true);
          s.f = l.weight * v;
          if (l.type == LobeType::SpecularGGX) s.f *= fresnel_principled(l.f0, l.eta, cos_oh);
          s.flags |= kLobeBelowShading;
          if (flip) s.wi = flip_z(s.wi);
          if (!sanitize(&s)) return false;
          *out = s;
          return true;
        }
        break;
      case LobeType::Dielectric:
      case LobeType::DielectricBeckmann: {
        const Micro mf = lobe_micro(l);
        float eta = lobe_eta(l);
        const GlassSplit g = glass_split(l, o.z, eta);
        if (u_extra < g.p_reflect) {
          if (!micro_sample_reflect(o, mf, u, &s.wi, below_shading)) return false;
          s.flags = kLobeGlossy | kLobeReflection;
          if (s.wi.z < 0) {  // Cycles' glass reflects with its GGX reflection closure: as above
            float cos_oh = 1;
            const float v = micro_reflect(o, s.wi, mf, &s.pdf, &cos_oh, true);
            s.f = l.weight * glass_reflection_color(l, eta, cos_oh) * (g.reflect * v);
            s.pdf *= g.p_reflect;
            s.flags |= kLobeBelowShading;
            if (flip) s.wi = flip_z(s.wi);
            if (!sanitize(&s)) return false;
            *out = s;
            return true;
          }
        } else {
          if (!micro_sample_refract(o, mf, eta, u, &s.wi)) return false;
          s.flags = kLobeGlossy | kLobeTransmission;
          s.eta = eta;
        }
        break;
      }
      case LobeType::Transparent:
      case LobeType::PrincipledHair:  // sampled above
      case LobeType::HairReflection:
      case LobeType::HairTransmission:
      case LobeType::Subsurface:  // Bsdf::sample hands it to the caller
        return false;
    }
    // f and pdf from the evaluation path, so that sample() and pdf() agree to the last bit.
    s.f = eval_upper(l, o, s.wi, &s.pdf);
  }
  if (flip) s.wi = flip_z(s.wi);
  if (!sanitize(&s)) return false;
  *out = s;
  return true;
}

// ---- the mixture --------------------------------------------------------------------------------

void Bsdf::add(const Lobe& lobe) {
  if (!is_finite(lobe.weight) || !(max_component(lobe.weight) > 0)) return;
  if (count_ >= kMaxLobes) {
    overflowed_ = true;
    return;
  }
  lobes_[count_++] = lobe;
}

bool Bsdf::selection(const Vec3& wo, float* p) const { return selection_probabilities(*this, wo, p); }

float Bsdf::lobe_pdfs(const Vec3& wo, const Vec3& wi, float* part) const {
  float p[kMaxLobes];
  for (int k = 0; k < count_; ++k) part[k] = 0;
  if (!selection_probabilities(*this, wo, p)) return 0;
  float total = 0;
  for (int k = 0; k < count_; ++k)
    if (!lobe_is_delta(lobes_[k])) total += (part[k] = p[k] * lobe_pdf(lobes_[k], wo, wi));
  return std::isfinite(total) ? total : 0.0f;
}

// Cycles 3.4's bump_shadowing_term (Chiang, Li and Burley, "Taming the Shadow Terminator"): with
// the shading normal +Z, g = cos(smooth, light) / (cos(shading, light) cos(smooth, shading)).
// Cycles' diffuse reflection closures take it (CLOSURE_IS_BSDF_DIFFUSE); Translucent and Velvet
// do not here. Then the Shading Offset's shift_cos_in (kernel/closure/bsdf.h, from appleseed):
// cos(frequency acos(cos_light)) / cos_light on every lobe lit from above the shading normal
// (Cycles' bsdf_eval rule, applied to sampled directions too).
float Bsdf::terminator_terms(const Lobe& lobe, const Vec3& wo, const Vec3& wi) const {
  const Vec3& l = light_is_wo_ ? wo : wi;
  float shift = 1;
  if (frequency_ > 1 && l.z >= 0) {
    const float c = std::min(l.z, 1.0f);
    // Towards c = 0 the value goes to 0 for every frequency > 1 (Cycles' 0 / 0 there is NaN).
    shift = c > 0 ? std::max(std::cos(std::acos(c) * frequency_), 0.0f) / c : 0.0f;
  }
  const LobeType t = lobe.type;
  if (!bumped_ || (t != LobeType::Diffuse && t != LobeType::PrincipledDiffuse && t != LobeType::Sheen &&
                   t != LobeType::DiffuseToon))
    return shift;
  const float den = l.z * smooth_.z;
  const float g = den != 0 ? dot(smooth_, l) / den : 0.0f;
  if (g >= 1) return shift;
  if (!(g >= 0)) return 0.0f;
  return shift * (-g * g * g + g * g + g);
}

namespace {
// Lobes whose f is not symmetric in (wo, wi): Cycles' Toon closures make f cos(wi) the ramp, its
// hair closures are computed with sd->I, the direction towards the camera, and glass takes its
// Fresnel split at wo and refracts with f(wo, wi) = eta^2 f(wi, wo) (bsdf.h, set_light_is_wo).
inline bool lobe_reciprocal(const Lobe& l) {
  return l.type != LobeType::DiffuseToon && l.type != LobeType::GlossyToon && !lobe_is_hair(l.type) &&
         !lobe_is_glass(l.type);
}
}  // namespace

// A lobe's f for the transport set (the adjoint under set_light_is_wo) and its pdf of sampling wi.
Spectrum Bsdf::lobe_value(const Lobe& l, const Vec3& wo, const Vec3& wi, float* pdf) const {
  if (!light_is_wo_ || lobe_reciprocal(l)) return lobe_eval_pdf(l, wo, wi, pdf);
  *pdf = lobe_pdf(l, wo, wi);
  return lobe_eval(l, wi, wo);
}

Spectrum Bsdf::eval(const Vec3& wo, const Vec3& wi, float* pdf, unsigned excluded) const {
  Spectrum f(0.0f);
  float p_total = 0;
  float p[kMaxLobes];
  float pk;
  const bool transmit = wo.z * wi.z < 0;
  auto skip = [&](const Lobe& l) { return excluded && (excluded & (1u << int(lobe_pass_kind(l, transmit)))); };
  if (!pdf) {
    for (int k = 0; k < count_; ++k)
      if (!skip(lobes_[k]))
        f += lobe_value(lobes_[k], wo, wi, &pk) * terminator_terms(lobes_[k], wo, wi);  // zero for delta lobes
  } else if (selection_probabilities(*this, wo, p)) {
    for (int k = 0; k < count_; ++k) {
      if (lobe_is_delta(lobes_[k]) || skip(lobes_[k])) continue;
      f += lobe_value(lobes_[k], wo, wi, &pk) * terminator_terms(lobes_[k], wo, wi);
      p_total += p[k] * pk;
    }
  } else {
    for (int k = 0; k < count_; ++k)
      if (!skip(lobes_[k])) f += lobe_value(lobes_[k], wo, wi, &pk) * terminator_terms(lobes_[k], wo, wi);
  }
  if (!is_finite(f)) f = Spectrum(0.0f);
  if (pdf) *pdf = std::isfinite(p_total) ? p_total : 0.0f;
  return f;
}

float Bsdf::pdf(const Vec3& wo, const Vec3& wi) const {
  float p[kMaxLobes];
  if (!selection_probabilities(*this, wo, p)) return 0;
  float p_total = 0;
  for (int k = 0; k < count_; ++k)
    if (!lobe_is_delta(lobes_[k])) p_total += p[k] * lobe_pdf(lobes_[k], wo, wi);
  return std::isfinite(p_total) ? p_total : 0.0f;
}

bool Bsdf::sample(const Vec3& wo, float u_lobe, Vec2 u, BsdfSample* out) const {
  float p[kMaxLobes];
  if (count_ == 0 || !selection_probabilities(*this, wo, p)) return false;
  int chosen = -1;
  float cdf = 0, cdf_chosen = 0;
  for (int k = 0; k < count_; ++k) {
    if (p[k] <= 0) continue;
    chosen = k;
    cdf_chosen = cdf;
    cdf += p[k];
    if (u_lobe < cdf) break;  // rounding past the end keeps the last lobe
  }
  if (chosen < 0) return false;
  float u_extra = clamp((u_lobe - cdf_chosen) / p[chosen], 0.0f, kOneMinusEpsilon);
  BsdfSample s;
  if (lobes_[chosen].type == LobeType::Subsurface) {  // Cycles' subsurface_bounce: weight x sum / its share
    s.flags = lobe_flags(lobes_[chosen]);
    s.f = lobes_[chosen].weight;
    s.pdf = p[chosen];
    s.wi = Vec3(0, 0, -1);
    s.lobe = chosen;
    *out = s;
    return true;
  }
  if (!lobe_sample(lobes_[chosen], wo, u, u_extra, &s, below_shading_)) return false;
  if (s.flags & kLobeSpecular) {
    s.pdf *= p[chosen];
    // The adjoint of a smooth refraction (the limit of the rough one's f(wi, wo) = f(wo, wi) /
    // eta^2); a mirror's Fresnel is the same at both ends.
    if (light_is_wo_ && !lobe_reciprocal(lobes_[chosen]) && (s.flags & kLobeTransmission) && s.eta != 1)
      s.f *= 1 / (s.eta * s.eta);
  } else {
    // Mixture pdf of the direction (one-sample MIS over the lobes' strategies) and the sum of
    // every non-delta lobe's value, so that MIS against light sampling sees one consistent pdf.
    float pdf = p[chosen] * s.pdf;
    if (light_is_wo_ && !lobe_reciprocal(lobes_[chosen])) s.f = lobe_eval(lobes_[chosen], s.wi, wo);
    s.f *= terminator_terms(lobes_[chosen], wo, s.wi);
    for (int k = 0; k < count_; ++k) {
      if (k == chosen || lobe_is_delta(lobes_[k])) continue;
      float pk;
      s.f += lobe_value(lobes_[k], wo, s.wi, &pk) * terminator_terms(lobes_[k], wo, s.wi);
      pdf += p[k] * pk;
    }
    s.pdf = pdf;
  }
  if (!sanitize(&s)) return false;
  *out = s;
  return true;
}

Spectrum Bsdf::transparency() const {
  Spectrum t(0.0f);
  for (int i = 0; i < count_; ++i)
    if (lobes_[i].type == LobeType::Transparent) t += lobes_[i].weight;
  return t;
}

void Bsdf::keep_transparent() {
  int kept = 0;
  for (int i = 0; i < count_; ++i)
    if (lobes_[i].type == LobeType::Transparent) lobes_[kept++] = lobes_[i];
  count_ = kept;
}

bool Bsdf::pass_transparent(float u, Spectrum* beta, bool defensive) {
  float sum = 0;
  for (int i = 0; i < count_; ++i) sum += std::abs(average(lobes_[i].weight));
  const float floor = defensive && count_ > 1 ? 0.125f * sum : 0.0f;
  float through = 0, rest = 0;
  for (int i = 0; i < count_; ++i)
    (lobes_[i].type == LobeType::Transparent ? through : rest) += std::max(std::abs(average(lobes_[i].weight)), floor);
  if (!(through > 0)) return false;
  const float p = rest > 0 ? through / (through + rest) : 1.0f;
  if (u < p) {
    *beta *= transparency() * (1 / p);
    return true;
  }
  int kept = 0;
  for (int i = 0; i < count_; ++i)
    if (lobes_[i].type != LobeType::Transparent) lobes_[kept++] = lobes_[i];
  count_ = kept;
  *beta *= 1 / (1 - p);
  return false;
}

// The lobes' weights summed and clamped to [0, 1] (Cycles' denoising albedo likewise sums closure
// weights); the Fresnel layers (specular, clearcoat) count their Fresnel at the hemispherical
// average f0 + (1 - f0)/21, the sheen Cycles' avg_value (1 - c)^5 c averaged likewise: 1/21.
Spectrum Bsdf::albedo() const {
  Spectrum a(0.0f);
  for (int k = 0; k < count_; ++k) {
    Spectrum w = vmax(lobes_[k].weight, Spectrum(0.0f));
    const LobeType t = lobes_[k].type;
    // The BSSRDF's weight holds its retro-reflection's (Cycles' denoising albedo skips it too).
    if (t == LobeType::PrincipledDiffuse && lobes_[k].diffuse_part == DiffusePart::RetroReflection) continue;
    if (t == LobeType::SpecularGGX || t == LobeType::Clearcoat || (t == LobeType::MultiGGX && lobes_[k].ms_fresnel)) {
      Spectrum f0 = t == LobeType::Clearcoat ? kClearcoatF0 : vmin(vmax(lobes_[k].f0, Spectrum(0.0f)), Spectrum(1.0f));
      w *= f0 + (Spectrum(1.0f) - f0) * (1.0f / 21.0f);
    } else if (t == LobeType::Sheen) {
      w *= 1.0f / 21.0f;
    } else if (lobe_is_glass(t) && lobes_[k].glass_part != GlassPart::Both) {
      // One branch alone: its weight at normal incidence.
      const GlassSplit g = glass_split(lobes_[k], 1, lobe_eta(lobes_[k]));
      w = w * g.reflect + w * vmax(lobes_[k].refraction_tint, Spectrum(0.0f)) * g.refract;
    }
    a += w;
  }
  return vmin(vmax(a, Spectrum(0.0f)), Spectrum(1.0f));
}

PassKind lobe_pass_kind(const Lobe& lobe, bool transmit) {
  switch (lobe.type) {
    case LobeType::Diffuse:
    case LobeType::PrincipledDiffuse:
    case LobeType::Sheen:
    case LobeType::DiffuseToon:
    case LobeType::Translucent:
    case LobeType::Subsurface:
      return PassKind::Diffuse;  // Cycles' CLOSURE_IS_BSDF_DIFFUSE range (and BSSRDFs)
    case LobeType::Dielectric:
    case LobeType::DielectricBeckmann:
    case LobeType::MultiGGXGlass:
      return transmit ? PassKind::Transmission : PassKind::Glossy;
    default:
      return PassKind::Glossy;
  }
}

void Bsdf::eval_kinds(const Vec3& wo, const Vec3& wi, Spectrum* out) const {
  out[0] = out[1] = out[2] = Spectrum(0.0f);
  const bool transmit = wo.z * wi.z < 0;
  for (int k = 0; k < count_; ++k) {
    if (lobe_is_delta(lobes_[k]) || lobes_[k].type == LobeType::Transparent) continue;
    const Spectrum f = lobe_eval(lobes_[k], wo, wi) * terminator_terms(lobes_[k], wo, wi);
    if (is_finite(f)) out[int(lobe_pass_kind(lobes_[k], transmit))] += f;
  }
}

void Bsdf::kind_colors(const Vec3& wo, Spectrum* out) const {
  out[0] = out[1] = out[2] = Spectrum(0.0f);
  for (int k = 0; k < count_; ++k) {
    const Lobe& l = lobes_[k];
    if (l.type == LobeType::Transparent) continue;
    if (lobe_is_glass(l.type)) {
      // Cycles' closure weights: the reflection's weight x F, the refraction's weight x base x
      // max(1e-4, 1 - F) (the Refraction BSDF's: its weight).
      const GlassSplit g = glass_split(l, std::abs(wo.z), wo.z < 0 ? 1 / lobe_eta(l) : lobe_eta(l));
      if (!glass_only_refracts(l)) out[int(PassKind::Glossy)] += l.weight * g.reflect;
      if (l.glass_part != GlassPart::Reflection)
        out[int(PassKind::Transmission)] += l.weight * l.refraction_tint * std::max(1e-4f, g.refract);
    } else {
      out[int(lobe_pass_kind(l, false))] += l.weight;
    }
  }
}

uint32_t Bsdf::flags() const {
  uint32_t f = 0;
  for (int k = 0; k < count_; ++k) f |= lobe_flags(lobes_[k]);
  return f;
}

bool Bsdf::has_non_delta() const {
  for (int k = 0; k < count_; ++k)
    if (!lobe_is_delta(lobes_[k])) return true;
  return false;
}

}  // namespace lt
