// Participating media: homogeneous (closed form) and heterogeneous (a voxel density grid times
// coefficients per unit density), with transmittance estimation and free-flight distance sampling.
//
// Heterogeneous estimators (select per call with VolumeEstimator):
//  * RayMarching (biased, deterministic): midpoint quadrature of sigma_t with a fixed step,
//    starting where the ray enters the grid's domain; distance sampling accumulates optical depth
//    in the same steps up to tau = -ln(1 - u) and reverts linearly inside the last step (sigma_t is
//    taken as constant within a step, so the revert is exact for the marched field).
//  * Tracking (unbiased): residual ratio tracking for transmittance (Novak et al. 2014) and delta
//    tracking for distances (Woodcock et al. 1965), generalised to chromatic media as spectral
//    tracking (Kutz et al. 2017). Both are callbacks of one track(), which walks the majorant
//    segments and samples the tentative collisions (pbrt-v4's SampleT_maj). The majorant is
//    piecewise constant: a coarse grid of per-cell maxima of the interpolated density
//    (media/majorant_grid.h), traversed by 3D DDA, not one global maximum; the same grid keeps
//    per-cell minima, the control extinction of residual ratio tracking, whose share of the
//    transmittance is computed exactly, so that only the residual max - min is tracked.
// Homogeneous media always use the closed forms, whatever the estimator.
//
// Conventions the caller must follow (pbrt-v3's):
//  * Ray parameters t are those of `ray` (world position ray.o + t ray.d); ray.d need not be unit
//    length: coefficients are per world unit and are scaled by |ray.d| internally.
//  * transmittance() returns an estimate of T(t0, t1) per RGB channel (exact for homogeneous media
//    and deterministic for ray marching; unbiased, possibly 0 or > 1, for ratio tracking).
//  * sample_distance(): multiply the path throughput by out->weight in BOTH cases.
//      - true  = a real collision at out->t (scattering or absorption is not split: the weight
//        already carries sigma_s): weight = sigma_s(t) T(t0, t) / pdf(t). The caller then
//        scatters with the phase function (NEE and phase sampling) WITHOUT multiplying sigma_s
//        again. Grey media give weight = albedo sigma_s / sigma_t.
//      - false = no collision before t1: weight = T(t0, t1) / P(no collision), 1 for grey media; the
//        caller continues to the surface (or boundary) at t1.
//    pdf and P use the channel-averaged (one-sample MIS, balance heuristic) densities for
//    homogeneous media and ray marching, and spectral tracking's weights for tracking, so that
//    every RGB channel's expectation is exact even when sigma_t differs per channel.
//  * Work is bounded: a tracking call stops after kMaxTrackingSteps tentative collisions (then
//    transmittance returns 0 and distance sampling forces a collision at the current point with
//    weight (current weight) x albedo; both are biased but happen only when the majorant's optical
//    depth over the segment exceeds ~kMaxTrackingSteps; counted in capped_calls()). Ray marching
//    takes at most kMaxMarchingSteps steps per call, enlarging the step if the segment needs more.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>

#include "core/math.h"
#include "core/sampling.h"
#include "geometry/motion.h"
#include "media/density_grid.h"
#include "media/grid_emission.h"
#include "media/majorant_grid.h"
#include "media/phase.h"

namespace lt {

enum class VolumeEstimator { RayMarching, Tracking };

struct MediumInteraction {
  float t = 0;             // ray parameter of the collision
  Vec3 p;                  // world position ray.o + t ray.d
  Spectrum sigma_s{0.0f};  // scattering coefficient at p, per world unit (informational: already in weight)
  Spectrum weight{1.0f};   // throughput factor; see the conventions above
  int steps = 0;           // marching steps or tentative collisions taken (statistics)
};

class Medium {
 public:
  static constexpr int kMaxTrackingSteps = 1 << 16;
  static constexpr int kMaxMarchingSteps = 1 << 16;
  static constexpr int kDefaultMajorantCell = 4;  // voxels per majorant cell edge

  Medium() = default;  // vacuum: empty()
  Medium(const Medium& o);
  Medium& operator=(const Medium& o);

  // sigma_a, sigma_s per world unit; g is the Henyey-Greenstein anisotropy.
  static Medium homogeneous(const Spectrum& sigma_a, const Spectrum& sigma_s, float g);
  // sigma_a, sigma_s per world unit and per unit density; the grid's index space maps to world by
  // object_to_world * grid.index_to_object. Builds the majorant grid (cells of `majorant_cell`
  // voxels per edge). Throws InvalidArgument for a null grid, negative or non-finite coefficients,
  // or a singular transform.
  static Medium heterogeneous(std::shared_ptr<const GridData> grid, const Spectrum& sigma_a, const Spectrum& sigma_s,
                              float g, const Transform& object_to_world = Transform(),
                              int majorant_cell = kDefaultMajorantCell);

  bool is_homogeneous() const { return !grid_; }
  // True if the medium has no effect on light (sigma_t == 0 everywhere): callers can skip it.
  bool empty() const { return empty_; }
  // World-space bounds of the region where sigma_t can be non-zero; false if unbounded
  // (homogeneous media are bounded by their mesh, not by the medium).
  bool bounds(Vec3* lo, Vec3* hi) const;
  // Clips [*t0, *t1] to the region where sigma_t can be non-zero; false if nothing is left.
  bool clip(const Ray& ray, float* t0, float* t1) const;

  Spectrum transmittance(const Ray& ray, float t0, float t1, Sampler& s, VolumeEstimator e, float step) const;
  bool sample_distance(const Ray& ray, float t0, float t1, Sampler& s, VolumeEstimator e, float step,
                       MediumInteraction* out) const;

