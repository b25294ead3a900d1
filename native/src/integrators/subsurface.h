// Subsurface scattering under a BSSRDF (LobeType::Subsurface, shading/bsdf.h) as Cycles 3.4 does
// it (kernel/integrator/subsurface.h): from the entry point into the shaded object's own geometry
// (Geometry::intersect_instance, Cycles' scene_intersect_local) to an exit point on it, which the
// caller then shades with a diffuse lobe of weight 1 (exit_lobe): Random Walk (Fixed Radius) by
// subsurface_random_walk.h, Christensen-Burley by subsurface_disk.h.
#pragma once

#include "geometry/geometry.h"
#include "shading/bsdf.h"

namespace lt {

struct SubsurfaceExit {
  SurfacePoint sp;
  // Unit, world: the side the exit point is shaded from (Cycles pretends a ray arrives from
  // there): the walk's last direction, or the disk hit's normal.
  Vec3 wo{0.0f};
};

// The walk from sp (n: the BSSRDF's shading normal, ng the geometric normal, both facing the ray
// that arrived; backfacing: it arrived from the back of the triangle) under lobe l. beta is the
// path's throughput with the lobe's weight / its selection probability in it; it leaves with the
// walk's weight in it. False: no exit (the path ends, as Cycles').
bool subsurface_scatter(const Geometry& geometry, const SurfacePoint& sp, const Vec3& n, const Vec3& ng,
                        bool backfacing, const Lobe& l, float time, Sampler& sampler, Spectrum* beta,
                        SubsurfaceExit* exit);

// The exit point's lobe (Cycles' subsurface_shader_data_setup): a Lambert-exit principled diffuse
// for the Principled BSDF's BSSRDF, else a Lambert diffuse; weight 1.
Lobe subsurface_exit_lobe(const Lobe& l);

// Exposed for tests: the volume coefficients of one channel (subsurface_random_walk_remap:
// Chiang et al. 2016's albedo inversion with Wrenninge et al.'s anisotropic fit), from the
// surface albedo, the radius d after bssrdf_radius and the anisotropy g.
void random_walk_remap(float albedo, float d, float g, float* sigma_t, float* alpha);

}  // namespace lt
