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
};

enum class LobeType : uint8_t {
  Diffuse,            // Lambert (roughness 0) or Oren-Nayar as Cycles' Diffuse BSDF
  GlossyGGX,          // GGX reflection, colour as constant reflectance (Cycles' Glossy BSDF, no Fresnel)
  Dielectric,         // Fresnel-weighted GGX reflection + refraction (Cycles' Glass BSDF); delta at alpha 0
  SpecularGGX,        // GGX reflection with Cycles' Principled v1 Fresnel from f0 to 1 (its specular layer)
  Transparent,        // straight pass-through (delta transmission)
  PrincipledDiffuse,  // Burley's diffuse with retro-reflection (Cycles' Principled diffuse closure)
};

struct Lobe {
  LobeType type = LobeType::Diffuse;
  Spectrum weight{1.0f};  // colour x mix weight
  float roughness = 0;    // Diffuse: Oren-Nayar sigma; PrincipledDiffuse: the Principled roughness;
                          // microfacet: unused (see alpha)
  float alpha = 0;        // GGX alpha = roughness^2; below kSmoothAlpha the lobe is delta
  float eta = 1.5f;       // Dielectric: relative IOR across the surface from wo's side;
                          // SpecularGGX: the IOR whose dielectric Fresnel shapes the blend to 1
  Spectrum f0{0.04f};     // SpecularGGX: reflectance at normal incidence (Cycles' cspec0)
};

struct BsdfSample {
  Vec3 wi;
  Spectrum f;          // BSDF value (cosine excluded); for delta lobes f*|wi.z|/pdf is the weight
  float pdf = 0;       // solid-angle pdf of the whole mixture, or the discrete probability if delta
  uint32_t flags = 0;  // the sampled lobe's LobeFlags
  float eta = 1;       // relative IOR crossed (1 for reflection)
};

constexpr int kMaxLobes = 8;
constexpr float kSmoothAlpha = 1e-4f;

class Bsdf {
 public:
  void clear() {
    count_ = 0;
    overflowed_ = false;
    bumped_ = false;
  }
  // The interpolated normal (local frame) when a Normal input bent the shading normal: Cycles 3.4
  // then scales its diffuse closures by bump_shadowing_term (kernel/closure/bsdf.h), which darkens
  // light grazing the smooth surface. light_is_wo: light transport (BDPT's light subpaths), where
  // the light arrives along wo rather than wi.
  void set_bump(const Vec3& smooth_local, bool light_is_wo) {
    bumped_ = true;
    smooth_ = smooth_local;
    light_is_wo_ = light_is_wo;
  }
  // Adds a lobe; lobes whose weight is zero are dropped, lobes past kMaxLobes merge into nothing
  // and are reported through overflowed().
  void add(const Lobe& lobe);
  int count() const { return count_; }
  const Lobe& lobe(int i) const { return lobes_[i]; }
  bool overflowed() const { return overflowed_; }

  // Sum of the non-delta lobes' f, and (pdf not null) the mixture pdf of sampling wi with sample().
  Spectrum eval(const Vec3& wo, const Vec3& wi, float* pdf) const;
  // The mixture pdf alone: eval()'s *pdf to the last bit, without evaluating f.
  float pdf(const Vec3& wo, const Vec3& wi) const;
  // Picks a lobe with probability proportional to its weight's estimate (the weight's average,
  // times the Fresnel at wo for SpecularGGX; see bsdf.cpp), samples it, then (for non-delta
  // lobes) evaluates all non-delta lobes for f and the mixture pdf. For a delta lobe, f and pdf
  // are that lobe's, the pdf times its selection probability.
  bool sample(const Vec3& wo, float u_lobe, Vec2 u, BsdfSample* out) const;
  // Directional albedo estimate of the lobes' weights (for the Albedo pass and Russian roulette).
  Spectrum albedo() const;
  uint32_t flags() const;  // union of lobe flags
  bool has_non_delta() const;
  // The probabilities with which sample() picks each lobe for this wo; false if none can be.
  bool selection(const Vec3& wo, float* p) const;
  // Each lobe's part of pdf(wo, wi): its selection probability times its own pdf (0 for delta
  // lobes). Given that sample() produced wi, lobe k picked it with probability part[k] / pdf.
  // Returns their sum, pdf(wo, wi).
  float lobe_pdfs(const Vec3& wo, const Vec3& wi, float* part) const;

 private:
  Lobe lobes_[kMaxLobes];
  int count_ = 0;
  bool overflowed_ = false;
  bool bumped_ = false, light_is_wo_ = false;
  Vec3 smooth_{0.0f, 0.0f, 1.0f};
  float bump_term(const Lobe& lobe, const Vec3& wo, const Vec3& wi) const;
};

// ---- single-lobe routines, exposed for the chi-square tests ----------------------------------
Spectrum lobe_eval(const Lobe& lobe, const Vec3& wo, const Vec3& wi);
float lobe_pdf(const Lobe& lobe, const Vec3& wo, const Vec3& wi);
bool lobe_sample(const Lobe& lobe, const Vec3& wo, Vec2 u, float u_extra, BsdfSample* out);
uint32_t lobe_flags(const Lobe& lobe);

// GGX (Trowbridge-Reitz) microfacet distribution with visible-normal sampling (Heitz 2018).
float ggx_D(const Vec3& m, float alpha);
float ggx_G1(const Vec3& w, float alpha);
Vec3 ggx_sample_visible_normal(const Vec3& wo, float alpha, Vec2 u);
float fresnel_dielectric(float cos_i, float eta);
// Cycles 3.4's Principled v1 specular Fresnel (interpolate_fresnel_color): f0 blended to 1 by the
// dielectric Fresnel of IOR eta at cos_i, renormalised to [0, 1]; f0 (cspec0) clamped to [0, 1].
Spectrum fresnel_principled(const Spectrum& f0, float eta, float cos_i);
// The IOR Cycles 3.4 derives from the Principled BSDF's Specular input: 2 / (1 - sqrt(0.08 s)) - 1
// (1.5 at the default 0.5); infinite from s = 12.5 on, where Cycles' own value is not finite.
float principled_specular_ior(float specular);

}  // namespace lt
