// The sheet's a05_smoke_debug view (Assignments 2 and 3): for a camera ray, the transmittance to
// the first opaque surface by ray marching or ratio tracking, or the distance sampled by ray
// marching (revert to the sampled optical depth) or delta tracking. Grey values in Combined.
#include "integrators/media_transport.h"

namespace lt {

SampleValue trace_volume_debug(const Scene& scene, const IntegratorSettings& s, const Ray& camera_ray, int panel,
                               Sampler& sampler, SampleStats& stats) {
  SampleValue out;
  out.alpha = 1;
  const VolumeEstimator est = panel == 0 || panel == 2 ? VolumeEstimator::RayMarching : VolumeEstimator::Tracking;
  VolumeStack stack;
  if (scene.has_boundaries()) init_volume_stack(scene, camera_ray, &stack, stats);
  if (panel < 2) {
    out.radiance = shadow_transmittance(scene, stack, camera_ray, sampler, est, s.volume_step, stats);
    return out;
  }
  // Distance to the first collision along the camera ray, through invisible boundaries.
  Ray ray = camera_ray;
  float travelled = 0;
  for (int crossings = 0;;) {
    Hit hit;
    ++stats.rays;
    bool found = scene.geometry.intersect(ray, 1u, &hit);
    Spectrum beta(1.0f);
    MediumInteraction mi;
    if (sample_media(scene, stack, ray, ray.tmin, found ? hit.t : ray.tmax, sampler, est, s.volume_step, &beta, &mi) >= 0) {
      out.radiance = Spectrum(travelled + mi.t * length(ray.d));
      return out;
    }
    if (!found) break;
    SurfacePoint sp = scene.geometry.surface(hit);
    if (!scene.null_surface(sp.material) || !pass_boundary(scene, sp, hit.t, &ray, &stack, &crossings)) break;
    travelled += hit.t * length(ray.d);
  }
  out.radiance = Spectrum(0.0f);
  return out;
}

}  // namespace lt
