// What every integrator shares: its settings and the per-camera-sample entry point.
#pragma once

#include <cstdint>

#include "core/film.h"
#include "core/sampling.h"
#include "scene/scene.h"

namespace lt {

struct IntegratorSettings {
  int max_bounces = 12;
  int diffuse_bounces = 4, glossy_bounces = 4, transmission_bounces = 12, transparent_bounces = 8;
  float clamp_direct = 0, clamp_indirect = 0;  // 0: off
  bool transparent_background = false;
};

struct SampleStats {
  uint64_t rays = 0;
};

// Radiance along a camera ray, plus the first-hit data passes. One call is one sample.
SampleValue trace_path(const Scene& scene, const IntegratorSettings& settings, const Ray& camera_ray,
                       Sampler& sampler, SampleStats& stats);

}  // namespace lt
