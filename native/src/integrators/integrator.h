// What every integrator shares: its settings and one interface the render job drives (trace one
// camera sample, with optional hooks around a pass; pbrt-v4's ImageTileIntegrator, Mitsuba's
// SamplingIntegrator), and the factory that picks an integrator from the settings.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/film.h"
#include "core/sampling.h"
#include "integrators/light_passes.h"
#include "media/medium.h"
#include "media/volume_stack.h"
#include "scene/scene.h"

namespace lt {

// VolumeDebug: the 2x2 estimator view of integrators/volume_debug.cpp (each panel a half-size view).
enum class IntegratorType { Path = 0, Bidirectional = 1, VolPath = 2, VolumeDebug = 3, Count = 4 };

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
  // Passes the film keeps that integrators fill: Cycles' light passes (SampleValue::light) and the
  // data passes of the first hit (position, UV, mist, indices, Cryptomatte ids); Mist as Cycles'
  // World > Mist Pass.
  bool light_passes = false, data_passes = false;
  float mist_start = 5, mist_depth = 25, mist_falloff = 2;
  int lightgroups = 0;  // light group passes the film keeps (SampleValue::lightgroups)
  int aovs = 0;         // shader AOVs the film keeps (SampleValue::aovs)
  // Cycles' pass alpha threshold: the camera path writes AOVs at the surfaces it reaches through
  // transparent passes up to the first whose alpha reaches it (single_pass_done).
  float pass_alpha_threshold = 0.5f;
  // Cycles' Ambient Occlusion pass and its rays' length (World > Light Settings > AO Distance),
  // and the Vector pass (the scene's motion steps are the neighbouring frames: render.h).
  bool ao_pass = false, vector_pass = false;
  float ao_distance = 10;
  // Shadow catchers: split camera paths at them (Cycles' catcher split; set when the scene has one
  // and the integrator splits: path and volumetric path) and Cycles' use_approximate_shadow_catcher.
  bool shadow_catcher = false, shadow_catcher_approximate = true;
};

// The Mist pass's value for a sample whose camera path scatters first at p with throughput beta
// (Cycles' film_write_data_passes: (1 - mist) x average throughput, mist from the camera distance).
float mist_coverage(const Camera& camera, const IntegratorSettings& s, const Vec3& p, const Spectrum& beta);
// The data passes of a first hit: position, UV, indices, mist, Cryptomatte ids and weight.
void write_data_passes(const Scene& scene, const Camera& camera, const IntegratorSettings& s, const SurfacePoint& sp,
                       const Spectrum& beta, SampleValue* out);

struct SampleStats;
// Cycles' AO pass (integrate_surface_ao): from sp, one cosine-distributed ray about n (the
// shading normal facing the path's side `side`, the geometric normal there) up to ao_distance,
// its transmittance through transparent surfaces and the media of `stack` (1: unoccluded).
// Draws from a copy of the sampler, so the path's own numbers (and Combined) stay as they are.
Spectrum ambient_occlusion(const Scene& scene, const IntegratorSettings& s, const SurfacePoint& sp, const Vec3& n,
                           const Vec3& side, const VolumeStack* stack, Sampler sampler, SampleStats& stats);
// Cycles' Vector pass (primitive_motion_vector): the film motion of the surface point sp seen at
// the centre step, (previous - now, now - next) in pixels; false on a camera whose projection it
// does not handle (panoramas), leaving *out as it is.
bool motion_vector(const Scene& scene, const Camera& camera, const SurfacePoint& sp, float out[4]);

struct SampleStats {
  uint64_t rays = 0;
};

// A camera ray with where it crosses the film (full-frame pixels, y up) and the pixel it
// estimates (the filter can place `film` in a neighbour).
struct CameraSample {
  Ray ray;
  Vec2 film;
  Vec2 pixel_center;
  float dP = 0, dD = 0;             // the ray's compact differentials (Camera::differentials), for bump
  Vec2 lens{0.5f, 0.5f};            // the lens sample the ray was generated with (Camera::generate)
  Spectrum* lightgroups = nullptr;  // the sample's light group buffer, zeroed (SampleValue::lightgroups)
  float* aovs = nullptr;            // its AOV buffer, zeroed (SampleValue::aovs)
};

