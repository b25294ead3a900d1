// Test hooks of bidirectional path tracing (implemented in bdpt_test_hooks.cpp); not for the renderer.
#pragma once

#include <vector>

#include "integrators/integrator.h"

namespace lt {

// Runs one BDPT sample and, for every full path it connects (strategies s >= 1, t >= 2), re-splits
// that path into every other strategy (s', t') that could have sampled it and returns the sums of
// their MIS weights, computed by the integrator's own weight code (each sum must be 1; a sum is NaN
// if any single weight falls outside [0, 1]).
std::vector<float> bdpt_mis_weight_sums(const RenderContext& ctx, const CameraSample& cs, Sampler& sampler);

}  // namespace lt
