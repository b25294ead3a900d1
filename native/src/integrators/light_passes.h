// Cycles 3.4's light passes (kernel/film/light_passes.h, integrator/shade_surface.h): a path's
// contributions are filed by what its first scattering vertex did. At a surface the BSDF value
// towards the direction taken is split by closure kind (Bsdf::eval_kinds; Cycles'
// pass_diffuse_weight and pass_glossy_weight, transmission the rest), a medium vertex files
// everything under Volume. Light reaching the camera through one scattering vertex (next-event
// estimation there, or an emitter its sampled direction reaches) is Direct, the rest Indirect, and
// emitters seen directly (through transparent surfaces too) are Emission, the world Environment.
#pragma once

#include <cmath>

#include "core/film.h"
#include "shading/bsdf.h"

namespace lt {

struct FirstBounce {
  bool volume = false;
  Spectrum share[3] = {Spectrum(0.0f), Spectrum(0.0f), Spectrum(1.0f)};  // PassKind order

  // Shares of a non-delta BSDF value split by kind (kinds: Bsdf::eval_kinds), per channel;
  // transmission is what diffuse and glossy leave (as Cycles, which does not store it).
  void set_surface(const Spectrum* kinds) {
    const Spectrum sum = kinds[0] + kinds[1] + kinds[2];
    volume = false;
    for (int k = 0; k < 3; ++k) {  // (an overflowing sum files everything as transmission)
      const bool split = sum[k] != 0 && std::isfinite(sum[k]);
      share[0][k] = split ? kinds[0][k] / sum[k] : 0.0f;
      share[1][k] = split ? kinds[1][k] / sum[k] : 0.0f;
    }
    share[2] = Spectrum(1.0f) - share[0] - share[1];
  }
  void set_kind(PassKind kind) {  // a delta lobe sampled
    volume = false;
    for (int k = 0; k < 3; ++k) share[k] = Spectrum(k == int(kind) ? 1.0f : 0.0f);
  }
  void set_volume() { volume = true; }
};

// Files contribution c of a path with `bounces` scattering vertices between camera and light
// (0: an emitter seen directly; `environment`: the world's) into out's light parts.
// (light: kLightParts values, SampleValue::light).
inline void add_light_part(Spectrum* light, const Spectrum& c, int bounces, const FirstBounce& first,
                           bool environment) {
  if (bounces <= 0) {
    light[environment ? kEnvironment : kEmission] += c;
    return;
  }
  const int indirect = bounces == 1 ? 0 : 1;
  if (first.volume) {
    light[kVolumeDirect + indirect] += c;
    return;
  }
  light[kDiffuseDirect + indirect] += c * first.share[0];
  light[kGlossyDirect + indirect] += c * first.share[1];
  light[kTransmissionDirect + indirect] += c * first.share[2];
}

// The first hit's closure colours (Bsdf::kind_colors) times the throughput that reached it.
inline void add_light_colors(SampleValue* out, const Bsdf& bsdf, const Vec3& wo, const Spectrum& beta) {
  Spectrum c[3];
  bsdf.kind_colors(wo, c);
  out->light[kDiffuseColor] += beta * c[0];
  out->light[kGlossyColor] += beta * c[1];
  out->light[kTransmissionColor] += beta * c[2];
}

}  // namespace lt
