// Ray kinds as Cycles' ray visibility flags (lt_visibility), shared by every integrator, and
// Cycles' sample clamp.
#pragma once

#include <cstdint>

#include "scene/bsdf.h"

namespace lt {

constexpr unsigned kVisCamera = 1, kVisDiffuse = 2, kVisGlossy = 4, kVisTransmission = 8, kVisShadow = 16;
constexpr unsigned kVisAll = 31;

// The visibility flag of a ray leaving a lobe of these flags.
inline unsigned visibility_of(uint32_t lobe) {
  if (lobe & kLobeTransmission) return kVisTransmission;
  if (lobe & kLobeDiffuse) return kVisDiffuse;
  return kVisGlossy;
}

// Cycles' sample clamp: scale a contribution so that its largest channel is at most `limit`.
inline Spectrum clamp_contribution(const Spectrum& c, float limit) {
  if (limit <= 0) return c;
  float m = max_component(c);
  return m > limit ? c * (limit / m) : c;
}

}  // namespace lt