// A light-tracing contribution to a pixel of the render region (BDPT's t = 1), and its cell in
// the strategy view (-1 when the view is off).
struct Splat {
  uint32_t pixel;
  Spectrum value;
  int32_t strategy = -1;
  // Light passes: the path's scattering vertices (its light vertex's lobe next to the camera is
  // its first bounce) and that vertex's split (light_passes.h).
  int32_t bounces = 0;
  FirstBounce first;
  int32_t lightgroup = -1;  // its light's group
};

// The strategy view's grid: row = path depth d = s + t - 2, column = s (0 .. depth + 2 - 1).
inline int strategy_columns(int depth) { return depth + 2; }
inline int strategy_cell(int s, int t, int depth) {
  int d = s + t - 2;
  return d >= 0 && d < depth && s < strategy_columns(depth) ? d * strategy_columns(depth) + s : -1;
}

// What an integrator renders: the scene through the camera (whose film is the full frame), and the
// render region inside the frame.
struct RenderContext {
  const Scene& scene;
  const Camera& camera;
  const FilterSampler& filter;
  IntegratorSettings settings;
  int x0, y0, width, height;  // render region in full-frame pixels
};

// A pass's light-tracing splats, two lists per tile (halves A and B) in tile order, and the camera
// samples traced in it (of them in half B).
struct PassSplats {
  const std::vector<std::vector<Splat>>& tiles;
  uint64_t samples, samples_half;
};

class Integrator {
 public:
  explicit Integrator(const RenderContext& ctx) : ctx_(ctx) {}
  virtual ~Integrator() = default;
  // The film's label mask (Film::set_labels), for views that name their parts; empty for none.
  virtual std::vector<uint8_t> film_labels() const { return {}; }
  // Before a pass; the film receives per-pixel extras during it (BDPT's strategy view).
  virtual void begin_pass(Film& film) {}
  // One camera sample (thread-safe): the value of its pixel; contributions to other pixels of the
  // region (light tracing) go to `splats`, dropped by the caller if the value is not finite.
  virtual SampleValue trace(const CameraSample& cs, Sampler& sampler, SampleStats& stats,
                            std::vector<Splat>& splats) const = 0;
  // A camera sample whose film position sees nothing (outside a fisheye's circle): black and
  // opaque, but it still counts as a light path (light tracing divides splats by their number),
  // so an integrator that splats traces that path (cs.ray holds only the time).
  virtual void trace_unseen(const CameraSample& cs, Sampler& sampler, SampleStats& stats,
                            std::vector<Splat>& splats) const {}
  // After a pass: the pass's splats into the film, in a fixed order (the same image for any
  // thread count).
  virtual void end_pass(Film& film, const PassSplats& splats) {}

 protected:
  RenderContext ctx_;
};

// The integrator for `type`; "Volumetric Path" on a scene without media is the path tracer (the
// same estimator, without the media code).
std::unique_ptr<Integrator> make_integrator(IntegratorType type, const RenderContext& ctx);
// What an integrator of a type asks of the film and the render job beyond the passes, known before
// the integrator exists (the job sizes the film and estimates its memory from it).
struct IntegratorNeeds {
  bool splats = false;         // light-tracing splats: the film's splat buffers
  int strategy_cells = 0;      // the film's per-pixel strategy view (Film::add_strategies)
  size_t bytes_per_pixel = 0;  // the integrator's own per-pixel buffers during a pass
};
IntegratorNeeds integrator_needs(IntegratorType type, const IntegratorSettings& s);
// The integrator's name as lt_integrator spells it without LT_INTEGRATOR_ (EXR metadata).
const char* integrator_name(IntegratorType type);

// The integrators, one file each; make_integrator picks among them.
// Unidirectional path tracing (path.cpp); `media`: volumetric path tracing, only for scenes with media.
std::unique_ptr<Integrator> make_path_integrator(const RenderContext& ctx, bool media);
// Bidirectional path tracing (bdpt.cpp): one camera subpath and one light subpath per sample, every
// connection strategy weighted by MIS; t = 1 contributions are splats. With the film's strategy
// view on, each sample's weighted contribution per strategy cell goes to the film too.
std::unique_ptr<Integrator> make_bdpt_integrator(const RenderContext& ctx);
IntegratorNeeds bdpt_needs(const IntegratorSettings& s);
// Volume debug view (volume_debug.cpp): a 2x2 grid of panels, each the whole view at half size:
// transmittance by ray marching | by ratio tracking (top), distance sampled by ray marching | by
// delta tracking (bottom).
std::unique_ptr<Integrator> make_volume_debug_integrator(const RenderContext& ctx);

}  // namespace lt
