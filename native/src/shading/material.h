// Materials: a surface shader program (program.h) evaluated at a surface point into BSDF lobes
// and emitted radiance.
#pragma once

#include <memory>
#include <vector>

#include "geometry/geometry.h"
#include "geometry/hit.h"
#include "shading/bsdf.h"
#include "shading/image.h"
#include "shading/program.h"

namespace lt {

// Cycles' displacement methods beyond Bump (Material > Settings > Displacement): the mesh's
// vertices move by the Material Output's Displacement at scene commit (shading/displacement.h);
// True recomputes the smooth normals, Both keeps them and the surface program bumps them.
enum class DisplacementMethod : uint8_t { None, True, Both };

class Material {
 public:
  explicit Material(Program program);
  // Lantern's (and Cycles') default surface: diffuse grey 0.8.
  static Material default_surface();

  // Fills bsdf with the lobes at a point and returns the emitted radiance there (both sides).
  // frame: the normal set when the program brings its own (a Normal input linked), else untouched,
  // and the anisotropic tangent.
  Spectrum evaluate(const ShadingContext& ctx, const std::vector<std::unique_ptr<Image>>& images, Bsdf* bsdf,
                    ShadingFrame* frame) const {
    return program_.run(ctx, images, bsdf, frame);
  }
  // Emitted radiance only (for light sampling, without building lobes).
  Spectrum emission(const ShadingContext& ctx, const std::vector<std::unique_ptr<Image>>& images) const {
    return emissive_ ? program_.run(ctx, images, nullptr, nullptr) : Spectrum(0.0f);
  }
  bool emissive() const { return emissive_; }
  // Whether it emits the same radiance everywhere (emission closures of constant inputs), and
  // that radiance: light samples then need no shading point (Cycles' constant emission).
  bool constant_emission(Spectrum* emitted) const {
    if (constant_emission_) *emitted = constant_emitted_;
    return constant_emission_;
  }
  bool may_be_transparent() const { return program_.may_be_transparent(); }
  bool needs_differentials() const { return program_.needs_differentials(); }
  bool traces_rays() const { return program_.traces_rays(); }
  // A rough scalar for how bright the emission is, for picking lights by power.
  float emission_power_estimate() const { return emission_estimate_; }
  const Program& program() const { return program_; }
  // Material.pass_index, for the Material Index pass.
  float pass_index() const { return pass_index_; }
  void set_pass_index(float v) { pass_index_ = v; }
  // Cryptomatte id of the material's name (cryptomatte_id; 0: none).
  float crypto_id() const { return crypto_id_; }
  void set_crypto_id(float v) { crypto_id_ = v; }
  // True displacement: the program giving the Material Output's Displacement (SetDisplacement).
  void set_displacement(std::shared_ptr<const Program> program, DisplacementMethod method) {
    displacement_ = std::move(program);
    displacement_method_ = displacement_ ? method : DisplacementMethod::None;
  }
  const Program* displacement() const { return displacement_.get(); }
  void keep_displacement_of(const Material& other) {
    displacement_ = other.displacement_;
    displacement_method_ = other.displacement_method_;
  }
  DisplacementMethod displacement_method() const { return displacement_method_; }

 private:
  Program program_;
  std::shared_ptr<const Program> displacement_;
  DisplacementMethod displacement_method_ = DisplacementMethod::None;
  float pass_index_ = 0, crypto_id_ = 0;
  bool emissive_ = false, constant_emission_ = false;
  float emission_estimate_ = 0;
  Spectrum constant_emitted_{0.0f};
};

// A program's shading normal as the integrators use it: on the geometric normal's side (ng faces
// the incoming ray), else the geometric normal.
inline Vec3 facing_normal(const Vec3& n, const Vec3& ng) { return dot(n, ng) > 0 ? n : ng; }
// The local frame lobes are evaluated in.
inline Frame local_frame(const ShadingFrame& f, const Vec3& ng) {
  const Vec3 n = facing_normal(f.n, ng);
  return is_black(f.tangent) ? Frame(n) : Frame(n, f.tangent);
}

// The shading point as the nodes see it, for a ray of direction ray_d that met sp at distance t
// from its start (a camera ray starts at the near clip, as Cycles').
ShadingContext shading_context(const Geometry& geometry, const SurfacePoint& sp, const Vec3& ray_d, float t);
// Gives the shading point the normal n (unit, facing the ray) and what depends on it: object_normal() and
// Geometry's Tangent (shading_context; Cycles' SetNormal replaces sd->N the same way).
void set_shading_normal(ShadingContext* ctx, const Vec3& n);
// What Bump and Wireframe need (ShadingContext::footprint, offset, corners): the ray footprint at
// the point (Cycles' compact dP: the camera's dP plus its dD times the path's length), the shading
// point moved by it along the surface, and the triangle's corners in world space.
void add_differentials(const Geometry& geometry, const SurfacePoint& sp, float footprint, ShadingContext* ctx);
// What Ambient Occlusion and Bevel need at a path's vertex: the scene to trace, the point's time,
// one number from the path's sampler for their rays (drawn only by materials that trace) and the
// smallest pdf of the path's bounces so far (Cycles' min_ray_pdf).
void add_tracing(const Geometry& geometry, const SurfacePoint& sp, float min_ray_pdf, Sampler& sampler,
                 ShadingContext* ctx);

}  // namespace lt
