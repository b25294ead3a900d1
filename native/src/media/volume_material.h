// Blender's volume shader nodes as medium coefficients, with Cycles' formulas (Cycles' svm_closure.h;
// DESIGN.md, Cycles conventions -> Volumes). The one place these conversions live.
#pragma once

#include "core/math.h"
#include "media/phase.h"

namespace lt {

enum class VolumeNode { Principled = 0, Scatter = 1, Absorption = 2, Emission = 3 };

struct VolumeCoefficients {
  Spectrum sigma_a{0.0f}, sigma_s{0.0f};  // per world unit (per unit grid density for VDB volumes)
  float g = 0;
  Spectrum emission{0.0f};  // emitted radiance per unit length (not scaled by density, as Cycles)
};

// Blackbody colour of temperature `kelvin` in linear Rec.709, as Cycles 3.4.1 computes it (unit
// luminance; constant below 800 K and above 12000 K): a piecewise fit to Cycles' own output
// (volume_material.cpp says how it was measured). Unclamped as Cycles' Principled Volume uses it
// (negative green and blue below ~1900 K); blackbody_rec709 clamps to 0 as its Blackbody node.
Spectrum blackbody_rec709_unclamped(float kelvin);
Spectrum blackbody_rec709(float kelvin);

// Principled Volume's emission per unit length (Cycles' svm_node_principled_volume): strength x
// colour, plus blackbody: tint x (sigma_SB 1e-6 / pi) x mix(1, T^4, intensity) x blackbody(T)
// when intensity > 0 (sigma_SB the Stefan-Boltzmann constant). Colours and tint clamped to >= 0;
// the blackbody colour is not (Cycles' is not: below ~1900 K the emission has negative channels).
Spectrum principled_volume_emission(float strength, const Spectrum& color, float blackbody_intensity,
                                    const Spectrum& blackbody_tint, float temperature);

// A volume shader made of several components (Add Shader: their sum; Mix Shader: the add-on
// scales each side's density / strength by its factor), as Cycles sums closures: absorption,
// scattering and emission add; the scattering components keep their own phase function, mixed by
// their scattering coefficients averaged over RGB (Phase::mixture; Cycles' sample_weight).
struct VolumeMix {
  Spectrum sigma_a{0.0f}, sigma_s{0.0f}, emission{0.0f};
  Phase phase;
};
VolumeMix sum_volume_components(const VolumeCoefficients* components, int count);

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
    case VolumeNode::Scatter:
      c.sigma_s = col * d;
      break;
    case VolumeNode::Absorption:
      c.sigma_a = (Spectrum(1.0f) - col) * d;
      break;
    case VolumeNode::Emission:
      break;  // emission only (principled_volume_emission's first term)
  }
  c.g = clamp(anisotropy, -0.9999f, 0.9999f);
  return c;
}

}  // namespace lt
