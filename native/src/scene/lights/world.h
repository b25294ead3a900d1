// The world background as a light. Its Surface is a shader program (the add-on compiles the World's
// node tree as it does materials) whose Background (emission) closures give the radiance arriving
// from a direction, or, when it folds to a constant, one colour. As Cycles does, a non-constant
// world is importance sampled from a map of the program baked on an equirectangular grid (weights
// average(|rgb|) x sin(theta), kernel/light/background.h), while the radiance is always the
// program's at the exact direction: the map decides only the pdf. A Sky Texture's sun disc (far
// smaller than a map pixel) has its pixels supersampled and its cone sampled beside the map.
#pragma once

#include <memory>
#include <vector>

#include "core/distribution.h"
#include "scene/lights/light.h"
#include "shading/image.h"
#include "shading/program.h"

namespace lt {

// The shading point of a ray that escaped in direction dir (Cycles' shader_setup_from_background:
// P = dir, N = Ng = I = -dir; Generated and Object are dir). Its Light Path flags are those of
// light sampling (Cycles' PATH_RAY_EMISSION: no ray kind set); an escaped ray's integrator sets its
// own (describe_ray).
ShadingContext world_context(const Vec3& dir);

class World {
 public:
  // A constant world: radiance `color` from every direction.
  void set_color(const Spectrum& c);
  // A world program (emission closures); map_resolution: the sampling map's width (height half of
  // it), 0 for automatic: the largest Environment Texture image's size, else 1024 x 512 (Cycles'
  // world sample_map_resolution and its automatic rule).
  void set_program(std::shared_ptr<const Program> program, int map_resolution);

  bool camera_visible = true;
  int lightgroup = -1;  // the light group of its light (-1: none)

  // Radiance arriving along -ctx.I (ctx from world_context, with the ray's Light Path flags).
  Spectrum radiance(const ShadingContext& ctx) const {
    return program_ ? program_->run(ctx, *images_, nullptr, nullptr) : color_;
  }
  // As light sampling sees it (Light Path flags of world_context).
  Spectrum radiance(const Vec3& dir) const {
    return escaped_radiance(dir, [](ShadingContext*) {});
  }
  // Along an escaped ray's direction: `prepare(ShadingContext*)` gives a program's context the
  // ray's Light Path values and writes its AOV outputs. A constant world has neither to use, and
  // its context is not built (an escaped ray is most of the shading under a uniform sky).
  template <class Prepare>
  Spectrum escaped_radiance(const Vec3& dir, Prepare&& prepare) const {
    if (!program_) return color_;
    ShadingContext wc = world_context(dir);
    prepare(&wc);
    return radiance(wc);
  }
  bool black() const { return !program_ && is_black(color_); }
  // Whether a sampling map is used (false: constant, never light-sampled by the integrators).
  bool has_map() const { return program_ != nullptr; }
  int map_width() const { return map_w_; }
  int map_height() const { return map_h_; }
  // Solid-angle mean of average(|radiance|) (light picking).
  float mean() const { return mean_; }

  // At commit (once after each set_*): folds a constant program into a colour, else bakes the
  // sampling map.
  void build(const std::vector<std::unique_ptr<Image>>& images);

  Vec2 sample_map(Vec2 u, float* pdf_uv) const { return distribution_.sample(u, pdf_uv); }
  float map_pdf(Vec2 uv) const { return distribution_.pdf(uv); }
  // A Sky Texture's sun discs (Program::sun_discs) are sampled apart, uniformly in their cones,
  // with this probability (0: none); world_sample and world_pdf mix them with the map.
  float sun_probability() const { return sun_probability_; }
  Vec3 sample_sun(Vec2 u) const;
  float sun_pdf(const Vec3& wi) const;  // solid-angle density of sample_sun (wi unit)

 private:
  // Returns the map's weight in the pixels it supersampled.
  double supersample_sun_discs(std::vector<float>* f, int w, int h) const;
  struct SunCone {
    Vec3 dir;
    float one_minus_cos;  // of the half angle
  };
  std::vector<SunCone> suns_;
  float sun_probability_ = 0;
  Spectrum color_{0.0f};
  std::shared_ptr<const Program> program_;
  int map_resolution_ = 0;
  const std::vector<std::unique_ptr<Image>>* images_ = nullptr;
  int map_w_ = 0, map_h_ = 0;
  Distribution2D distribution_;  // over the map's (u, v), weighted by sin(theta)
  float mean_ = 0;
  bool built_ = false;
};

bool world_sample(const World& w, Vec2 u, LightSample* s);
// Solid-angle density of world_sample for direction wi.
float world_pdf(const World& w, const Vec3& wi);
// The direction as world_sample picks it, the origin on the scene's disk (emit_from_scene_disk).
bool world_sample_emission(const World& w, const Vec3& center, float radius, Vec2 up, Vec2 ud, EmissionSample* e);

}  // namespace lt
