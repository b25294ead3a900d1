#include "scene/lights/world.h"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace lt {

ShadingContext world_context(const Vec3& dir) {
  ShadingContext c;
  c.P = c.generated = c.object_P = dir;
  c.N = c.Ng = c.I = -dir;
  c.set_normal_values(-dir, Vec3(0.0f));
  c.uv = Vec2{0, 0};
  c.bary = Vec2{0, 0};
  c.background = true;
  c.camera_ray = false;
  return c;
}

void World::set_color(const Spectrum& c) {
  color_ = c;
  program_.reset();
  built_ = false;
}

void World::set_program(std::shared_ptr<const Program> program, int map_resolution) {
  program_ = std::move(program);
  map_resolution_ = map_resolution;
  color_ = Spectrum(0.0f);
  built_ = false;
}

double World::supersample_sun_discs(std::vector<float>* f, int w, int h) const {
  // A sky's sun disc is smaller than a map pixel or two: pixel centres alone would miss it or give
  // its pixels the disc's full radiance. Pixels that may overlap a disc get the mean of a grid of
  // the program's values over them instead (in the disc's frame as the node sees an unmapped
  // direction; a disc mapped elsewhere stays point-sampled, still unbiased with MIS).
  constexpr int kGrid = 8;
  const float reach = kPi / h + 2 * kPi / w;  // a bound on a pixel's angular radius, doubled
  std::vector<uint8_t> near(f->size(), 0);
  for (const Program::SunDisc& disc : program_->sun_discs()) {
    const float cos_reach = std::cos(std::min(disc.half_angle + reach, kPi));
    tbb::parallel_for(0, h, [&](int y) {
      const float sin_theta = std::sin(kPi * (y + 0.5f) / h);
      for (int x = 0; x < w; ++x) {
        if (dot(equirectangular_to_direction({(x + 0.5f) / w, (y + 0.5f) / h}), disc.dir) < cos_reach) continue;
        double a = 0;
        for (int j = 0; j < kGrid; ++j)
          for (int i = 0; i < kGrid; ++i) {
            const Vec2 uv{(x + (i + 0.5f) / kGrid) / w, (y + (j + 0.5f) / kGrid) / h};
            const float v = average(abs(radiance(equirectangular_to_direction(uv))));
            if (std::isfinite(v)) a += v;
          }
        (*f)[size_t(y) * w + x] = float(a / (kGrid * kGrid)) * sin_theta;
        near[size_t(y) * w + x] = 1;
      }
    });
  }
  double mass = 0;  // the map's weight around the discs
  for (size_t i = 0; i < f->size(); ++i)
    if (near[i]) mass += (*f)[i];
  return mass;
}

void World::build(const std::vector<std::unique_ptr<Image>>& images) {
  images_ = &images;
  if (built_) return;
  built_ = true;
  mean_ = average(abs(color_));
  map_w_ = map_h_ = 0;
  distribution_ = Distribution2D();
  suns_.clear();
  sun_probability_ = 0;
  if (!program_) return;
  Spectrum constant;
  if (program_->constant_emission(images, &constant)) {
    // No table for a constant world: the light set never picks it (LightSet::build); on its own it
    // samples uniformly.
    program_.reset();
    color_ = constant;
    mean_ = average(abs(color_));
    return;
  }
  int w = map_resolution_, h = map_resolution_ / 2;
  if (map_resolution_ <= 0) {
    w = h = 0;
    for (uint32_t id : program_->environment_images()) {
      w = std::max(w, images[id]->width());
      h = std::max(h, images[id]->height());
    }
    if (w == 0 || h == 0) w = 1024, h = 512;
    if (w > 8192) {  // the largest map lantern.h allows (Cycles' Map Resolution maximum)
      h = std::max(1, int(int64_t(h) * 8192 / w));
      w = 8192;
    }
  }
  w = std::max(w, 1);
  h = std::max(h, 1);
  // Cycles' background_cdf: the program at each pixel centre, average colour x sin(theta).
  std::vector<float> f(size_t(w) * h);
  tbb::parallel_for(0, h, [&](int y) {
    const float v = (y + 0.5f) / h, sin_theta = std::sin(kPi * v);
    for (int x = 0; x < w; ++x) {
      const Spectrum L = radiance(equirectangular_to_direction({(x + 0.5f) / w, v}));
      const float a = average(abs(L));
      f[size_t(y) * w + x] = std::isfinite(a) ? a * sin_theta : 0.0f;
    }
  });
  const double sun_mass = supersample_sun_discs(&f, w, h);
  double sum = 0, weight = 0;
  for (int y = 0; y < h; ++y) {
    const double sin_theta = std::sin(kPi * (y + 0.5) / h);
    for (int x = 0; x < w; ++x) sum += f[size_t(y) * w + x];
    weight += sin_theta * w;
  }
  mean_ = weight > 0 ? float(sum / weight) : 0.0f;
  // The discs' cones are sampled beside the map (as Cycles' background sun sampling) with a
  // probability that grows with their share s of the map's weight, s / (1 + s): a bright sun gets
  // about half the samples, exactly in it, and the sky keeps the rest.
  for (const Program::SunDisc& disc : program_->sun_discs()) {
    const float sin_half = std::sin(0.5f * disc.half_angle);
    if (disc.half_angle > 0 && disc.half_angle < kPi) suns_.push_back({disc.dir, 2 * sin_half * sin_half});
  }
  const double share = sum > 0 ? std::min(1.0, sun_mass / sum) : 0.0;
  sun_probability_ = suns_.empty() ? 0.0f : float(share / (1 + share));
  distribution_ = Distribution2D(f, w, h);
  map_w_ = w;
  map_h_ = h;
}

