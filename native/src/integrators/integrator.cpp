#include "integrators/integrator.h"

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

}  // namespace lt