  const Phase& phase() const { return phase_; }
  // A mixture of HG lobes (volume shader mixes; media/volume_material.h) replaces the single lobe.
  void set_phase(const Phase& p) { phase_ = p; }
  // Emitted radiance per unit length (Cycles' volume emission, not scaled by density; a channel may
  // be negative, as Cycles' blackbody below ~1900 K); homogeneous media only (throws
  // InvalidArgument otherwise, or for non-finite values). Emission is
  // light no estimator samples: the integrators add its closed-form integral along each segment.
  void set_emission(const Spectrum& e);
  const Spectrum& emission() const { return emission_; }
  bool emissive() const { return emissive_; }
  // A heterogeneous medium's emission read from grids (a Volume object's; media/grid_emission.h),
  // evaluated per lookup inside the domain (zero outside it); an emission with a region
  // (GridEmission::set_region) widens the domain to hold it. Throws InvalidArgument for a
  // homogeneous medium.
  void set_grid_emission(std::shared_ptr<const GridEmission> e);
  const GridEmission* grid_emission() const { return grid_emission_.get(); }
  // Emission per unit length at a world point (exact lookups; for tests and quadrature).
  Spectrum emission_at(const Vec3& p, float time = 0.5f) const;
  // A heterogeneous medium's emission reaching ray.o from [t0, t1]: an estimate of
  // integral E(s) T(t0, s) T_o(s) ds, T this medium's transmittance and T_o(s) =
  // exp(-sigma_other (s - t0) |ray.d|) x other(s) that of the media overlapping it (sigma_other the
  // homogeneous ones' extinction, `other` an estimate of the heterogeneous ones' transmittance to s,
  // or null). RayMarching integrates per step as Cycles does (E and sigma_t constant over the step,
  // closed form inside it); Tracking is unbiased: residual ratio tracking whose every tentative
  // collision scores E x the transmittance estimate there / its rate (pbrt-v4's emission at
  // tentative collisions, with Cycles' emission not scaled by density); where the density's
  // majorant is 0 the rate is one collision per voxel, so emission without density is found too.
  Spectrum emission_integral(const Ray& ray, float t0, float t1, Sampler& s, VolumeEstimator e, float step,
                             const Spectrum& sigma_other, const std::function<Spectrum(float)>* other) const;
  // Coefficients at a world point (exact lookups; for tests and quadrature).
  Spectrum sigma_t(const Vec3& p, float time = 0.5f) const { return (sigma_a_ + sigma_s_) * density(p, time); }
  Spectrum sigma_s(const Vec3& p, float time = 0.5f) const { return sigma_s_ * density(p, time); }
  float density(const Vec3& p, float time = 0.5f) const;  // 1 for homogeneous media
  const Spectrum& sigma_a_unit() const { return sigma_a_; }
  const Spectrum& sigma_s_unit() const { return sigma_s_; }
  // Smallest world-space edge of a voxel (0 for homogeneous media).
  float voxel_size() const { return voxel_size_; }
  // The ray-marching step in world units when the render gives none (a step <= 0 or NaN passed
  // to the estimators): the voxel size, as Cycles' step rate 1, or the Volume object's Step Size.
  float march_step() const { return march_step_; }
  void set_march_step(float step) { march_step_ = step; }
  const MajorantGrid& majorant_grid() const { return majorant_; }
  // Drops the control (every cell's lower bound becomes 0): Tracking's transmittance then is plain
  // ratio tracking, the baseline that tests and comparisons measure against.
  void drop_control() { majorant_.clear_minima(); }
  // A Volume object's motion over the shutter: its object-to-world transforms at equally spaced
  // times (at least 2, finite and invertible; interpolated as instances: core/motion.h). A ray
  // then looks its grid up through the transform at the ray's time (every ray of a sample has
  // one): the grid, its majorants and its march step stay as they are, in index space. Exact for
  // rigid motion; a scale that changes over the shutter keeps the density per world unit given.
  // No steps: still again. Throws InvalidArgument for a homogeneous medium or bad steps.
  void set_motion(const std::vector<Transform>& object_to_world);
  bool moves() const { return !motion_.empty(); }
  // World to the grid's index space at a shutter time (0 .. 1; any time for a still medium).
  Transform world_to_index(float time) const;
  std::shared_ptr<const GridData> grid() const { return grid_; }
  // Bytes held for this medium's grid: NanoVDB buffer (or dense array) + majorant grid.
  size_t memory_bytes() const;
  // Calls that hit kMaxTrackingSteps (see the conventions above).
  uint64_t capped_calls() const { return capped_.load(std::memory_order_relaxed); }

 private:
  void count_capped() const { capped_.fetch_add(1, std::memory_order_relaxed); }

  Spectrum sigma_a_{0.0f}, sigma_s_{0.0f};
  Phase phase_;
  Spectrum emission_{0.0f};
  std::shared_ptr<const GridEmission> grid_emission_;
  bool empty_ = true, emissive_ = false;
  std::shared_ptr<const GridData> grid_;
  Transform world_to_index_;                 // at the shutter's centre, or for a still medium
  Transform object_to_index_;                // the grid's, for a moving medium's world_to_index(time)
  std::vector<DecomposedTransform> motion_;  // object to world over the shutter (set_motion)
  MajorantGrid majorant_;
  float voxel_size_ = 0, march_step_ = 0;
  int majorant_cell_ = kDefaultMajorantCell;
  mutable std::atomic<uint64_t> capped_{0};
};

}  // namespace lt
