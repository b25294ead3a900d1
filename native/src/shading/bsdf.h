// Scattering at a surface point as a weighted sum of lobes, like Cycles' closures: a material's
// shader tree is flattened into at most kMaxLobes lobes with RGB weights (mix factors folded in).
//
// All directions are in the local shading frame: +Z is the shading normal, flipped by the caller
// to face the side wo arrives from, so wo.z >= 0 except where shading normals bend it. eta is the
// relative index of refraction inside/outside as seen from wo's side (the caller passes 1/ior on
// back faces). f() values exclude the cosine; the integrator multiplies |wi.z|. Each lobe is
// defined relative to the hemisphere wo lies in: with wo.z < 0 (a reverse evaluation from the far
// side, or a bent shading normal) the frame is mirrored, so reflection stays on wo's side and
// refraction crosses to the other, and glass sees 1/eta from below.
#pragma once

#include <cstdint>

#include "core/math.h"
#include "core/sampling.h"

namespace lt {

enum LobeFlags : uint32_t {
  kLobeReflection = 1,
  kLobeTransmission = 2,
  kLobeDiffuse = 4,
  kLobeGlossy = 8,
  kLobeSpecular = 16,  // delta distribution: eval() and pdf() are zero; only sample() reaches it
  // A microfacet reflection sampled below the shading normal (but kept by the caller's geometric
  // test): see Bsdf::sample_below_shading. eval() is zero there, so only this sample reaches it.
  kLobeBelowShading = 32,
  // The Subsurface lobe was picked (Bsdf::sample): no direction; the caller walks under the
  // surface (integrators/subsurface.h) with weight f / pdf and shades the exit point.
  kLobeSubsurface = 64,
};

// Each type with the Cycles 3.4 node (svm_node_closure_bsdf) and parameters that make it. The caller
// builds the local frame: +Z the closure's normal, +X the tangent for anisotropic lobes (Cycles' T,
// already rotated by the node's Rotation, projected onto the tangent plane), +Y = normal x tangent
// (Cycles' make_orthonormals_tangent). "weight" is the closure weight (colour x mix factor).
enum class LobeType : uint8_t {
  // Diffuse BSDF: roughness = Roughness (Lambert at 0, Oren-Nayar sigma above).
  Diffuse,
  // Glossy / Anisotropic BSDF with distribution GGX (and Sharp: alpha 0): alpha, alpha_y as below.
  // Colour as constant reflectance, no Fresnel.
  GlossyGGX,
  // Glass BSDF (GGX, Sharp): Fresnel-weighted GGX reflection + refraction; eta = IOR (1/IOR on back
  // faces), alpha = Roughness^2; delta at alpha 0. glass_part (below) keeps one branch: the
  // Refraction BSDF node and the Principled glass with a Transmission Roughness.
  Dielectric,
  // Principled BSDF's specular layer: alpha = r^2 / aspect, alpha_y = r^2 aspect with aspect =
  // sqrt(1 - 0.9 Anisotropic), f0 = cspec0, eta = principled_specular_ior(Specular).
  SpecularGGX,
  // Transparent BSDF (delta pass-through).
  Transparent,
  // Principled BSDF's diffuse: roughness = Roughness.
  PrincipledDiffuse,
  // Glossy / Anisotropic BSDF with distribution Beckmann: alpha, alpha_y as for GlossyGGX. Cycles'
  // rational approximation of the Smith G1 in f; the exact visible-normal sampling.
  GlossyBeckmann,
  // Glass BSDF with distribution Beckmann: as Dielectric (alpha = Roughness^2, eta = IOR).
  DielectricBeckmann,
  // Glossy / Anisotropic BSDF with distribution Ashikhmin-Shirley: alpha, alpha_y as for GlossyGGX
  // (exponent 2 / alpha^2 - 2, alphas clamped to [1e-4, 1]; delta at max(alpha, alpha_y) <= 1e-4).
  AshikhminShirley,
  // Principled BSDF's clearcoat (bsdf_microfacet_ggx_clearcoat in Cycles 3.4): alpha =
  // Clearcoat Roughness^2 for Burley's GTR1 distribution, Smith G of GGX at a fixed alpha 0.25,
  // Fresnel of IOR 1.5 (cspec0 0.04); weight = closure weight x 0.25 x Clearcoat (the caller folds
  // the factor in, Cycles puts it in fresnel_color). Frame: the Clearcoat Normal.
  Clearcoat,
  // Principled BSDF's sheen (bsdf_principled_sheen): f = (1 - wi.h)^5; weight = closure weight x
  // Sheen x sheen colour (mix(1, base colour / luminance, Sheen Tint), computed by the caller) x
  // the diffuse weight (1 - Metallic)(1 - Transmission).
  Sheen,
  // Velvet BSDF (bsdf_ashikhmin_velvet): roughness = Sigma (clamped to [0.01, 1]).
  Velvet,
  // Translucent BSDF: Lambert on the side opposite to wo.
  Translucent,
  // Toon BSDF, component Diffuse: toon_size = Size, toon_smooth = Smooth (both clamped to [0, 1]).
  DiffuseToon,
  // Toon BSDF, component Glossy: toon_size = Size, toon_smooth = Smooth, a cone about the mirror
  // direction.
  GlossyToon,
  // Glossy / Anisotropic BSDF with distribution Multiscatter GGX (bsdf_microfacet_multi_ggx, Heitz
  // et al. 2016's random walk, up to 10 bounces, no Fresnel): alpha, alpha_y as for GlossyGGX
  // (clamped to [1e-4, 1]; delta at alpha x alpha_y < 1e-7); weight = closure weight, ms_color =
  // the node's Color (saturated), the extra factor of every bounce after the first. f is Cycles'
  // estimate: exact single scattering plus one random walk seeded from the direction pair.
  // With ms_fresnel, the Principled BSDF's specular at Multiscatter GGX above roughness 0.075
  // (..._multi_ggx_fresnel): alphas, f0 and eta as SpecularGGX.
  MultiGGX,
  // Hair lobes (shading/bsdf_hair.cpp), on curves: hair_tangent is the curve's direction in the
  // local frame (+Z the normal from the curve's axis). They are neither reflection nor
  // transmission by hemisphere: a sample's flags say which side of +Z it left on.
  // Principled Hair BSDF (Chiang et al. 2016 as Cycles 3.4's bsdf_hair_principled.h):
  // hair_sigma = absorption, hair_roughness = v and hair_radial = s (already mapped to variance and
  // logistic scale), hair_m0 = the R lobe's variance (Coat), hair_tilt = cuticle angle alpha,
  // eta = IOR. h comes from wo, as Cycles' from sd->I.
  PrincipledHair,
  // Hair BSDF (Cycles' bsdf_hair.h), Reflection and Transmission: hair_roughness = Roughness U,
  // hair_radial = Roughness V (both clamped to [0.001, 1]), hair_tilt = the node's offset
  // negated (Cycles' bsdf->offset).
  HairReflection,
  HairTransmission,
  // Glass BSDF with distribution Multiscatter GGX (bsdf_microfacet_multi_ggx_glass) and the
  // Principled BSDF's glass at Multiscatter GGX above roughness 0.05 (..._glass_fresnel, with
  // ms_fresnel): Heitz et al. 2016's dielectric walk, reflection and refraction in one closure.
  // alpha = Roughness^2 (isotropic, clamped to [1e-4, 1]; delta at alpha^2 < 1e-7), eta as for
  // Dielectric, ms_color = the node's Color (the Principled: the base colour), weight = closure
  // weight. The Principled's reflection blends glass_f0 towards 1 (interpolate_fresnel_color)
  // and its refraction takes refraction_tint (see bsdf.cpp).
  MultiGGXGlass,
  // A BSSRDF (Cycles 3.4's Bssrdf closure, closure/bssrdf.h): no value and no pdf at the point;
  // picked by sample() (kLobeSubsurface) with Cycles' sample weight, average(weight) x its channels
  // of radius >= 1e-8. sss_radius is the radius after bssrdf_setup_radius, sss_albedo the
  // surface albedo, sss_anisotropy in [0, 0.9], sss_method a SubsurfaceMethod, sss_fresnel the
  // Principled BSDF's (a Lambert-exit principled diffuse at the exit, else a Lambert one).
  Subsurface,
};
constexpr int kLobeTypeCount = int(LobeType::Subsurface) + 1;
// Subsurface methods (the node's subsurface_method / falloff), as Cycles 3.4's closure types.
enum class SubsurfaceMethod : uint8_t { Burley = 0, RandomWalkFixedRadius = 1, RandomWalk = 2 };
// The components of a PrincipledDiffuse lobe (Cycles' PrincipledDiffuseComponents): the whole
// BRDF; with subsurface scattering its Lambert part at channels of radius below 1e-8, its
// retro-reflection beside the BSSRDF, and the Lambert part's exit half (1 - F_L / 2) / pi.
enum class DiffusePart : uint8_t { Full = 0, Lambert = 1, LambertExit = 2, RetroReflection = 3 };
inline bool lobe_is_hair(LobeType t) {
  return t == LobeType::PrincipledHair || t == LobeType::HairReflection || t == LobeType::HairTransmission;
}
// The glass lobes, which reflect or refract with the relative IOR eta (integrators count their
// bounces by the branch sampled). Translucent transmits without crossing an IOR; Cycles counts it
// as a transmission bounce with diffuse ray visibility (integrator/path_state.h).
inline bool lobe_is_glass(LobeType t) {
  return t == LobeType::Dielectric || t == LobeType::DielectricBeckmann || t == LobeType::MultiGGXGlass;
}

// Which branches a glass lobe keeps, and their weights at wo (F the dielectric Fresnel of wo's
// angle at the macro normal), as Cycles 3.4's closures (svm_node_closure_bsdf):
enum class GlassPart : uint8_t {
  Both,        // Glass BSDF: reflection x F and refraction x (1 - F), sampled in that split
  Reflection,  // the Principled glass's reflection closure alone: x F
  Refraction,  // its refraction closure alone: x (1 - F) (a Transmission Roughness of its own)
  // Refraction BSDF node (CLOSURE_BSDF_REFRACTION_ID, MICROFACET_{GGX,BECKMANN}_REFRACTION_ID):
  // refraction alone with no Fresnel factor (the weight is the Color); light that would reflect
  // totally at wo's microfacet is lost, as in Cycles.
  RefractionBsdf,
};

// Glossy / Anisotropic BSDF roughness (svm_node_closure_bsdf): alpha = Roughness^2 when isotropic;
// with Anisotropy a (clamped to [-0.99, 0.99]) alpha = alpha0 / (1 + a), alpha_y = alpha0 (1 + a)
// for a < 0, and alpha = alpha0 (1 - a), alpha_y = alpha0 / (1 - a) otherwise; each clamped to 1.

struct Lobe {
  LobeType type = LobeType::Diffuse;
  Spectrum weight{1.0f};    // colour x mix weight
  float roughness = 0;      // Diffuse: Oren-Nayar sigma; PrincipledDiffuse: the Principled roughness;
                            // Velvet: sigma; microfacet: unused (see alpha)
  float alpha = 0;          // microfacet alpha along the tangent (+X), = roughness^2; below
                            // kSmoothAlpha (for alpha x alpha_y: kSmoothAlpha^2) the lobe is delta
  float alpha_y = -1;       // alpha along the bitangent (+Y); negative: equal to alpha (isotropic)
  float eta = 1.5f;         // Dielectric: relative IOR across the surface from wo's side;
                            // SpecularGGX: the IOR whose dielectric Fresnel shapes the blend to 1
  Spectrum f0{0.04f};       // SpecularGGX: reflectance at normal incidence (Cycles' cspec0)
  float toon_size = 0;      // DiffuseToon, GlossyToon: Size
  float toon_smooth = 0;    // DiffuseToon, GlossyToon: Smooth
  Spectrum ms_color{1.0f};  // MultiGGX(Glass): the colour of each bounce after the first
  // MultiGGX, MultiGGXGlass: the Principled BSDF's closures (Cycles' ..._FRESNEL_ID): the walk
  // colours reflections by interpolate_fresnel_color towards f0 (MultiGGX, with eta) or glass_f0
  // (MultiGGXGlass) and refractions by ms_color, instead of ms_color for every later bounce.
  bool ms_fresnel = false;
  // Dielectric, DielectricBeckmann: the Principled BSDF's glass (Cycles 3.4 makes it a Fresnel
  // reflection closure and a refraction closure of other colours): the refraction's colour
  // relative to weight (the base colour), and the cspec0 its reflection blends towards 1 by
  // fresnel_principled (mix(1, base, Specular Tint)). Both white for the Glass BSDF node.
  Spectrum refraction_tint{1.0f};
  Spectrum glass_f0{1.0f};
  // Hair lobes (see LobeType): unit tangent in the local frame and the fibre's parameters.
  Vec3 hair_tangent{1.0f, 0.0f, 0.0f};
  Spectrum hair_sigma{0.0f};
  float hair_roughness = 0.3f, hair_radial = 0.3f, hair_m0 = 0.3f, hair_tilt = 0;
  GlassPart glass_part = GlassPart::Both;        // Dielectric, DielectricBeckmann: the branches kept
  DiffusePart diffuse_part = DiffusePart::Full;  // PrincipledDiffuse
  // Subsurface (see LobeType).
  Spectrum sss_radius{0.0f}, sss_albedo{0.0f};
  float sss_anisotropy = 0;
  SubsurfaceMethod sss_method = SubsurfaceMethod::RandomWalk;
  bool sss_fresnel = false;
};
// A glass lobe that only refracts (its bounces are transmissions) or that reflects and refracts.
inline bool glass_only_refracts(const Lobe& l) {
  return lobe_is_glass(l.type) && (l.glass_part == GlassPart::Refraction || l.glass_part == GlassPart::RefractionBsdf);
}
inline bool glass_reflects_and_refracts(const Lobe& l) {
  return lobe_is_glass(l.type) && l.glass_part == GlassPart::Both;
}

struct BsdfSample {
  Vec3 wi;
  Spectrum f;          // BSDF value (cosine excluded); for delta lobes f*|wi.z|/pdf is the weight
  float pdf = 0;       // solid-angle pdf of the whole mixture, or the discrete probability if delta
  uint32_t flags = 0;  // the sampled lobe's LobeFlags
  float eta = 1;       // relative IOR crossed (1 for reflection)
  int lobe = -1;       // kLobeSubsurface: the index of the Subsurface lobe picked
};

constexpr int kMaxLobes = 8;
constexpr float kSmoothAlpha = 1e-4f;

class Bsdf {
 public:
  void clear() {
    count_ = 0;
    holdout_ = Spectrum(0.0f);
    overflowed_ = false;
    bumped_ = false;
    frequency_ = 1;
    light_is_wo_ = false;
    below_shading_ = false;
  }
  // Light transport (BDPT's light subpaths): the light arrives along wo, so eval() and sample()
  // give the adjoint BSDF f(wi, wo) (Veach 1997, sec. 3.7.6). It differs from f(wo, wi) for the
  // Toon lobes, which Cycles divides by the light's cosine (f cos = the ramp), the hair lobes,
  // which Cycles computes with sd->I (towards the camera), and the glass lobes: their Fresnel
  // split is taken at wo, and their refraction, without Walter et al.'s 1/eta^2 radiance
  // scaling as Cycles', has f(wo, wi) = eta^2 f(wi, wo) (eta relative from wo's side; Veach
  // sec. 5.2), so a sampled smooth refraction's adjoint weight is 1/eta^2 of its radiance one.
  // The others are reciprocal as Lantern writes them. Pdfs stay those of sampling wi from wo.
  // clear() resets.
  void set_light_is_wo(bool light_is_wo) { light_is_wo_ = light_is_wo; }
  // The interpolated normal (local frame) when a Normal input bent the shading normal: Cycles 3.4
  // then scales its diffuse closures by bump_shadowing_term (kernel/closure/bsdf.h), which darkens
  // light grazing the smooth surface. light_is_wo: light transport (BDPT's light subpaths), where
  // the light arrives along wo rather than wi.
  void set_bump(const Vec3& smooth_local, bool light_is_wo) {
    bumped_ = true;
    smooth_ = smooth_local;
    light_is_wo_ = light_is_wo;
  }
  // The bump's smooth normal in another local frame (BDPT's frames for other viewers, bdpt.h);
  // bumped false: none there.
  void set_smooth(bool bumped, const Vec3& smooth_local) {
    bumped_ = bumped;
    smooth_ = smooth_local;
  }
  // The object's shadow terminator Shading Offset as Cycles' cosine frequency multiplier (1: off;
  // Instance::terminator_frequency); clear() resets it, so set it after the material ran.
  void set_terminator_frequency(float frequency) { frequency_ = frequency; }
  // Cycles 3.4's microfacet sampling (bsdf_microfacet_ggx_sample, _beckmann_sample) keeps a
  // reflection that lands below the shading normal if it is above the geometric one, weighted by
  // G1(wi) computed with cos^2 (so positive), while its eval() is zero there: with a bent normal
  // a rough metal reflects more than its eval() integrates (1.2 % with a 30-degree tilt at
  // roughness 0.6). The path tracers, which agree with Cycles sample by sample, turn this on;
  // BDPT keeps the consistent BSDF its MIS needs. Such samples carry kLobeBelowShading.
  void sample_below_shading(bool on) { below_shading_ = on; }
  // Adds a lobe; lobes whose weight is zero are dropped, lobes past kMaxLobes merge into nothing
  // and are reported through overflowed().
  void add(const Lobe& lobe);
  int count() const { return count_; }
  const Lobe& lobe(int i) const { return lobes_[i]; }
  bool overflowed() const { return overflowed_; }

