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
