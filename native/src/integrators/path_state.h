// What the integrators track along a path the way Cycles does: ray kinds (Cycles' ray visibility
// flags, lt_visibility), bounce kinds, counts and their limits, the sample clamp and Russian
// roulette.
#pragma once

#include <cstdint>

#include "core/sampling.h"
#include "integrators/integrator.h"
#include "shading/bsdf.h"
#include "shading/program.h"

namespace lt {

constexpr unsigned kVisCamera = 1, kVisDiffuse = 2, kVisGlossy = 4, kVisTransmission = 8, kVisShadow = 16;
constexpr unsigned kVisAll = 31;

// The lobes (bits 1 << PassKind) a light hidden from some kinds of ray leaves out of its light
// samples, as Cycles' SHADER_EXCLUDE_DIFFUSE / _GLOSSY / _TRANSMIT (surface_shader.h).
inline unsigned excluded_kinds(unsigned light_visibility) {
  return (light_visibility & kVisDiffuse ? 0u : 1u << int(PassKind::Diffuse)) |
         (light_visibility & kVisGlossy ? 0u : 1u << int(PassKind::Glossy)) |
         (light_visibility & kVisTransmission ? 0u : 1u << int(PassKind::Transmission));
}

// The visibility flag of a ray leaving a lobe of these flags.
inline unsigned visibility_of(uint32_t lobe) {
  if (lobe & kLobeTransmission) return kVisTransmission;
  if (lobe & kLobeDiffuse) return kVisDiffuse;
  return kVisGlossy;
}

// Cycles' sample clamp: scale a contribution so that its largest channel is at most `limit` in
// magnitude (a negative light's contribution is clamped as a positive one).
inline Spectrum clamp_contribution(const Spectrum& c, float limit) {
  if (limit <= 0) return c;
  float m = max_abs_component(c);
  return m > limit ? c * (limit / m) : c;
}

// Bounce kinds, as Cycles limits them: a scattering counts as the kind of the lobe (closure) that
// sampled it. Volume and Mixed are BDPT's (a vertex whose BSDF has lobes of several kinds, which
// the path tracer counts as one or another by the lobe it picks; bdpt.cpp).
enum class BounceKind : uint8_t { None = 0, Diffuse = 1, Glossy = 2, Transmission = 3, Volume = 4, Mixed = 5 };

// A pass-through without refraction (a Transparent lobe, or glass of IOR 1 at roughness 0): Cycles
// counts it as transparent, not as a bounce, and the ray keeps its kind.
inline bool is_transparent(uint32_t lobe_flags, float eta) {
  return lobe_flags == (kLobeSpecular | kLobeTransmission) && eta == 1;
}
// The kind of a scattering by a lobe of these flags (BsdfSample::flags) across relative IOR eta.
inline BounceKind bounce_kind(uint32_t lobe_flags, float eta) {
  if (is_transparent(lobe_flags, eta)) return BounceKind::None;
  // Cycles counts any transmission as a transmission bounce, Translucent's diffuse one too.
  if (lobe_flags & kLobeTransmission) return BounceKind::Transmission;
  if (lobe_flags & kLobeDiffuse) return BounceKind::Diffuse;
  return BounceKind::Glossy;
}
// The same for lobe l reflecting or transmitting (a Transparent lobe only transmits).
inline BounceKind bounce_kind(const Lobe& l, bool transmit) {
  if (l.type == LobeType::Transparent) transmit = true;
  const uint32_t flags = lobe_flags(l) & ~(transmit ? kLobeReflection : kLobeTransmission);
  return bounce_kind(flags, transmit && lobe_is_glass(l.type) ? l.eta : 1.0f);
}

// Cycles' bounce bookkeeping, for the path tracer and BDPT alike: transparent pass-throughs are
// counted apart from the bounces, and each kind against its own limit.
struct Bounces {
  int total = 0;
  int n[5] = {0, 0, 0, 0, 0};  // by BounceKind, None to Volume (None: transparent pass-throughs)
  int of(BounceKind k) const { return k == BounceKind::Mixed ? 0 : n[int(k)]; }
  bool from_camera() const { return total == 0 && of(BounceKind::None) == 0; }  // still on the camera ray
  // Counts a scattering of kind k. Mixed counts nothing: its kind is that of the lobe the path
  // tracer would sample (BDPT's kind_limit_factor weighs it).
  void add(BounceKind k) {
    if (k == BounceKind::Mixed) return;
    ++n[int(k)];
    if (k != BounceKind::None) ++total;
  }
  // Counts the scattering a BSDF sample made; a bounce changes the next ray's kind.
  void count(const BsdfSample& bs, unsigned* visibility) {
    const BounceKind k = bounce_kind(bs.flags, bs.eta);
    add(k);
    if (k != BounceKind::None) *visibility = visibility_of(bs.flags);
  }
  // Cycles' limit on scatterings of kind k.
  static int limit(const IntegratorSettings& s, BounceKind k) {
    switch (k) {
      case BounceKind::None:
        return s.transparent_bounces;
      case BounceKind::Diffuse:
        return s.diffuse_bounces;
      case BounceKind::Glossy:
        return s.glossy_bounces;
      case BounceKind::Transmission:
        return s.transmission_bounces;
      case BounceKind::Volume:
        return s.volume_bounces;
      case BounceKind::Mixed:
        break;
    }
    return INT32_MAX;
  }
  // Past the limit of a kind of bounce (diffuse, glossy, transmission, volume).
  bool kind_exceeded(const IntegratorSettings& s) const {
    for (int k = int(BounceKind::Diffuse); k <= int(BounceKind::Volume); ++k)
      if (n[k] > limit(s, BounceKind(k))) return true;
    return false;
  }
  // Past any of Cycles' limits: a path tracer's path ends.
  bool exceeded(const IntegratorSettings& s) const {
    return total > s.max_bounces || kind_exceeded(s) || of(BounceKind::None) > s.transparent_bounces;
  }
};

// What the Light Path node reports for a ray of kind `visibility` after bounces b.
inline void describe_ray(const Bounces& b, unsigned visibility, ShadingContext* c) {
  c->camera_ray = b.from_camera();
  c->diffuse_ray = !c->camera_ray && (visibility & kVisDiffuse);
  c->glossy_ray = !c->camera_ray && (visibility & kVisGlossy);
  c->transmission_ray = !c->camera_ray && (visibility & kVisTransmission);
  c->reflection_ray = c->diffuse_ray || c->glossy_ray;
  c->ray_depth = b.total;
  c->diffuse_depth = b.of(BounceKind::Diffuse);
  c->glossy_depth = b.of(BounceKind::Glossy);
  c->transparent_depth = b.of(BounceKind::None);
  c->transmission_depth = b.of(BounceKind::Transmission);
}

// Shadow catchers (integrators/path.cpp, bdpt.cpp): the world a camera ray (bounces b, kind
// `visibility`) sees along `dir`, kept for the approximate matte over an opaque film (Cycles'
// background pass); zero when that matte does not use it.
inline Spectrum catcher_background(const Scene& scene, const IntegratorSettings& s, const Vec3& dir, const Bounces& b,
                                   unsigned visibility) {
  if (!s.shadow_catcher || !s.shadow_catcher_approximate || s.transparent_background) return Spectrum(0.0f);
  if (scene.lights.world_light() < 0 || !scene.world.camera_visible) return Spectrum(0.0f);
  return scene.world.escaped_radiance(dir, [&](ShadingContext* wc) { describe_ray(b, visibility, wc); });
}
// Whether light li shines in the scene a catcher-only path sees: lamps, the world and the
// emission of catchers, not that of other objects (Cycles' light_distribution_sample).
inline bool lights_catchers(const Scene& scene, int li) {
  const Light& l = scene.lights.light(li);
  return l.type != LightType::Triangle || scene.geometry.instance(l.instance).shadow_catcher;
}

// Cycles' integrate_surface_holdout (integrator/shade_surface.h): at a surface that a camera path
// reaches through transparent passes only (Cycles' PATH_RAY_TRANSPARENT_BACKGROUND; with Film >
// Transparent or not), the holdout weight times the throughput becomes transparency of the film
// (alpha = 1 - transparency; the RGB gets nothing for it). The weight is the Holdout closures'
// sum, or on a holdout object 1 - its transparency, its other closures and its emission dropped.
// Elsewhere a Holdout closure is nothing (black, opaque) and a holdout object renders as usual.
// Returns false where the weight is 1: the path ends there.
inline bool hold_out(bool object, Bsdf* bsdf, Spectrum* emitted, const Spectrum& beta, float* transparent) {
  Spectrum w = bsdf->holdout();
  if (object) {
    w = Spectrum(1.0f) - bsdf->transparency();
    bsdf->keep_transparent();
    *emitted = Spectrum(0.0f);
  }
  if (is_black(w)) return true;
  *transparent += average(w * beta);
  return !(w[0] == 1 && w[1] == 1 && w[2] == 1);
}

// Cycles' PATH_RAY_SINGLE_PASS_DONE (film/data_passes.h): a camera path writes its AOVs (and Cycles
// its data passes) at each surface it reaches through transparent passes until one that is not
// transparent or whose alpha (1 - transparency, averaged) reaches the threshold (0: any surface).
inline bool single_pass_done(bool may_be_transparent, const Bsdf& bsdf, float threshold) {
  return !may_be_transparent || threshold == 0 || 1 - average(bsdf.transparency()) >= threshold;
}
// Points a camera path's shading context at the sample's AOVs where Cycles writes them.
inline void write_aovs_at(ShadingContext* ctx, float* aovs, const IntegratorSettings& s) {
  ctx->aovs = aovs;
  ctx->aov_count = aovs ? s.aovs : 0;
}

// Russian roulette once the path has had a chance to gather light (unbiased: divide by q), on the
// throughput relative to the path's start (`start`: the largest component of its initial beta),
// so a light subpath, whose beta carries the emitted power, is ended by the albedos it meets as a
// camera path is, whatever the light's units (and sign: a negative light's beta is negative).
// Survival q = min(1, sqrt(|beta| / start)), Cycles 3.4's rule (path_state.h,
// path_state_continuation_probability: the square root ends paths later than q = |beta| would, and
// divides survivors by less: on a sphere under a white world that cut the error per sample by
// 1.6x for 1.1x the cost, bench/README.md). A survivor's relative throughput sqrt(|beta| / start)
// stays at or below its start, so no path is amplified past it; one at or above its start (a
// mirror's 1) runs on unchanged to the bounce limit. A cap below 1 would multiply such a path by
// 1/cap at every bounce: 256 mirror bounces at 0.95 weigh 5e5 (heavy-tailed, visible as fireflies
// and a wrong-looking mean). Returns false when the path ends.
inline float survival_probability(const Spectrum& beta, float start = 1.0f) {
  return std::min(1.0f, std::sqrt(max_abs_component(beta) / start));
}
// The roulette starts at bounce `first`: the path tracers play it from the vertex reached after
// kPathRouletteBounce bounces (relMSE x time 3-10 % lower than after 3 on cornell_area,
// world_spheres and smoke_box, bench/README.md), BDPT's subpaths after kBdptRouletteBounce.
constexpr int kPathRouletteBounce = 4, kBdptRouletteBounce = 3;
inline bool russian_roulette(int bounce, int first, Spectrum* beta, Sampler& sampler, float start = 1.0f) {
  if (bounce < first) return true;
  const float u = sampler.next_1d();  // drawn either way: one dimension per bounce
  const float q = survival_probability(*beta, start);
  if (q >= 1) return true;
  if (u >= q) return false;
  *beta /= q;
  return true;
}

}  // namespace lt