  // Sum of the non-delta lobes' f, and (pdf not null) the mixture pdf of sampling wi with sample().
  // excluded: bits 1 << PassKind of lobes left out of both (a light hidden from that kind of ray;
  // Cycles' _surface_shader_exclude).
  Spectrum eval(const Vec3& wo, const Vec3& wi, float* pdf, unsigned excluded = 0) const;
  // The mixture pdf alone: eval()'s *pdf to the last bit, without evaluating f.
  float pdf(const Vec3& wo, const Vec3& wi) const;
  // Picks a lobe with probability proportional to its weight's estimate (the weight's average,
  // times the Fresnel at wo for SpecularGGX; see bsdf.cpp), samples it, then (for non-delta
  // lobes) evaluates all non-delta lobes for f and the mixture pdf. For a delta lobe, f and pdf
  // are that lobe's, the pdf times its selection probability.
  bool sample(const Vec3& wo, float u_lobe, Vec2 u, BsdfSample* out) const;
  // Directional albedo estimate of the lobes' weights (for the Albedo pass and Russian roulette).
  Spectrum albedo() const;
  // Cycles' light passes (kernel/film/light_passes.h) split a first bounce by closure kind:
  // eval()'s f per PassKind into out[3] (its sum is eval()'s f), and the kinds' colours as
  // Cycles' surface_shader_diffuse / glossy / transmission (sums of closure weights). Cycles 3.4
  // builds a Glass BSDF from a reflection closure (glossy, weight x F(wo)) and a refraction one
  // (transmission, weight x max(1e-4, 1 - F(wo))): glass lobes split the same way.
  void eval_kinds(const Vec3& wo, const Vec3& wi, Spectrum* out) const;
  void kind_colors(const Vec3& wo, Spectrum* out) const;
  // The summed weights of the Transparent lobes: what a shadow ray passes (Cycles'
  // shader_bsdf_transparency).
  Spectrum transparency() const;
  // Transparency as a choice (the Transparent lobes' share p of the lobes' average weights): with
  // probability p the ray passes straight on and beta is scaled by transparency() / p (returns
  // true); else the Transparent lobes are removed and beta is scaled by 1 / (1 - p). `defensive`
  // (a camera ray's first surface): each lobe's share is at least 1/8 of the sum, Cycles'
  // defensive sampling (surface_shader_prepare_closures), so that what depends on the choice
  // (shader AOVs behind the surface) has Cycles' expectation.
  bool pass_transparent(float u, Spectrum* beta, bool defensive = false);
  // Holdout closures make no lobe: their summed weight (Cycles' CLOSURE_HOLDOUT_ID), which a
  // camera path turns into transparency of the film (integrators/path_state.h, hold_out).
  void add_holdout(const Spectrum& w) { holdout_ += w; }
  const Spectrum& holdout() const { return holdout_; }
  // A holdout object seen by the camera keeps only its Transparent lobes (Cycles'
  // surface_shader_apply_holdout).
  void keep_transparent();
  uint32_t flags() const;  // union of lobe flags
  bool has_non_delta() const;
  // The probabilities with which sample() picks each lobe for this wo; false if none can be.
  bool selection(const Vec3& wo, float* p) const;
  // Each lobe's part of pdf(wo, wi): its selection probability times its own pdf (0 for delta
  // lobes). Given that sample() produced wi, lobe k picked it with probability part[k] / pdf.
  // Returns their sum, pdf(wo, wi).
  float lobe_pdfs(const Vec3& wo, const Vec3& wi, float* part) const;

