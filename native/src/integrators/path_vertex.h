// A vertex of a camera or light subpath for bidirectional path tracing (Veach 1997, ch. 10;
// pbrt 3, section 16.3). Densities are stored in area measure (solid angle for infinite lights)
// so that MIS weights are sums of ratios of neighbouring densities.
#pragma once

#include "core/math.h"
#include "geometry/hit.h"
#include "integrators/path_state.h"
#include "media/volume_stack.h"
#include "shading/bsdf.h"

namespace lt {

enum class VertexType : uint8_t {
  Camera,
  Light,
  Surface,
  Medium,  // scattering inside a participating medium (its phase function instead of a BSDF)
};

struct PathVertex {
  VertexType type = VertexType::Surface;
  bool delta = false;                  // reached by sampling a delta lobe, or a delta light/camera position
  bool infinite = false;               // sun or world light vertex: a direction rather than a point
  int light = -1;                      // light index: Light vertices, and Surface vertices on emissive meshes
  BounceKind kind = BounceKind::None;  // for Cycles' per-kind limits (see bdpt.cpp)
  // Vertices of several possible kinds, between two vertices of the same subpath: the probabilities
  // that the path tracer counts their bounce as diffuse, glossy, transmission (-1: it cannot
  // sample the path there). Set by the walk once both neighbours are known (bdpt.cpp).
  float kind_p[3] = {0, 0, 0};
  Spectrum beta{1.0f};  // throughput of the subpath up to and including this vertex
  Spectrum le{0.0f};    // Surface vertices: the radiance they emit towards their predecessor (s = 0)
  float pdf_fwd = 0;    // density of sampling this vertex from its predecessor
  float pdf_rev = 0;    // density of sampling it from its successor (the other direction)
  // Light vertices: next-event estimation's density for this light point from the neighbouring
  // vertex in units of the light's area density 1/A: the light tree's pick probability x
  // LightSet::nee_position_ratio (light subpaths pick by power, uniform by area: pdf_fwd).
  float nee_pick = 0;
  Vec3 p;
  Vec3 n;       // geometric normal (zero for points in space: point lights, camera, media)
  Frame frame;  // shading frame, z facing the side the vertex was reached from
  Vec3 ns;      // Surface vertices: the shading normal facing the predecessor (Cycles' sd->N)
  Vec3 wo;      // direction towards the predecessor: local (surfaces), world (media)
  // Surfaces: Cycles tilts the shading normal for the viewer (ensure_valid_reflection), so the
  // frame depends on the direction a path arrives from (Bdpt::view_frame): the normal untilted
  // (ShadingFrame::raw), the smooth normal of the bump term and the tangent; tilts: it may.
  Vec3 raw_n, smooth_n, tangent;
  bool tilts = false;
  SurfacePoint sp;
  Bsdf bsdf;
  int medium = -1;  // Medium vertices: the medium whose phase function scatters
  // The ray kinds (path_state.h's kVis bits) that can reach the vertex: its object's or light's
  // ray visibility; every kind for medium and camera vertices (see Bdpt::mis_weight).
  unsigned vis = kVisAll;
  VolumeStack stack;  // scenes with media: the media around the vertex on the side it was reached from

  bool on_surface() const { return n.x != 0 || n.y != 0 || n.z != 0; }
  bool connectible() const {
    switch (type) {
      case VertexType::Surface:
        return bsdf.has_non_delta();
      case VertexType::Light:
        return !delta_direction;
      default:
        return true;
    }
  }
  bool delta_direction = false;  // Light vertices: the light emits in one direction (sun with angle 0)
};

}  // namespace lt
