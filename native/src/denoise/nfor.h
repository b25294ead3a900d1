// A feature-guided denoiser after NFOR (Bitterli et al. 2016, "Nonlinearly Weighted First-order
// Regression for Denoising Monte Carlo Renderings"), simplified as docs/denoise.md says: each half
// image of the film is reconstructed by first-order regressions on the denoising features
// (camera-space normal, albedo, distance) in a window around each pixel, each fit evaluated over
// its whole window and the overlapping fits averaged (NFOR's collaborative reconstruction), weighted by NL-means
// weights computed on the *other* half (cross-filtering: the weights are independent of the noise
// they average), and the two reconstructions are averaged. The NL-means distance is normalised by
// the guide half's own variance estimate (from its samples alone: a variance from the halves'
// difference would hold the half being weighed and brightened the mean), so the filter's strength
// follows the image's noise, not a per-scene setting.
#pragma once

#include <vector>

#include "core/film.h"

namespace lt {

struct DenoiseParams {
  // Search window radius: (2 window + 1)^2 neighbours (NFOR: 9). With the collaborative
  // reconstruction (each fit evaluated over its whole window) 3 measured better than the per-pixel
  // fit with 5 on the Cornell box, at 2.5x less work (bench/denoise.cpp, docs/denoise.md).
  int window = 3;
  int patch = 3;  // NL-means patch radius (NFOR: 3)
  // NL-means bandwidth in units of the noise (Rousselle et al. 2012, eq. 6; NFOR's k = 0.5 and
  // 1.0 candidates, of which this is the smaller: detail first).
  float k = 0.5f;
};

// The denoised RGB (on the calling TBB arena's threads), width*height*3 floats (rows as the film's), non-negative.
// Deterministic for any thread count (each pixel's sums are added in a fixed order: tiles in four rounds by parity, a
// tile's additions in a fixed order); finite for any input: pixels that are not valid or hold a non-finite value take
// no part as neighbours and are reconstructed from their valid neighbours (0 when they have none).
std::vector<float> denoise(const HalfImages& in, const DenoiseParams& params = DenoiseParams());

}  // namespace lt
