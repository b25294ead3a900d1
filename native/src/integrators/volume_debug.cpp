// The sheet's a05_smoke_debug view (Assignments 2 and 3): for a camera ray, the transmittance to
// the first opaque surface by ray marching or ratio tracking, or the distance sampled by ray
// marching (revert to the sampled optical depth) or delta tracking. Grey values in Combined.
// Panels: top row transmittance (marching | ratio tracking), bottom row sampled distance
// (marching | delta tracking); each panel is the whole view at half the resolution.
#include <algorithm>

#include "core/label_font.h"
#include "integrators/media_transport.h"

namespace lt {

namespace {

// For the camera ray of a panel pixel, panel 0 = transmittance by ray marching, 1 = by ratio
// tracking, 2 = sampled distance by ray marching, 3 = by delta tracking (distance from the ray
// origin in world units, 0 without a collision).
SampleValue trace_panel(const Scene& scene, const IntegratorSettings& s, const Ray& camera_ray, int panel,
                        Sampler& sampler, SampleStats& stats) {
  SampleValue out;
  out.alpha = 1;
  const VolumeEstimator est = panel == 0 || panel == 2 ? VolumeEstimator::RayMarching : VolumeEstimator::Tracking;
  VolumeStack stack;
  if (scene.has_boundaries()) init_volume_stack(scene, camera_ray, &stack, stats);
  if (panel < 2) {
    out.radiance =
        shadow_transmittance(scene, stack, camera_ray, sampler, est, s.volume_step, stats, s.transparent_bounces);
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
    if (sample_media(scene, stack, ray, ray.tmin, found ? hit.t : ray.tmax, sampler, est, s.volume_step, &beta, &mi) >=
        0) {
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

class VolumeDebugIntegrator final : public Integrator {
 public:
  explicit VolumeDebugIntegrator(const RenderContext& ctx)
      : Integrator(ctx), w_(ctx.camera.width()), h_(ctx.camera.height()) {}

  // The panel names, stamped at each panel's top-left corner (in the region's pixels): 2x for
  // panels 200 px wide or more, skipped for panels too small to hold them.
  std::vector<uint8_t> film_labels() const override {
    static const char* const kNames[4] = {"T MARCH", "T RATIO", "D MARCH", "D DELTA"};
    const int hw = std::max(1, w_ / 2), hh = std::max(1, h_ / 2);
    const int pw = std::min(hw, w_ - hw), ph = std::min(hh, h_ - hh);
    constexpr int kMargin = 1;
    int scale = pw >= 200 ? 2 : 1;
    while (scale > 0 && (label_width("T MARCH", scale) + 2 * kMargin > pw || label_height(scale) + 2 * kMargin > ph))
      --scale;
    if (!scale) return {};
    std::vector<uint8_t> mask(size_t(ctx_.width) * ctx_.height, kLabelNone);
    for (int panel = 0; panel < 4; ++panel) {
      const int x = (panel % 2) * hw + kMargin, y_top = (panel < 2 ? h_ : hh) - 1 - kMargin;
      stamp_label(mask, ctx_.width, ctx_.height, x - ctx_.x0, y_top - ctx_.y0, kNames[panel], scale);
    }
    return mask;
  }

  // The camera sample's film position within its panel, scaled up to the whole view.
  SampleValue trace(const CameraSample& cs, Sampler& sampler, SampleStats& stats, std::vector<Splat>&) const override {
    const int hw = std::max(1, w_ / 2), hh = std::max(1, h_ / 2);
    const int col = cs.film.x >= hw ? 1 : 0, top = cs.film.y >= hh ? 1 : 0;
    float fx = std::min(cs.film.x - col * hw, float(hw)) * w_ / float(hw);
    float fy = std::min(cs.film.y - top * hh, float(hh)) * h_ / float(hh);
    Ray ray;
    if (!ctx_.camera.generate(fx, fy, cs.lens, &ray, cs.ray.time)) {
      SampleValue none;  // nothing seen there: black and opaque, as render.cpp
      none.alpha = 1;
      return none;
    }
    return trace_panel(ctx_.scene, ctx_.settings, ray, (1 - top) * 2 + col, sampler, stats);
  }

 private:
  int w_, h_;  // the full frame
};

}  // namespace

std::unique_ptr<Integrator> make_volume_debug_integrator(const RenderContext& ctx) {
  return std::make_unique<VolumeDebugIntegrator>(ctx);
}

}  // namespace lt
