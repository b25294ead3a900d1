// Blender's volume shader nodes as medium coefficients, with Cycles' formulas (Cycles' svm_closure.h;
// DESIGN.md, Cycles conventions -> Volumes). The one place these conversions live.
#pragma once

#include "core/math.h"

namespace lt {

enum class VolumeNode { Principled = 0, Scatter = 1, Absorption = 2 };

struct VolumeCoefficients {
  Spectrum sigma_a{0.0f}, sigma_s{0.0f};  // per world unit (per unit grid density for VDB volumes)
  float g = 0;
};

// Principled Volume: sigma_s = d colour, sigma_t = d (colour + (1 - colour)(1 - sqrt(absorption colour)));
// Volume Scatter: sigma_s = d colour; Volume Absorption: sigma_a = d (1 - colour). Colours are
// clamped to [0, 1] as Cycles' closures do, density to >= 0.
inline VolumeCoefficients volume_coefficients(VolumeNode node, const Spectrum& color, float density,
                                              const Spectrum& absorption_color, float anisotropy) {
  VolumeCoefficients c;
  const float d = std::max(0.0f, density);
  Spectrum col = vmin(Spectrum(1.0f), vmax(Spectrum(0.0f), color));
  switch (node) {
    case VolumeNode::Principled: {
      Spectrum a = vmax(Spectrum(0.0f), absorption_color);
      for (int k = 0; k < 3; ++k) {
        c.sigma_s[k] = d * col[k];
        c.sigma_a[k] = d * (1 - col[k]) * std::max(0.0f, 1 - std::sqrt(a[k]));
      }
      break;
    }
    case VolumeNode::Scatter: c.sigma_s = col * d; break;
    case VolumeNode::Absorption: c.sigma_a = (Spectrum(1.0f) - col) * d; break;
  }
  c.g = clamp(anisotropy, -0.9999f, 0.9999f);
  return c;
}

}  // namespace lt
