// BSDF lobes and their mixture (see bsdf.h). Formulas follow Cycles 3.4's closures so that the same
// material renders to the same mean image:
//   Diffuse      bsdf_diffuse (Lambert) / bsdf_oren_nayar (Fujii's improved Oren-Nayar, as Cycles)
//   GlossyGGX    bsdf_microfacet_ggx, no Fresnel, separable Smith G = G1(wo) G1(wi)
//   Dielectric   Cycles' Glass BSDF node: a GGX reflection closure weighted by F(wo.n) and a GGX
//                refraction closure (Walter et al. 2007) weighted by 1 - F(wo.n), F the exact
//                dielectric Fresnel at the macro normal; no 1/eta^2 radiance scaling
//   SpecularGGX  bsdf_microfacet_ggx_fresnel_setup as the Principled BSDF sets it up: GGX
//                reflection times interpolate_fresnel_color, f0 (1 - FH) + FH with
//                FH = (F(wi.m, eta) - F(1, eta)) / (1 - F(1, eta)), F the dielectric Fresnel
//   Transparent  bsdf_transparent
//   PrincipledDiffuse  bsdf_principled_diffuse with PRINCIPLED_DIFFUSE_FULL (Burley 2012)
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

namespace lt {

namespace {

// Below |eta - 1| the refraction lobe is narrower than anything the float maths can resolve; the
// interface is then treated as smooth (Cycles uses 1e-4 the same way).
constexpr float kEtaDeltaEpsilon = 1e-3f;

inline Vec3 flip_z(const Vec3& v) { return {v.x, v.y, -v.z}; }

inline float lobe_alpha(const Lobe& l) { return l.alpha >= 0 ? std::min(l.alpha, 1.0f) : 0.0f; }  // NaN -> 0
inline float lobe_eta(const Lobe& l) { return (l.eta > 0 && std::isfinite(l.eta)) ? l.eta : 1.0f; }
inline float lobe_sigma(const Lobe& l) { return l.roughness > 0 ? std::min(l.roughness, 1.0f) : 0.0f; }

// The lobe as seen from below (-Z): the frame is mirrored, and glass's relative IOR inverts, since
// eta is the IOR of the -Z side over the +Z side. This is what a reverse evaluation needs (BDPT's
// pdf of the opposite direction through glass), and it keeps bent shading normals finite.
const Lobe& lobe_from_below(const Lobe& l, Lobe* tmp) {
  if (l.type != LobeType::Dielectric) return l;
  *tmp = l;
  tmp->eta = 1 / lobe_eta(l);
  return *tmp;
}

bool lobe_is_delta(const Lobe& l) {
  switch (l.type) {
    case LobeType::Diffuse:
    case LobeType::PrincipledDiffuse:
      return false;
    case LobeType::GlossyGGX:
    case LobeType::SpecularGGX:
      return !(lobe_alpha(l) >= kSmoothAlpha);
    case LobeType::Dielectric: {
      float eta = lobe_eta(l);  // symmetric in eta and 1/eta, so both sides agree
      return !(lobe_alpha(l) >= kSmoothAlpha) || std::abs(eta - 1) < kEtaDeltaEpsilon ||
             std::abs(1 / eta - 1) < kEtaDeltaEpsilon;
    }
    case LobeType::Transparent:
      return true;
  }
  return true;
}

// G1(w) / |w.z| for GGX, finite down to w.z = 0 (then 2 / (alpha sin)).
inline float ggx_G1_over_cos(const Vec3& w, float alpha) {
  float c = std::abs(w.z);
  float s2 = w.x * w.x + w.y * w.y;
  float d = c + std::sqrt(alpha * alpha * s2 + c * c);
  return d > 0 ? 2 / d : 0;
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

// Burley 2012 ("Physically Based Shading at Disney", eq. 4 with its retro-reflection), as Cycles
// 3.4's bsdf_principled_diffuse with PRINCIPLED_DIFFUSE_FULL: f = (1/pi) [(1 - FV/2)(1 - FL/2)
// + RR (FL + FV + FL FV (RR - 1))], FL = (1 - cos_i)^5, FV = (1 - cos_o)^5, RR = roughness (1 + i.o)
// (= 2 roughness (i.h)^2). Equal to Burley's (1 + (Fd90 - 1) FL)(1 + (Fd90 - 1) FV) with Fd90 =
// 1/2 + RR. o.z > 0.
Spectrum principled_diffuse_eval(const Lobe& l, const Vec3& o, const Vec3& i) {
  if (i.z <= 0) return Spectrum(0.0f);
  const float r = lobe_sigma(l);  // the roughness, clamped to [0, 1] as Cycles' node does
  auto schlick = [](float c) {
    const float m = clamp(1 - c, 0.0f, 1.0f);
    return (m * m) * (m * m) * m;
  };
  const float fl = schlick(i.z), fv = schlick(o.z);
  const float rr = r * (1 + dot(i, o));
  const float f = (1 - 0.5f * fv) * (1 - 0.5f * fl) + rr * (fl + fv + fl * fv * (rr - 1));
  return l.weight * (kInvPi * f);
}

// ---- GGX reflection (GlossyGGX, SpecularGGX, Dielectric's reflection) -------------------------
// f = D G1(o) G1(i) / (4 cos_o cos_i) (Cycles' separable Smith G), pdf = D_o(m) / (4 o.m)
// = G1(o) D / (4 cos_o). Both from the half vector of (o, i) so sample() and pdf() agree.
float ggx_reflect(const Vec3& o, const Vec3& i, float alpha, float* pdf, float* cos_oh) {
  *pdf = 0;
  if (i.z <= 0 || o.z <= 0) return 0;
  Vec3 h = o + i;
  float len = length(h);
  if (!(len > 0)) return 0;
  Vec3 m = h / len;
  float d = ggx_D(m, alpha);
  float g1o = ggx_G1_over_cos(o, alpha);
  *pdf = 0.25f * g1o * d;
  if (cos_oh) *cos_oh = clamp(dot(o, m), 0.0f, 1.0f);
  return 0.25f * d * g1o * ggx_G1_over_cos(i, alpha);
}

bool ggx_sample_reflect(const Vec3& o, float alpha, Vec2 u, Vec3* i) {
  Vec3 m = ggx_sample_visible_normal(o, alpha, u);
  float c = dot(o, m);
  if (!(c > 0)) return false;
  *i = normalize(m * (2 * c) - o);
  return i->z > 0 && is_finite(*i);
}

// ---- GGX refraction (Walter et al. 2007, eq. 21 without Fresnel and without 1/eta^2) ----------
// o.z > 0 on the side of relative IOR 1, i.z < 0 inside (relative IOR eta). The generalised half
// vector is m = +-normalize(o + eta i), oriented to m.z > 0; the pair is valid only if o.m > 0 and
// i.m < 0. f = D G1(o) G1(i) eta^2 |o.m| |i.m| / (cos_o cos_i (o.m + eta i.m)^2),
// pdf = D_o(m) eta^2 |i.m| / (o.m + eta i.m)^2 (the Jacobian of the refraction map).
float ggx_refract(const Vec3& o, const Vec3& i, float alpha, float eta, float* pdf) {
  *pdf = 0;
  if (i.z >= 0 || o.z <= 0) return 0;
  Vec3 ht = o + i * eta;
  float len2 = length_squared(ht);
  if (!(len2 > 0)) return 0;
  Vec3 m = ht / std::sqrt(len2);
  if (m.z < 0) m = -m;
  float om = dot(o, m), im = dot(i, m);
  if (!(om > 0) || !(im < 0)) return 0;
  float d = ggx_D(m, alpha);
  float g1o = ggx_G1_over_cos(o, alpha);
  float jac = eta * eta * -im / len2;
  *pdf = g1o * om * d * jac;
  return d * g1o * ggx_G1_over_cos(i, alpha) * om * jac;
}

bool ggx_sample_refract(const Vec3& o, float alpha, float eta, Vec2 u, Vec3* i) {
  Vec3 m = ggx_sample_visible_normal(o, alpha, u);
  float c = dot(o, m);
  if (!(c > 0)) return false;
  float sin2_t = (1 - c * c) / (eta * eta);
  if (sin2_t >= 1) return false;  // total internal reflection at this microfacet: Cycles drops it
  float cos_t = std::sqrt(1 - sin2_t);
  *i = normalize(-o / eta + m * (c / eta - cos_t));
  return i->z < 0 && is_finite(*i);
}

// ---- per-lobe evaluation in the frame where o.z > 0 -------------------------------------------
Spectrum eval_upper(const Lobe& l, const Vec3& o, const Vec3& i, float* pdf) {
  *pdf = 0;
  switch (l.type) {
    case LobeType::Diffuse:
    case LobeType::PrincipledDiffuse:
      if (i.z <= 0) return Spectrum(0.0f);
      *pdf = i.z * kInvPi;
      return l.type == LobeType::Diffuse ? diffuse_eval(l, o, i) : principled_diffuse_eval(l, o, i);
    case LobeType::GlossyGGX:
      return l.weight * ggx_reflect(o, i, lobe_alpha(l), pdf, nullptr);
    case LobeType::SpecularGGX: {
      float cos_oh = 0;
      float v = ggx_reflect(o, i, lobe_alpha(l), pdf, &cos_oh);
      return v > 0 ? l.weight * fresnel_principled(l.f0, l.eta, cos_oh) * v : Spectrum(0.0f);
    }
    case LobeType::Dielectric: {
      float alpha = lobe_alpha(l), eta = lobe_eta(l);
      float fr = fresnel_dielectric(o.z, eta);
      float p = 0, v;
      if (i.z > 0) {
        v = fr * ggx_reflect(o, i, alpha, &p, nullptr);
        *pdf = fr * p;
      } else {
        v = (1 - fr) * ggx_refract(o, i, alpha, eta, &p);
        *pdf = (1 - fr) * p;
      }
      return l.weight * v;
    }
    case LobeType::Transparent:
      break;
  }
  return Spectrum(0.0f);
}

bool sanitize(BsdfSample* s) {
  if (!(s->pdf > 0) || !std::isfinite(s->pdf) || !is_finite(s->f) || !is_finite(s->wi)) return false;
  for (int k = 0; k < 3; ++k) s->f[k] = std::max(0.0f, s->f[k]);
  return true;
}

// Lobe selection estimate: the average of the weight, times the specular layer's Fresnel at wo
// (Cycles' sample_weight), but never below its value at 60 degrees, so that a layer black at
// normal incidence (f0 = 0) that reflects at other angles is still sampled. Glass needs no
// factor: its Fresnel split is internal.
float selection_estimate(const Lobe& l, const Vec3& wo) {
  Spectrum w = vmax(l.weight, Spectrum(0.0f));
  if (l.type == LobeType::SpecularGGX)
    w *= vmax(fresnel_principled(l.f0, l.eta, std::abs(wo.z)), fresnel_principled(l.f0, l.eta, 0.5f));
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

// ---- GGX and Fresnel ----------------------------------------------------------------------------

// D(m) = alpha^2 / (pi cos^4 (alpha^2 + tan^2)^2) written as alpha^2 / (pi (sin^2 + alpha^2 cos^2)^2)
// for unit m, which stays accurate as m approaches the normal for small alpha.
float ggx_D(const Vec3& m, float alpha) {
  if (m.z <= 0 || !(alpha > 0)) return 0;
  float a2 = alpha * alpha;
  float d = m.x * m.x + m.y * m.y + a2 * m.z * m.z;
  return d > 0 ? a2 / (kPi * d * d) : 0;
}

// Smith masking 2 / (1 + sqrt(1 + alpha^2 tan^2)) (Walter et al. 2007, eq. 34).
float ggx_G1(const Vec3& w, float alpha) { return std::abs(w.z) * ggx_G1_over_cos(w, alpha); }

// Heitz 2018: stretch wo to the unit-roughness configuration, sample the projected hemisphere
// seen from it, unstretch. Works for wo on either side (mirrored into z >= 0); returns m.z >= 0.
Vec3 ggx_sample_visible_normal(const Vec3& wo, float alpha, Vec2 u) {
  Vec3 vh(alpha * wo.x, alpha * wo.y, std::abs(wo.z));
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
  Vec3 ne(alpha * nh.x, alpha * nh.y, std::max(0.0f, nh.z));
  float nlen = length(ne);
  return nlen > 0 ? ne / nlen : Vec3(0, 0, 1);
}

// Exact unpolarised Fresnel reflectance of a dielectric interface; eta = n_inside / n_outside,
// cos_i < 0 means arriving from inside. Returns 1 under total internal reflection.
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
  if (!(eta > 1)) return c0;                                           // IOR 1 (Specular 0): F(1) = F(cos) = 0
  if (!(eta < INFINITY)) return Spectrum(1.0f);                        // F(1) = 1: a perfect mirror
  const float r = (eta - 1) / (eta + 1), F0 = r * r;                   // fresnel_dielectric_cos(1, eta)
  // FH <= 1; FH < 0 where the dielectric Fresnel dips below F0 (at Specular 5, not at 2), but the
  // blend stays >= (f0 - F0) / (1 - F0) >= 0 for f0 >= F0 (the Principled BSDF's f0 unless its
  // base colour is below 0.08 specular at metallic > 0), and equals the dielectric Fresnel itself
  // for f0 = F0. The clamp keeps the rest (and rounding) in [0, 1].
  const float fh = (fresnel_dielectric(clamp(cos_i, 0.0f, 1.0f), eta) - F0) / (1 - F0);
  return vmin(vmax(c0 * (1 - fh) + Spectrum(fh), Spectrum(0.0f)), Spectrum(1.0f));
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
      return kLobeDiffuse | kLobeReflection;
    case LobeType::GlossyGGX:
    case LobeType::SpecularGGX:
      return (delta ? kLobeSpecular : kLobeGlossy) | kLobeReflection;
    case LobeType::Dielectric:
      return (delta ? kLobeSpecular : kLobeGlossy) | kLobeReflection | kLobeTransmission;
    case LobeType::Transparent:
      return kLobeSpecular | kLobeTransmission;
  }
  return 0;
}

namespace {
// lobe_eval() and lobe_pdf() from one evaluation.
Spectrum lobe_eval_pdf(const Lobe& l, const Vec3& wo, const Vec3& wi, float* pdf_out) {
  *pdf_out = 0;
  if (wo.z == 0 || lobe_is_delta(l)) return Spectrum(0.0f);
  float pdf;
  Lobe tmp;
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

bool lobe_sample(const Lobe& lobe, const Vec3& wo, Vec2 u, float u_extra, BsdfSample* out) {
  if (wo.z == 0 || !is_finite(wo)) return false;
  const bool flip = wo.z < 0;
  const Vec3 o = flip ? flip_z(wo) : wo;
  Lobe tmp;
  const Lobe& l = flip ? lobe_from_below(lobe, &tmp) : lobe;
  BsdfSample s;
  s.eta = 1;
  if (lobe_is_delta(l)) {
    // f * |wi.z| / pdf equals the lobe's weight times the chosen branch's Fresnel over its
    // probability, which for all of these is the weight itself.
    const Vec3 mirror(-o.x, -o.y, o.z);
    switch (l.type) {
      case LobeType::GlossyGGX:
        s.wi = mirror;
        s.pdf = 1;
        s.f = l.weight / o.z;
        s.flags = kLobeSpecular | kLobeReflection;
        break;
      case LobeType::SpecularGGX:
        s.wi = mirror;
        s.pdf = 1;
        s.f = l.weight * fresnel_principled(l.f0, l.eta, o.z) / o.z;
        s.flags = kLobeSpecular | kLobeReflection;
        break;
      case LobeType::Dielectric: {
        float eta = lobe_eta(l);
        float fr = fresnel_dielectric(o.z, eta);
        if (u_extra < fr) {
          s.wi = mirror;
          s.pdf = fr;
          s.f = l.weight * fr / o.z;
          s.flags = kLobeSpecular | kLobeReflection;
        } else {
          float sin2_t = (1 - o.z * o.z) / (eta * eta);
          if (sin2_t >= 1) return false;  // only reachable when fr rounds below 1 at TIR
          float cos_t = std::sqrt(1 - sin2_t);
          s.wi = normalize(Vec3(-o.x / eta, -o.y / eta, -cos_t));
          s.pdf = 1 - fr;
          s.f = l.weight * (1 - fr) / std::abs(s.wi.z);
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
      case LobeType::Diffuse:
      case LobeType::PrincipledDiffuse:
        return false;
    }
  } else {
    const float alpha = lobe_alpha(l);
    switch (l.type) {
      case LobeType::Diffuse:
      case LobeType::PrincipledDiffuse:
        s.wi = sample_cosine_hemisphere(u);
        if (!(s.wi.z > 0)) return false;
        s.flags = kLobeDiffuse | kLobeReflection;
        break;
      case LobeType::GlossyGGX:
      case LobeType::SpecularGGX:
        if (!ggx_sample_reflect(o, alpha, u, &s.wi)) return false;
        s.flags = kLobeGlossy | kLobeReflection;
        break;
      case LobeType::Dielectric: {
        float eta = lobe_eta(l);
        float fr = fresnel_dielectric(o.z, eta);
        if (u_extra < fr) {
          if (!ggx_sample_reflect(o, alpha, u, &s.wi)) return false;
          s.flags = kLobeGlossy | kLobeReflection;
        } else {
          if (!ggx_sample_refract(o, alpha, eta, u, &s.wi)) return false;
          s.flags = kLobeGlossy | kLobeTransmission;
          s.eta = eta;
        }
        break;
      }
      case LobeType::Transparent:
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
float Bsdf::bump_term(const Lobe& lobe, const Vec3& wo, const Vec3& wi) const {
  if (!bumped_ || (lobe.type != LobeType::Diffuse && lobe.type != LobeType::PrincipledDiffuse)) return 1.0f;
  const Vec3& l = light_is_wo_ ? wo : wi;
  const float den = l.z * smooth_.z;
  const float g = den != 0 ? dot(smooth_, l) / den : 0.0f;
  if (g >= 1) return 1.0f;
  if (!(g >= 0)) return 0.0f;
  return -g * g * g + g * g + g;
}

Spectrum Bsdf::eval(const Vec3& wo, const Vec3& wi, float* pdf) const {
  Spectrum f(0.0f);
  float p_total = 0;
  float p[kMaxLobes];
  if (!pdf) {
    for (int k = 0; k < count_; ++k)
      f += lobe_eval(lobes_[k], wo, wi) * bump_term(lobes_[k], wo, wi);  // zero for delta lobes
  } else if (selection_probabilities(*this, wo, p)) {
    for (int k = 0; k < count_; ++k) {
      if (lobe_is_delta(lobes_[k])) continue;
      float pk;
      f += lobe_eval_pdf(lobes_[k], wo, wi, &pk) * bump_term(lobes_[k], wo, wi);
      p_total += p[k] * pk;
    }
  } else {
    for (int k = 0; k < count_; ++k) f += lobe_eval(lobes_[k], wo, wi) * bump_term(lobes_[k], wo, wi);
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
  if (!lobe_sample(lobes_[chosen], wo, u, u_extra, &s)) return false;
  if (s.flags & kLobeSpecular) {
    s.pdf *= p[chosen];
  } else {
    // Mixture pdf of the direction (one-sample MIS over the lobes' strategies) and the sum of
    // every non-delta lobe's value, so that MIS against light sampling sees one consistent pdf.
    float pdf = p[chosen] * s.pdf;
    s.f *= bump_term(lobes_[chosen], wo, s.wi);
    for (int k = 0; k < count_; ++k) {
      if (k == chosen || lobe_is_delta(lobes_[k])) continue;
      float pk;
      s.f += lobe_eval_pdf(lobes_[k], wo, s.wi, &pk) * bump_term(lobes_[k], wo, s.wi);
      pdf += p[k] * pk;
    }
    s.pdf = pdf;
  }
  if (!sanitize(&s)) return false;
  *out = s;
  return true;
}

// The lobes' weights summed and clamped to [0, 1] (Cycles' denoising albedo likewise sums closure
// weights); the specular layer counts its Fresnel at the hemispherical average f0 + (1 - f0)/21.
Spectrum Bsdf::albedo() const {
  Spectrum a(0.0f);
  for (int k = 0; k < count_; ++k) {
    Spectrum w = vmax(lobes_[k].weight, Spectrum(0.0f));
    if (lobes_[k].type == LobeType::SpecularGGX) {
      Spectrum f0 = vmin(vmax(lobes_[k].f0, Spectrum(0.0f)), Spectrum(1.0f));
      w *= f0 + (Spectrum(1.0f) - f0) * (1.0f / 21.0f);
    }
    a += w;
  }
  return vmin(vmax(a, Spectrum(0.0f)), Spectrum(1.0f));
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
