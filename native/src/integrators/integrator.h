// What every integrator shares: its settings and the per-camera-sample entry point.
#pragma once

#include <cstdint>
#include <vector>

#include "core/film.h"
#include "core/sampling.h"
#include "media/medium.h"
#include "scene/scene.h"

namespace lt {

enum class MisHeuristic { Power = 0, Balance = 1, Uniform = 2 };

struct IntegratorSettings {
  int max_bounces = 12;
  // Bidirectional: vertex limits of the two subpaths (the camera's own vertex and the light's
  // vertex count) and the MIS heuristic.
  int max_camera_length = 64, max_light_length = 64;
  MisHeuristic mis = MisHeuristic::Power;
  // Bidirectional strategy view: weighted contributions of every (s, t) with path depth
  // s + t - 2 < strategy_depth, laid out as a grid (0: off).
  int strategy_depth = 0;
  int diffuse_bounces = 4, glossy_bounces = 4, transmission_bounces = 12, transparent_bounces = 8;
  float clamp_direct = 0, clamp_indirect = 0;  // 0: off
  bool transparent_background = false;
  // Volumes: Cycles' volume bounce limit (0: single scattering), the estimator for heterogeneous
  // media and the ray-marching step in world units (<= 0: each medium's own, Medium::march_step).
  int volume_bounces = 0;
  VolumeEstimator volume_estimator = VolumeEstimator::Tracking;
  float volume_step = 0;
};

struct SampleStats {
  uint64_t rays = 0;
};

// A camera ray with where it crosses the film (full-frame pixels, y up) and the pixel it
// estimates (the filter can place `film` in a neighbour).
struct CameraSample {
  Ray ray;
  Vec2 film;
  Vec2 pixel_center;
};

// A light-tracing contribution to a pixel of the render region (BDPT's t = 1), and its cell in
// the strategy view (-1 when the view is off).
struct Splat {
  uint32_t pixel;
  Spectrum value;
  int32_t strategy = -1;
};

// The strategy view's grid: row = path depth d = s + t - 2, column = s (0 .. depth + 2 - 1).
inline int strategy_columns(int depth) { return depth + 2; }
inline int strategy_cell(int s, int t, int depth) {
  int d = s + t - 2;
  return d >= 0 && d < depth && s < strategy_columns(depth) ? d * strategy_columns(depth) + s : -1;
}

struct RenderContext {
  const Scene& scene;
  const Camera& camera;
  const FilterSampler& filter;
  IntegratorSettings settings;
  int x0, y0, width, height;  // render region in full-frame pixels
};

// Bidirectional path tracing: one camera subpath and one light subpath per sample, every
// connection strategy weighted by MIS; t = 1 contributions go to `splats`.
// `strategies`, when not null, receives this sample's weighted contribution per strategy cell
// (strategy_depth * strategy_columns entries, zeroed by the caller).
SampleValue trace_bdpt(const RenderContext& ctx, const CameraSample& cs, Sampler& sampler, SampleStats& stats,
                       std::vector<Splat>& splats, Spectrum* strategies = nullptr);

// For tests: runs one BDPT sample and, for every full path it connects (strategies s >= 1,
// t >= 2), re-splits that path into every other strategy (s', t') that could have sampled it and
// returns the sums of their MIS weights, computed by the integrator's own weight code (each sum
// must be 1; a sum is NaN if any single weight falls outside [0, 1]).
std::vector<float> bdpt_mis_weight_sums(const RenderContext& ctx, const CameraSample& cs, Sampler& sampler);

// Radiance along a camera ray, plus the first-hit data passes. One call is one sample.
SampleValue trace_path(const Scene& scene, const IntegratorSettings& settings, const Ray& camera_ray,
                       Sampler& sampler, SampleStats& stats);

// Volumetric path tracing (integrators/path.cpp, the same code with media): a volume stack,
// free-flight sampling, NEE through media and invisible boundaries. Only for scenes with media.
SampleValue trace_volpath(const Scene& scene, const IntegratorSettings& settings, const Ray& camera_ray,
                          Sampler& sampler, SampleStats& stats);

// Volume debug view (integrators/volume_debug.cpp): for the camera ray of a panel pixel, panel
// 0 = transmittance by ray marching, 1 = by ratio tracking, 2 = sampled distance by ray marching,
// 3 = by delta tracking (distance from the ray origin in world units, 0 without a collision).
SampleValue trace_volume_debug(const Scene& scene, const IntegratorSettings& settings, const Ray& camera_ray,
                               int panel, Sampler& sampler, SampleStats& stats);

}  // namespace lt
