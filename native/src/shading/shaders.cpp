#include "shading/shaders.h"

#include "geometry/geometry.h"
#include "shading/bsdf.h"
#include "shading/material.h"

namespace lt {

namespace {

float unit(float x) { return std::isfinite(x) ? clamp(x, 0.0f, 1.0f) : 0.0f; }
Vec3 finite(Vec3 c) {
  for (int k = 0; k < 3; ++k) c[k] = std::isfinite(c[k]) ? c[k] : 0.0f;
  return c;
}
Vec3 non_negative(Vec3 c) {
  for (int k = 0; k < 3; ++k) c[k] = std::isfinite(c[k]) ? std::max(0.0f, c[k]) : 0.0f;
  return c;
}
// Glass and Principled IOR as Cycles 3.4 takes it (fmaxf(ior, 1e-5f)): below 1 is an optically
// thinner inside (an air bubble in water, IOR 0.75, reflects totally beyond asin(0.75) = 48.6
// degrees from its normal); 0 or less becomes 1e-5, a near-perfect mirror.
float glass_ior(float ior) { return std::max(ior, 1e-5f); }
constexpr float kClosureCutoff = 1e-5f;  // Cycles' CLOSURE_WEIGHT_CUTOFF

// One shading normal per point: the first closure that brings its own (Normal linked) sets it.
void take_normal(Machine& m, const Vec3& n, const Vec3& weight) {
  if (m.has_shading_normal || is_black(weight) || !(dot(n, n) > 0) || !is_finite(n)) return;
  Vec3 N = normalize(n);
  m.shading_normal_raw = normalize(m.untilted(n));
  if (m.ctx) {
    const Vec3 valid = ensure_valid_reflection(m.ctx->Ng, m.ctx->I, N);
    N = is_finite(valid) ? valid : N;
  }
  m.shading_normal = N;
  m.has_shading_normal = true;
}

bool backfacing(const Machine& m) { return m.ctx && m.ctx->backfacing; }

// A tangent for anisotropic lobes (a zero Tangent input stands for the shading point's), turned
// about the normal n by `rotation` turns (Cycles' rotate_around_axis(T, N, rotation * 2 pi)).
void take_tangent(Machine& m, Vec3 t, const Vec3& n, float rotation) {
  if (!(dot(t, t) > 0) || !is_finite(t)) t = m.ctx ? m.ctx->surface_tangent() : Vec3(0.0f);
  if (rotation != 0 && std::isfinite(rotation)) {
    const float a = rotation * 2 * kPi, c = std::cos(a), s = std::sin(a);
    t = t * c + cross(n, t) * s + n * (dot(n, t) * (1 - c));  // Rodrigues
  }
  if (is_black(m.shading_tangent)) m.shading_tangent = t;
}

// Glossy / Anisotropic roughness (bsdf.h): alpha along the tangent and the bitangent.
void anisotropic_alphas(float roughness, float anisotropy, Lobe* l) {
  const float a0 = roughness * roughness;
  const float a = clamp(std::isfinite(anisotropy) ? anisotropy : 0.0f, -0.99f, 0.99f);
  if (a == 0) {
    l->alpha = a0;
    return;
  }
  l->alpha = std::min(1.0f, a < 0 ? a0 / (1 + a) : a0 * (1 - a));
  l->alpha_y = std::min(1.0f, a < 0 ? a0 * (1 + a) : a0 / (1 - a));
}

LobeType glossy_type(uint32_t distribution) {
  switch (distribution) {
    case kDistBeckmann:
      return LobeType::GlossyBeckmann;
    case kDistAshikhminShirley:
      return LobeType::AshikhminShirley;
    case kDistMultiGGX:
      return LobeType::MultiGGX;
    default:
      return LobeType::GlossyGGX;
  }
}

SubsurfaceMethod subsurface_method(uint32_t param) {
  return param <= uint32_t(SubsurfaceMethod::RandomWalk) ? SubsurfaceMethod(param) : SubsurfaceMethod::RandomWalk;
}

// Cycles 3.4's bssrdf_alloc and bssrdf_setup (closure/bssrdf.h): the retro-reflection of the
// Principled BSDF's diffuse (roughness >= 0; the Subsurface Scattering node has none) beside the
// BSSRDF, channels of radius below 1e-8 a diffuse of their weight, the rest the Subsurface lobe.
void add_bssrdf(Machine& m, Vec3 weight, Vec3 radius, const Vec3& albedo, float roughness, float ior, float anisotropy,
                SubsurfaceMethod method) {
  if (!(std::abs(average(weight)) >= kClosureCutoff)) return;
  if (roughness >= 0) {
    Lobe retro;
    retro.type = LobeType::PrincipledDiffuse;
    retro.diffuse_part = DiffusePart::RetroReflection;
    retro.roughness = roughness;
    retro.weight = weight;
    m.bsdf->add(retro);
  }
  Vec3 small(0.0f);
  for (int k = 0; k < 3; ++k)
    if (!(radius[k] >= 1e-8f)) {
      small[k] = weight[k];
      weight[k] = radius[k] = 0;
    }
  if (!is_black(small)) {
    Lobe d;
    d.type = roughness >= 0 ? LobeType::PrincipledDiffuse : LobeType::Diffuse;
    d.diffuse_part = DiffusePart::Lambert;
    d.weight = small;
    m.bsdf->add(d);
  }
  if (is_black(weight)) return;
  Lobe l;
  l.type = LobeType::Subsurface;
  l.weight = weight;
  l.sss_albedo = albedo;
  l.sss_method = method;
  l.sss_fresnel = roughness >= 0;
  // Clamps protecting against extreme values, as Cycles'.
  const float eta = clamp(std::isfinite(ior) ? ior : 1.4f, 1.01f, 3.8f);
  l.sss_anisotropy = clamp(std::isfinite(anisotropy) ? anisotropy : 0.0f, 0.0f, 0.9f);
  l.sss_radius = bssrdf_radius(radius, albedo, method, eta);
  m.bsdf->add(l);
}

// Cycles 3.4 svm_node_closure_bsdf, CLOSURE_BSSRDF_*_ID: the Subsurface Scattering node.
void subsurface_node(const Instr& in, Machine& m, const Vec3& weight) {
  take_normal(m, m.v(in.in[1]), weight);
  const Vec3 color = non_negative(m.v(in.in[2]));
  if (!m.ctx || !m.ctx->subsurface) {  // after a diffuse bounce: Cycles' diffuse of the colour
    Lobe d;
    d.weight = weight * color;
    m.bsdf->add(d);
    return;
  }
  const float scale = m.f(in.in[3]);
  const Vec3 radius = non_negative(m.v(in.in[4]) * (std::isfinite(scale) ? scale : 0.0f));
  add_bssrdf(m, weight * color, radius, color, -1, m.f(in.in[5]), m.f(in.in[6]), subsurface_method(in.param[0]));
}

void principled(const Instr& in, Machine& m, Vec3 weight) {
  // Cycles 3.4 svm_node_closure_principled. Alpha below 1 makes the rest of the closure partly
  // transparent.
  const float alpha = unit(m.f(in.in[23]));
  if (alpha < 1) {
    Lobe t;
    t.type = LobeType::Transparent;
    t.weight = weight * (1 - alpha);
    m.bsdf->add(t);
    weight *= alpha;
  }
  const Vec3 normal = m.v(in.in[1]);
  take_normal(m, normal, weight);
  const float subsurface = unit(m.f(in.in[3]));
  // Cycles 3.4's BSSRDF colour, mix(base, Subsurface Color, Subsurface). Where the closure makes
  // no BSSRDF (after a diffuse bounce; BDPT: ShadingContext::subsurface) it is the base colour of
  // every layer, as Cycles' base_color = mixed_ss_base_color under PATH_RAY_DIFFUSE_ANCESTOR.
  const Vec3 mixed = lerp(subsurface, non_negative(m.v(in.in[2])), non_negative(m.v(in.in[5])));
  const bool bssrdf = m.ctx && m.ctx->subsurface;
  const Vec3 base = bssrdf ? non_negative(m.v(in.in[2])) : mixed;
  const float metallic = unit(m.f(in.in[8]));
  const bool multiscatter = in.param[0] == kDistMultiGGX;
  const float transmission = unit(m.f(in.in[19])) * (1 - metallic);
  const float r = unit(m.f(in.in[11]));
  // 12.5 is where 0.08 specular reaches 1 (an infinite IOR); NaN becomes 0.
  const float spec = std::min(std::max(0.0f, m.f(in.in[9])), 12.5f);
  const float diffuse_weight = (1 - metallic) * (1 - transmission);
  // The base colour normalised by its luminance: the tint of sheen (Rec. 709 luminance, Cycles'
  // linear_rgb_to_gray) and of specular (Cycles 3.4 uses the approximation 0.3 R + 0.6 G + 0.1 B
  // there, svm_node_closure_bsdf).
  const float lum = 0.2126f * base.x + 0.7152f * base.y + 0.0722f * base.z;
  const Vec3 tint = lum > 0 ? base / lum : Vec3(1.0f);
  const float spec_lum = 0.3f * base.x + 0.6f * base.y + 0.1f * base.z;
  const Vec3 spec_tint = spec_lum > 0 ? base / spec_lum : Vec3(1.0f);
  if (bssrdf && subsurface > kClosureCutoff) {
    if (std::abs(average(mixed)) > kClosureCutoff)
      add_bssrdf(m, weight * mixed * diffuse_weight, non_negative(m.v(in.in[4]) * subsurface), mixed, r, m.f(in.in[6]),
                 m.f(in.in[7]), subsurface_method(in.param[1]));
  } else {
    Lobe d;
    d.type = LobeType::PrincipledDiffuse;
    d.roughness = r;
    d.weight = weight * base * diffuse_weight;
    m.bsdf->add(d);
  }
  const float sheen = std::max(0.0f, m.f(in.in[14]));
  if (sheen > kClosureCutoff && diffuse_weight > kClosureCutoff) {
    Lobe s;
    s.type = LobeType::Sheen;
    s.weight = weight * lerp(unit(m.f(in.in[15])), Vec3(1.0f), tint) * (sheen * diffuse_weight);
    m.bsdf->add(s);
  }
  // Cycles leaves the layer out when Specular and Metallic are both below its closure cutoff.
  if (spec > kClosureCutoff || metallic > kClosureCutoff) {
    Lobe g;
    // Cycles 3.4 keeps single-scattering GGX at Roughness <= 0.075 under Multiscatter GGX.
    g.type = multiscatter && r > 0.075f ? LobeType::MultiGGX : LobeType::SpecularGGX;
    g.ms_fresnel = g.type == LobeType::MultiGGX;
    g.weight = weight * (1 - transmission);
    // Cycles does not clamp Anisotropic: a linked value below 0 turns the lobe the other way, one
    // above 1/0.9 makes aspect 0 (alpha saturates to 1). NaN is 0.
    const float anisotropic = std::isfinite(m.f(in.in[12])) ? m.f(in.in[12]) : 0.0f;
    if (anisotropic != 0) {
      // bsdf.h: alpha = r^2 / aspect, alpha_y = r^2 aspect, along the (rotated) tangent.
      const float aspect = std::sqrt(std::max(0.0f, 1 - 0.9f * anisotropic));
      g.alpha = aspect > 0 ? r * r / aspect : (r > 0 ? 1.0f : 0.0f);
      g.alpha_y = r * r * aspect;
      take_tangent(m, m.v(in.in[25]), m.has_shading_normal ? m.shading_normal : m.ctx->N, m.f(in.in[13]));
    } else {
      g.alpha = r * r;
    }
    const Vec3 tinted = lerp(unit(m.f(in.in[10])), Vec3(1.0f), spec_tint);
    g.f0 = lerp(metallic, tinted * (0.08f * spec), base);  // fresnel_principled saturates it
    g.eta = principled_specular_ior(spec);
    m.bsdf->add(g);
  }
  if (transmission > 0) {
    Lobe t;
    // Multiscatter GGX above Roughness 0.05: one closure (MultiGGXGlass) with the same colours.
    t.type = multiscatter && r > 0.05f ? LobeType::MultiGGXGlass : LobeType::Dielectric;
    t.ms_fresnel = t.type == LobeType::MultiGGXGlass;
    t.ms_color = vmin(base, Vec3(1.0f));
    // Cycles 3.4: a reflection closure of weight transmission x F, coloured by
    // interpolate_fresnel_color towards cspec0 = mix(1, base, Specular Tint), and a refraction
    // closure of weight base x transmission x (1 - F).
    t.weight = weight * transmission;
    t.refraction_tint = base;
    t.glass_f0 = lerp(unit(m.f(in.in[10])), Vec3(1.0f), base);
    t.alpha = r * r;
    const float ior = glass_ior(m.f(in.in[18]));
    t.eta = backfacing(m) ? 1 / ior : ior;
    // Cycles 3.4 (GGX; the add-on hands Multiscatter GGX, whose glass ignores it, a zero): the
    // refraction closure's roughness is 1 - (1 - Roughness)(1 - Transmission Roughness); when it
    // differs from the reflection's the two closures are separate lobes.
    const float tr = unit(m.f(in.in[20]));
    if (tr > 0 && r < 1) {
      Lobe refract = t;
      const float rt = 1 - (1 - r) * (1 - tr);
      refract.glass_part = GlassPart::Refraction;
      refract.alpha = rt * rt;
      t.glass_part = GlassPart::Reflection;
      m.bsdf->add(t);
      m.bsdf->add(refract);
    } else {
      m.bsdf->add(t);
    }
  }
  const float clearcoat = std::max(0.0f, m.f(in.in[16]));
  if (clearcoat > kClosureCutoff) {
    Lobe c;
    c.type = LobeType::Clearcoat;
    c.weight = weight * (0.25f * clearcoat);
    const float cr = unit(m.f(in.in[17]));
    c.alpha = cr * cr;
    m.bsdf->add(c);
  }
}

const OpSignature kSignatures[] = {
    {"vvf", "", "", false},                           // emission
    {"vvvf", "", "", false},                          // diffuse
    {"vvvf", "", "i", false},                         // glossy
    {"vvvff", "", "i", false},                        // glass
    {"vv", "", "", false},                            // transparent
    {"vvvfvvfffffffffffffffvffvv", "", "ii", false},  // principled
    {"vf", "vv", "", true},                           // mix weights
    {"v", "", "", false},                             // holdout
    {"vvvfffv", "", "i", false},                      // anisotropic
    {"vvvf", "", "", false},                          // velvet
    {"vvv", "", "", false},                           // translucent
    {"vvvff", "", "i", false},                        // toon
    {"f", "", "i", false},                            // aov value
    {"v", "", "i", false},                            // aov color
};

const OpSignature kRefractionSignature = {"vvvff", "", "i", false};
const OpSignature kSubsurfaceSignature = {"vvvfvff", "", "i", false};

const OpSignature kHairSignatures[] = {
    {"vvffvvffffffff", "", "ii", false},  // principled hair
    {"vvfffv", "", "i", false},           // hair bsdf
};

// The hair lobes' tangent T (world, unit) in the local frame the integrator will build from the
// machine's normal and tangent (local_frame), which T becomes unless a closure set one before.
void take_hair_tangent(Machine& m, const Vec3& T, Lobe* l) {
  if (is_black(m.shading_tangent)) m.shading_tangent = T;
  const Vec3 n = m.has_shading_normal ? facing_normal(m.shading_normal, m.ctx->Ng) : m.ctx->N;
  const Frame f(n, m.shading_tangent);
  l->hair_tangent = normalize(f.to_local(T));
}

// The curve's direction (Cycles' sd->dPdu), else the shading point's tangent.
Vec3 hair_direction(const Machine& m) {
  if (length_squared(m.ctx->dpdu) > 0) return normalize(m.ctx->dpdu);
  const Vec3 t = m.ctx->surface_tangent();
  return is_black(t) ? Frame(m.ctx->N).s : t;
}

// Cycles' Random of a curve (ATTR_STD_CURVE_RANDOM).
float curve_random(const ShadingContext& c) {
  if (!c.mesh || c.mesh->kind != GeometryKind::Curves || c.curve < 0) return -1;
  return c.mesh->curves.random[size_t(c.curve)];
}

// Chiang et al.'s roughness maps (Cycles' bsdf_principled_hair_setup): v from the longitudinal
// roughness (and the coat's R), s from the azimuthal.
float hair_variance(float r) {
  const float r2 = r * r, r20 = std::pow(r, 20.0f);
  return (0.726f * r + 0.812f * r2 + 3.7f * r20) * (0.726f * r + 0.812f * r2 + 3.7f * r20);
}
float hair_scale(float r) { return (0.265f * r + 1.194f * r * r + 5.372f * std::pow(r, 22.0f)) * 0.626657069f; }
float hair_albedo_scale(float x) {
  return (((((0.245f * x) + 5.574f) * x - 10.73f) * x + 2.532f) * x - 0.215f) * x + 5.969f;
}
Spectrum sigma_from_reflectance(const Spectrum& c, float radial) {
  Spectrum s;
  for (int k = 0; k < 3; ++k) {
    const float v = std::log(std::max(c[k], 1e-30f)) / hair_albedo_scale(radial);
    s[k] = v * v;
  }
  return s;
}

// Cycles 3.4 svm_node_closure_bsdf, CLOSURE_BSDF_HAIR_PRINCIPLED_ID.
void principled_hair(const Instr& in, Machine& m, const Vec3& weight) {
  Lobe l;
  l.type = LobeType::PrincipledHair;
  l.weight = weight;
  float random = curve_random(*m.ctx);
  if (in.param[1] != 0 || random < 0) random = m.f(in.in[13]);
  const float factor_rough = 1 + 2 * (random - 0.5f) * m.f(in.in[12]);
  const float roughness = m.f(in.in[6]) * factor_rough, radial = m.f(in.in[7]) * factor_rough;
  const float m0 = 1 - unit(m.f(in.in[8]));
  const float v = clamp(std::isfinite(roughness) ? roughness : 0.0f, 0.001f, 1.0f);
  const float s = clamp(std::isfinite(radial) ? radial : 0.0f, 0.001f, 1.0f);
  l.hair_roughness = hair_variance(v);
  l.hair_radial = hair_scale(s);
  l.hair_m0 = hair_variance(clamp(m0 * v, 0.001f, 1.0f));
  l.hair_tilt = std::isfinite(m.f(in.in[10])) ? m.f(in.in[10]) : 0.0f;
  const float ior = m.f(in.in[9]);
  l.eta = std::isfinite(ior) && ior > 1e-5f ? ior : 1e-5f;
  switch (in.param[0]) {
    case kHairAbsorption:
      l.hair_sigma = non_negative(m.v(in.in[5]));
      break;
    case kHairMelanin: {
      float melanin = m.f(in.in[2]) * (1 + 2 * (random - 0.5f) * unit(m.f(in.in[11])));
      melanin = -std::log(std::max(1 - (std::isfinite(melanin) ? melanin : 0.0f), 0.0001f));
      const float redness = std::isfinite(m.f(in.in[3])) ? m.f(in.in[3]) : 0.0f;
      const float eu = melanin * (1 - redness), pheo = melanin * redness;
      // Melanin absorption (Bitterli's remapping, as Cycles'), plus the optional tint.
      l.hair_sigma = Spectrum(0.506f, 0.841f, 1.653f) * eu + Spectrum(0.343f, 0.733f, 1.924f) * pheo +
                     sigma_from_reflectance(non_negative(m.v(in.in[4])), radial);
      break;
    }
    default:
      l.hair_sigma = sigma_from_reflectance(non_negative(m.v(in.in[1])), radial);
      break;
  }
  l.hair_sigma = non_negative(l.hair_sigma);
  take_hair_tangent(m, hair_direction(m), &l);
  m.bsdf->add(l);
}

// Cycles 3.4 svm_node_closure_bsdf, CLOSURE_BSDF_HAIR_REFLECTION_ID and _TRANSMISSION_ID. Off
// curves Cycles takes the surface's dPdv and no offset; Lantern takes its tangent.
void hair_bsdf(const Instr& in, Machine& m, const Vec3& weight) {
  Lobe l;
  l.type = in.param[0] == 1 ? LobeType::HairTransmission : LobeType::HairReflection;
  l.weight = weight * non_negative(m.v(in.in[1]));
  const float ru = m.f(in.in[3]), rv = m.f(in.in[4]);
  l.hair_roughness = clamp(std::isfinite(ru) ? ru : 0.0f, 0.001f, 1.0f);
  l.hair_radial = clamp(std::isfinite(rv) ? rv : 0.0f, 0.001f, 1.0f);
  const float offset = m.f(in.in[2]);
  l.hair_tilt = std::isfinite(offset) ? -offset : 0.0f;
  Vec3 T = m.v(in.in[5]);
  if (!(length_squared(T) > 0) || !is_finite(T)) {
    T = hair_direction(m);
    if (length_squared(m.ctx->dpdu) == 0) l.hair_tilt = 0;
  } else {
    T = normalize(T);
  }
  take_hair_tangent(m, T, &l);
  m.bsdf->add(l);
}

}  // namespace

const OpSignature* shaders_family_signature(uint32_t op) {
  if (op >= kOpPrincipledHair && op <= kOpHairBsdf) return &kHairSignatures[op - kOpPrincipledHair];
  if (op == kOpRefraction) return &kRefractionSignature;
  if (op == kOpSubsurface) return &kSubsurfaceSignature;
  if (op < kOpEmission || op > kOpAovColor) return nullptr;
  return &kSignatures[op - kOpEmission];
}

void exec_shaders_family(const Instr& in, Machine& m) {
  if (in.op == kOpAovValue || in.op == kOpAovColor) {
    if (!m.ctx || !m.ctx->aovs || int(in.param[0]) >= m.ctx->aov_count) return;
    float* o = m.ctx->aovs + 4 * size_t(in.param[0]);
    if (in.op == kOpAovValue) {
      o[0] += m.f(in.in[0]);
    } else {
      const Vec3 c = m.v(in.in[0]);
      o[0] += c.x;
      o[1] += c.y;
      o[2] += c.z;
      o[3] += 1;
    }
    return;
  }
  if (in.op == kOpMixWeights) {
    const Vec3 w = m.v(in.in[0]);
    const float f = unit(m.f(in.in[1]));
    m.set(in.out[0], w * (1 - f));
    m.set(in.out[1], w * f);
    return;
  }
  const Vec3 weight = m.v(in.in[0]);
  if (is_black(weight)) return;
  if (in.op == kOpEmission) {
    // Emission keeps its sign, as Cycles' (a negative colour or strength is negative light).
    m.emitted += weight * finite(m.v(in.in[1])) * m.f(in.in[2]);
    return;
  }
  if (in.op == kOpPrincipled) {
    // Emission first: light sampling runs without lobes.
    const Vec3 e = finite(m.v(in.in[21]));
    if (!is_black(e)) m.emitted += weight * e * m.f(in.in[22]);
    if (m.bsdf) principled(in, m, weight);
    return;
  }
  if (!m.bsdf) return;
  if (in.op == kOpPrincipledHair || in.op == kOpHairBsdf) {
    if (!m.ctx) return;  // folding constants: hair closures need the shading point
    in.op == kOpPrincipledHair ? principled_hair(in, m, weight) : hair_bsdf(in, m, weight);
    return;
  }
  Lobe l;
  switch (in.op) {
    case kOpDiffuse:
      take_normal(m, m.v(in.in[1]), weight);
      l.type = LobeType::Diffuse;
      l.weight = weight * non_negative(m.v(in.in[2]));
      l.roughness = unit(m.f(in.in[3]));
      break;
    case kOpGlossy:
    case kOpAnisotropic: {
      const Vec3 n = m.v(in.in[1]);
      take_normal(m, n, weight);
      const float r = in.param[0] == kDistSharp ? 0.0f : unit(m.f(in.in[3]));
      l.type = in.param[0] == kDistSharp ? LobeType::GlossyGGX : glossy_type(in.param[0]);
      l.weight = weight * non_negative(m.v(in.in[2]));
      if (in.op == kOpAnisotropic && r > 0) {
        anisotropic_alphas(r, m.f(in.in[4]), &l);
        if (l.alpha_y >= 0)
          take_tangent(m, m.v(in.in[6]), m.has_shading_normal ? m.shading_normal : m.ctx->N, m.f(in.in[5]));
      } else {
        l.alpha = r * r;
      }
      // Multiscatter GGX: the colour again for every bounce after the first (Cycles' extra->color).
      if (l.type == LobeType::MultiGGX) l.ms_color = vmin(non_negative(m.v(in.in[2])), Vec3(1.0f));
      break;
    }
    case kOpVelvet:
      take_normal(m, m.v(in.in[1]), weight);
      l.type = LobeType::Velvet;
      l.weight = weight * non_negative(m.v(in.in[2]));
      l.roughness = m.f(in.in[3]);
      break;
    case kOpTranslucent:
      take_normal(m, m.v(in.in[1]), weight);
      l.type = LobeType::Translucent;
      l.weight = weight * non_negative(m.v(in.in[2]));
      break;
    case kOpToon:
      take_normal(m, m.v(in.in[1]), weight);
      l.type = in.param[0] == 1 ? LobeType::GlossyToon : LobeType::DiffuseToon;
      l.weight = weight * non_negative(m.v(in.in[2]));
      l.toon_size = unit(m.f(in.in[3]));
      l.toon_smooth = unit(m.f(in.in[4]));
      break;
    case kOpGlass:
    case kOpRefraction: {
      take_normal(m, m.v(in.in[1]), weight);
      const float r = in.param[0] == kDistSharp ? 0.0f : unit(m.f(in.in[3]));
      l.type = in.param[0] == kDistBeckmann ? LobeType::DielectricBeckmann : LobeType::Dielectric;
      l.weight = weight * non_negative(m.v(in.in[2]));
      if (in.op == kOpGlass && in.param[0] == kDistMultiGGX) {
        l.type = LobeType::MultiGGXGlass;
        l.ms_color = vmin(non_negative(m.v(in.in[2])), Vec3(1.0f));  // Cycles' extra->color
      }
      l.alpha = r * r;
      const float ior = glass_ior(m.f(in.in[4]));
      l.eta = backfacing(m) ? 1 / ior : ior;
      if (in.op == kOpRefraction) l.glass_part = GlassPart::RefractionBsdf;
      break;
    }
    case kOpTransparent:
      l.type = LobeType::Transparent;
      l.weight = weight * non_negative(m.v(in.in[1]));
      break;
    case kOpHoldout:
      m.bsdf->add_holdout(weight);
      return;
    case kOpSubsurface:
      subsurface_node(in, m, weight);
      return;
    default:
      return;
  }
  m.bsdf->add(l);
}

}  // namespace lt