 private:
  // The lobes, the first count_ of them set. Left unwritten past those: a Bsdf is made per path
  // sample, and filling its eight default lobes (1.3 KB) was 2-3 % of a simple scene's render.
  struct Lobes {
    Lobes() {}  // NOLINT: uninitialised on purpose (add() writes each lobe before it is read)
    Lobe& operator[](int i) { return at[i]; }
    const Lobe& operator[](int i) const { return at[i]; }
    union {
      Lobe at[kMaxLobes];
    };
  } lobes_;
  int count_ = 0;
  Spectrum holdout_{0.0f};
  bool overflowed_ = false;
  bool bumped_ = false, light_is_wo_ = false, below_shading_ = false;
  Vec3 smooth_{0.0f, 0.0f, 1.0f};
  float frequency_ = 1;
  // The shadow terminator factors of a lobe's value: bump shadowing and the shading offset.
  float terminator_terms(const Lobe& lobe, const Vec3& wo, const Vec3& wi) const;
  Spectrum lobe_value(const Lobe& lobe, const Vec3& wo, const Vec3& wi, float* pdf) const;
};

// The kind a Cycles light pass files a closure under (PassKind order: diffuse, glossy,
// transmission); glass lobes are glossy when wi stays on wo's side, transmission otherwise.
enum class PassKind : uint8_t { Diffuse = 0, Glossy = 1, Transmission = 2 };
PassKind lobe_pass_kind(const Lobe& lobe, bool transmit);
// The kind of a sampled delta lobe from its flags.
inline PassKind flags_pass_kind(uint32_t flags) {
  if (flags & kLobeDiffuse) return PassKind::Diffuse;
  return (flags & kLobeTransmission) ? PassKind::Transmission : PassKind::Glossy;
}

// ---- single-lobe routines, exposed for the chi-square tests ----------------------------------
// Hair lobes (bsdf_hair.cpp): f (cosine excluded) with the lobe's weight, its pdf; a direction.
Spectrum hair_eval(const Lobe& lobe, const Vec3& wo, const Vec3& wi, float* pdf);
bool hair_sample(const Lobe& lobe, const Vec3& wo, Vec2 u, float u_extra, Vec3* wi);
Spectrum lobe_eval(const Lobe& lobe, const Vec3& wo, const Vec3& wi);
float lobe_pdf(const Lobe& lobe, const Vec3& wo, const Vec3& wi);
bool lobe_sample(const Lobe& lobe, const Vec3& wo, Vec2 u, float u_extra, BsdfSample* out, bool below_shading = false);
uint32_t lobe_flags(const Lobe& lobe);

// GGX (Trowbridge-Reitz) microfacet distribution with visible-normal sampling (Heitz 2018);
// anisotropic forms with alpha_x along +X and alpha_y along +Y.
float ggx_D(const Vec3& m, float alpha);
float ggx_D(const Vec3& m, float alpha_x, float alpha_y);
float ggx_G1(const Vec3& w, float alpha);
float ggx_G1(const Vec3& w, float alpha_x, float alpha_y);
Vec3 ggx_sample_visible_normal(const Vec3& wo, float alpha, Vec2 u);
Vec3 ggx_sample_visible_normal(const Vec3& wo, float alpha_x, float alpha_y, Vec2 u);
// Beckmann distribution: D, the exact Smith G1 (erf form), Cycles 3.4's rational approximation of
// it (bsdf_beckmann_G1, used in f), and exact visible-normal sampling (Heitz and d'Eon 2014).
float beckmann_D(const Vec3& m, float alpha_x, float alpha_y);
float beckmann_G1(const Vec3& w, float alpha_x, float alpha_y);
float beckmann_G1_cycles(const Vec3& w, float alpha_x, float alpha_y);
Vec3 beckmann_sample_visible_normal(const Vec3& wo, float alpha_x, float alpha_y, Vec2 u);
// Burley's GTR1 (generalised Trowbridge-Reitz, gamma 1), Cycles' D_GTR1 for the clearcoat.
float gtr1_D(float cos_m, float alpha);
float fresnel_dielectric(float cos_i, float eta);
// Cycles' ensure_valid_reflection (kernel/closure/bsdf_util.h), applied by its closure nodes to
// their normal: tilts N towards Ng just enough that the mirror reflection of I stays above the
// surface (normal maps seen at grazing angles otherwise shade from below).
Vec3 ensure_valid_reflection(const Vec3& Ng, const Vec3& I, const Vec3& N);
// Cycles 3.4's Principled v1 Fresnel (interpolate_fresnel_color): f0 blended to 1 by the
// dielectric Fresnel of IOR eta at cos_i, renormalised to [0, 1]; f0 (cspec0) clamped to [0, 1].
// eta may be below 1 (the Principled glass seen from inside; total internal reflection gives 1).
Spectrum fresnel_principled(const Spectrum& f0, float eta, float cos_i);
// Cycles 3.4's bssrdf_setup_radius (closure/bssrdf.h): Burley and Random Walk (Fixed Radius)
// scale the radius by 1/(4 pi); Random Walk by sqrt(3 (1 - alpha')), alpha' the single-scattering
// albedo whose dipole reflectance (bssrdf_dipole_compute_Rd, Jensen's F_dr at IOR ior) is the
// surface albedo: bssrdf_alpha_prime inverts it by 12 bisections, as Cycles does.
float bssrdf_alpha_prime(float albedo, float ior);
Spectrum bssrdf_radius(const Spectrum& radius, const Spectrum& albedo, SubsurfaceMethod method, float ior);
// The IOR Cycles 3.4 derives from the Principled BSDF's Specular input: 2 / (1 - sqrt(0.08 s)) - 1
// (1.5 at the default 0.5); infinite from s = 12.5 on, where Cycles' own value is not finite.
float principled_specular_ior(float specular);

}  // namespace lt
