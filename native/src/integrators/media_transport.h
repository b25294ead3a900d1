// Light transport through the scene's media, shared by the volumetric path tracer and the volume
// debug view: the volume stack at the camera, transmittance along segments and shadow rays through
// invisible boundaries, and free-flight sampling over overlapping media.
#pragma once

#include "integrators/integrator.h"
#include "integrators/path_state.h"
#include "media/volume_stack.h"

namespace lt {

// Invisible medium boundaries one path, shadow ray or stack probe passes before it is given up: a
// bound on the work where boundaries nest deeply or a ray grazes along one.
constexpr int kMaxBoundaryCrossings = 1024;

// The media containing the ray's origin: the first boundary of each medium met along the ray is a
// back face (closed meshes; parity as in pbrt's medium interfaces). Follows the ray to infinity,
// seeing the boundaries of objects that rays of kind `visibility` see (a shadow catcher's
// catcher-only path: catchers' alone, as Cycles' integrator_volume_stack_init).
void init_volume_stack(const Scene& scene, const Ray& ray, VolumeStack* stack, SampleStats& stats,
                       unsigned visibility = kVisAll);
// The stack of a shadow catcher's catcher-only path (or light subpath) from ray.o: the media of
// catchers alone, no global media (Cycles re-inits the stack at the split, without the world's
// volume): volumes of other objects, even one around the camera, are not there.
VolumeStack catcher_volume_stack(const Scene& scene, const Ray& ray, SampleStats& stats);

// Applies a boundary crossing at a surface point by a ray leaving towards `dir` (enter when dir
// goes against the geometric normal's outside, i.e. into the closed mesh).
void cross_boundary(const Scene& scene, const SurfacePoint& sp, const Vec3& dir, VolumeStack* stack);

// Continues `ray`, which hit the invisible medium boundary sp at ray parameter hit_t, along the same
// line: crosses the boundary (updating the stack) and moves the origin past the surface, ray.tmax
// shortened by hit_t so the ray still ends where it did. Returns false, changing nothing, when
// ++*crossings (counted over a path or shadow ray) exceeds kMaxBoundaryCrossings.
bool pass_boundary(const Scene& scene, const SurfacePoint& sp, float hit_t, Ray* ray, VolumeStack* stack,
                   int* crossings);

// For a ray leaving a surface point that a path reached from the side of geometric normal `side`:
// crosses the boundary only if the ray goes through the surface (a reflection stays in the media
// it arrived in).
void leave_surface(const Scene& scene, const SurfacePoint& sp, const Vec3& side, const Vec3& dir, VolumeStack* stack);

// Product of the transmittances of every medium of the stack and every global medium on [t0, t1].
Spectrum media_transmittance(const Scene& scene, const VolumeStack& stack, const Ray& ray, float t0, float t1,
                             Sampler& sampler, VolumeEstimator est, float step);

// Free-flight sampling on [t0, t1] over the stack's and the global media: each medium is sampled
// on [t0, nearest collision so far]; the nearest collision wins (exact for independent media;
// a superseded collision's weight becomes its survival weight sigma_t/sigma_s x weight).
// Multiplies *beta by the weights; returns the colliding medium or -1 (continue to t1).
int sample_media(const Scene& scene, const VolumeStack& stack, const Ray& ray, float t0, float t1, Sampler& sampler,
                 VolumeEstimator est, float step, Spectrum* beta, MediumInteraction* mi);

// Volume emission reaching ray.o from [t0, t1] (t1 may be infinite): the emitted radiance per unit
// length of every emitting medium the ray is in (the stack's and, for a path in them, the global
// media: Volume objects and World volumes), integrated against the transmittance of every medium
// the ray is in. Homogeneous emitters: closed form over the homogeneous media (E (1 - exp(-sigma_t
// d)) / sigma_t per channel, as Cycles' volume_emission_integrate); if heterogeneous media overlap,
// their transmittance to one point sampled with density proportional to the homogeneous
// transmittance multiplies it (unbiased). Heterogeneous emitters: Medium::emission_integral.
// Emission is found only along path segments, never by light sampling (Cycles 3.4 does the same);
// it gets full weight. groups (may be null): the light groups the value belongs to, each emitter's
// part of the estimate per channel going to its group: the object whose boundary entered a mesh
// medium (Cycles files a segment's emission under one object's group, shade_volume.h: the same
// where one emitting volume is around the ray), a Volume object's own (Scene::medium_lightgroup),
// none for World volumes (as Cycles).
Spectrum media_emission(const Scene& scene, const VolumeStack& stack, const Ray& ray, float t0, float t1,
                        Sampler& sampler, VolumeEstimator est, float step, LightgroupShares* groups);

// Transmittance of a shadow ray (ray.tmax: distance to the light) through invisible boundaries
// (updating a copy of the stack), media and transparent surfaces (the weights of their Transparent
// lobes, Cycles' transparent shadows; more than max_transparent of them block, as Cycles'
// transparent bounce limit); 0 if an opaque surface is in the way. A scene with neither media nor
// transparent materials asks Embree for any hit. Surfaces seen by rays of kind `visibility` are in
// the way (BDPT's connections also stand for camera and indirect rays).
Spectrum shadow_transmittance(const Scene& scene, VolumeStack stack, Ray ray, Sampler& sampler, VolumeEstimator est,
                              float step, SampleStats& stats, int max_transparent, unsigned visibility = kVisShadow);

}  // namespace lt