bool world_sample(const World& w, Vec2 u, LightSample* s) {
  s->distance = INFINITY;
  s->n = Vec3(0.0f);
  s->on_surface = false;
  s->delta = false;
  if (w.has_map()) {
    const float q = w.sun_probability();
    if (u.x < q) {
      s->wi = w.sample_sun(Vec2{u.x / q, u.y});
    } else {
      float pdf_uv;
      const Vec2 uv = w.sample_map(Vec2{q > 0 ? std::min((u.x - q) / (1 - q), kOneMinusEpsilon) : u.x, u.y}, &pdf_uv);
      if (!(std::sin(kPi * (1 - uv.y)) > 0) || !(pdf_uv > 0)) return false;
      s->wi = equirectangular_to_direction(uv);
      if (q == 0) s->pdf = pdf_uv / (2 * kPi * kPi * std::sin(kPi * (1 - uv.y)));
    }
    if (q > 0) s->pdf = world_pdf(w, s->wi);  // the mixture's
    if (!(s->pdf > 0)) return false;
  } else {
    s->wi = sample_uniform_sphere(u);
    s->pdf = uniform_sphere_pdf();
  }
  s->radiance = w.radiance(s->wi);
  return true;
}

Vec3 World::sample_sun(Vec2 u) const {
  const int n = int(suns_.size());
  const int k = std::min(int(u.x * n), n - 1);
  const SunCone& c = suns_[size_t(k)];
  // Uniform in the cone, 1 - cos theta = t (1 - cos max) kept exact for a tiny cone.
  const float t = std::min(u.x * n - k, 1.0f) * c.one_minus_cos;
  const float cos_theta = 1 - t, sin_theta = std::sqrt(std::max(t * (2 - t), 0.0f));
  const float phi = 2 * kPi * u.y;
  return Frame(c.dir).to_world(Vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta));
}

float World::sun_pdf(const Vec3& wi) const {
  float pdf = 0;
  for (const SunCone& c : suns_)
    if (0.5f * length_squared(wi - c.dir) <= c.one_minus_cos) pdf += 1 / (2 * kPi * c.one_minus_cos);
  return pdf / float(suns_.size());
}

float world_pdf(const World& w, const Vec3& wi) {
  if (!w.has_map()) return uniform_sphere_pdf();
  const float sin_theta = std::sqrt(wi.x * wi.x + wi.y * wi.y) / length(wi);  // exact near the poles
  const float map = sin_theta > 0 ? w.map_pdf(direction_to_equirectangular(wi)) / (2 * kPi * kPi * sin_theta) : 0.0f;
  const float q = w.sun_probability();
  return q > 0 ? (1 - q) * map + q * w.sun_pdf(normalize(wi)) : map;
}

bool world_sample_emission(const World& w, const Vec3& center, float radius, Vec2 up, Vec2 ud, EmissionSample* e) {
  LightSample ls;
  if (!world_sample(w, ud, &ls)) return false;
  Vec3 dir = -ls.wi;  // direction light travels
  e->pdf_dir = ls.pdf;
  e->radiance = ls.radiance;
  emit_from_scene_disk(dir, center, radius, up, e);
  return e->pdf_dir > 0 && !is_black(e->radiance);
}

}  // namespace lt
