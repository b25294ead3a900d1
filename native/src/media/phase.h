// Henyey-Greenstein phase function (Henyey & Greenstein 1941) with exact inversion sampling
// (pbrt 3, section 15.2.3; Mitsuba 3's hg.cpp).
//
// Direction convention (pbrt's and Mitsuba's; the same as the BSDFs' wo/wi): both directions point
// AWAY from the scattering point. wo points towards where the light goes (the previous vertex of a
// camera path: wo = -ray.d of the ray that reached the point); wi points towards where the light
// comes from (the next vertex of a camera path, or the light in NEE). Light travelling straight on
// has wi == -wo. With cos = dot(wo, wi),
//     p(wo, wi) = (1 - g^2) / (4 pi (1 + g^2 + 2 g cos)^(3/2)),
// so g > 0 favours wi near -wo: forward scattering, as in Cycles; g = 0 is isotropic (1 / 4 pi) and
// g < 0 scatters back. p is symmetric in (wo, wi) and integrates to 1 over wi for every wo.
// Sampling is exact, so the returned pdf equals the value (the caller's weight is 1).
#pragma once

#include "core/math.h"
#include "core/sampling.h"

namespace lt {

struct PhaseHG {
  float g = 0;  // in (-1, 1); values outside are clamped to +-kMaxG

  static constexpr float kMaxG = 0.9999f;

  float eval(const Vec3& wo, const Vec3& wi) const;
  // Samples wi for a given wo; *pdf == eval(wo, *wi) (solid angle). Returns false only if the
  // inputs are not finite.
  bool sample(const Vec3& wo, Vec2 u, Vec3* wi, float* pdf) const;
  float pdf(const Vec3& wo, const Vec3& wi) const { return eval(wo, wi); }
};

// The HG density as a function of cos = dot(wo, wi) (both directions away from the point).
float hg_phase(float cos_theta, float g);

// A medium's phase function: one HG lobe (the common case, evaluated without a loop) or a mixture
// of up to kMaxLobes HG lobes, sum_k w_k p_HG(g_k) with weights w_k >= 0 summing to 1. A volume
// shader that adds or mixes several scattering nodes (Add / Mix Shader) gives one lobe per
// distinct anisotropy, weighted by that node's scattering coefficient averaged over RGB (Cycles
// weights its phase closures by sample_weight = average(sigma_s) in the same way; per-channel
// sigma_s with different colours per lobe is therefore approximated exactly as Cycles does).
// Sampling picks a lobe by weight (reusing u.x), samples it exactly, and returns the pdf of the
// whole mixture at the sampled direction, so *pdf == eval(wo, *wi) and the weight is exactly 1.
struct Phase {
  static constexpr int kMaxLobes = 8;

  int count = 1;
  float g[kMaxLobes] = {0};
  float weight[kMaxLobes] = {1};

  static Phase hg(float g);
  // Lobes with equal g are merged; zero weights are dropped. Throws InvalidArgument for more than
  // kMaxLobes distinct lobes, or weights that are negative, non-finite or all zero.
  static Phase mixture(const float* g, const float* weight, int n);

  bool is_single() const { return count == 1; }
  float eval(const Vec3& wo, const Vec3& wi) const {
    if (count == 1) return hg_phase(dot(wo, wi), g[0]);
    return eval_mixture(dot(wo, wi));
  }
  bool sample(const Vec3& wo, Vec2 u, Vec3* wi, float* pdf) const;
  float pdf(const Vec3& wo, const Vec3& wi) const { return eval(wo, wi); }

 private:
  float eval_mixture(float cos_theta) const;
};

}  // namespace lt
