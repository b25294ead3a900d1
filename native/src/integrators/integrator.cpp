#include "integrators/integrator.h"

#include "integrators/media_transport.h"

namespace lt {

std::unique_ptr<Integrator> make_integrator(IntegratorType type, const RenderContext& ctx) {
  switch (type) {
    case IntegratorType::Bidirectional:
      return make_bdpt_integrator(ctx);
    case IntegratorType::VolumeDebug:
      return make_volume_debug_integrator(ctx);
    case IntegratorType::VolPath:
      return make_path_integrator(ctx, ctx.scene.has_media());
    case IntegratorType::Path:
    case IntegratorType::Count:
      break;
  }
  return make_path_integrator(ctx, false);
}

IntegratorNeeds integrator_needs(IntegratorType type, const IntegratorSettings& s) {
  return type == IntegratorType::Bidirectional ? bdpt_needs(s) : IntegratorNeeds{};
}

const char* integrator_name(IntegratorType type) {
  switch (type) {
    case IntegratorType::Path:
      return "PATH";
    case IntegratorType::Bidirectional:
      return "BIDIRECTIONAL";
    case IntegratorType::VolPath:
      return "VOLPATH";
    case IntegratorType::VolumeDebug:
      return "VOLUME_DEBUG";
    case IntegratorType::Count:
      break;
  }
  return "?";
}

}  // namespace lt

namespace lt {

float mist_coverage(const Camera& camera, const IntegratorSettings& s, const Vec3& p, const Spectrum& beta) {
  // Cycles' camera_distance: along the view axis for orthographic cameras, else from the camera.
  const float d = camera.orthographic() ? std::abs(camera.depth(p)) : length(p - camera.position());
  const float inv_depth = s.mist_depth > 0 ? 1 / s.mist_depth : 0.0f;  // Cycles' film.cpp
  float mist = clamp((d - s.mist_start) * inv_depth, 0.0f, 1.0f);
  if (s.mist_falloff == 2.0f)
    mist *= mist;
  else if (s.mist_falloff == 0.5f)
    mist = std::sqrt(mist);
  else if (s.mist_falloff != 1.0f)
    mist = std::pow(mist, s.mist_falloff);
  return (1 - mist) * (beta[0] + beta[1] + beta[2]) / 3;
}

void write_data_passes(const Scene& scene, const Camera& camera, const IntegratorSettings& s, const SurfacePoint& sp,
                       const Spectrum& beta, SampleValue* out) {
  out->position = sp.p;
  const Mesh& mesh = scene.geometry.mesh(scene.geometry.instance(sp.instance).mesh);
  out->uv = mesh.corner_uvs.empty() ? Vec3(0.0f) : Vec3(sp.uv.x, sp.uv.y, 1.0f);
  const Instance& inst = scene.geometry.instance(sp.instance);
  out->object_index = inst.pass_index;
  out->material_index = sp.material >= 0 ? scene.material(sp.material).pass_index() : 0.0f;
  out->crypto_id[kCryptoObject] = inst.crypto_object;
  out->crypto_id[kCryptoMaterial] = sp.material >= 0 ? scene.material(sp.material).crypto_id() : 0.0f;
  out->crypto_id[kCryptoAsset] = inst.crypto_asset;
  out->crypto_weight = (beta[0] + beta[1] + beta[2]) / 3;
  out->mist += mist_coverage(camera, s, sp.p, beta);
}

Spectrum ambient_occlusion(const Scene& scene, const IntegratorSettings& s, const SurfacePoint& sp, const Vec3& n,
                           const Vec3& side, const VolumeStack* stack, Sampler sampler, SampleStats& stats) {
  // Cycles samples the direction with the BSDF's dimension (PRNG_SURFACE_BSDF); the copy gives the
  // ray the numbers next-event estimation takes next, which keeps them stratified over the pixel.
  sampler.next_1d();
  const Vec3 d = Frame(n).to_world(sample_cosine_hemisphere(sampler.next_2d()));
  Ray ray;
  ray.d = d;
  leave(sp, &ray);
  ray.tmin = 0;
  ray.tmax = s.ao_distance;
  ray.time = sp.time;
  VolumeStack st;
  if (stack) {
    st = *stack;
    leave_surface(scene, sp, side, d, &st);
  }
  return shadow_transmittance(scene, st, ray, sampler, s.volume_estimator, s.volume_step, stats, s.transparent_bounces);
}

bool motion_vector(const Scene& scene, const Camera& camera, const SurfacePoint& sp, float out[4]) {
  // The point at the previous and next frames (motion steps at times 0 and 1, the centre at 0.5):
  // a triangle's barycentric point on its corners then (deformation included), else the
  // object-space point through the instance's transform then.
  const Instance& inst = scene.geometry.instance(sp.instance);
  const bool triangles = scene.geometry.mesh(inst.mesh).is_triangles();
  Vec2 at[3];
  for (int k = 0; k < 3; ++k) {
    const float time = 0.5f * k;
    // The centre too, so that what does not move has exactly zero motion.
    Vec3 p;
    if (triangles) {
      Vec3 p0, p1, p2;
      scene.geometry.triangle(sp.instance, sp.primitive, &p0, &p1, &p2, time);
      p = p0 * (1 - sp.bary.x - sp.bary.y) + p1 * sp.bary.x + p2 * sp.bary.y;
    } else {
      p = scene.geometry.pose(sp.instance, time).xf.point(sp.po);
    }
    if (!camera.raster(p, time, &at[k])) return false;
  }
  // Cycles' primitive_motion_vector: (pre - centre, centre - post).
  out[0] = at[0].x - at[1].x;
  out[1] = at[0].y - at[1].y;
  out[2] = at[1].x - at[2].x;
  out[3] = at[1].y - at[2].y;
  return true;
}

}  // namespace lt
