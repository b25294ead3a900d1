#include "scene/lights/world.h"

namespace lt {

namespace {

// Equirectangular mapping of Blender's Environment Texture: +X at the image centre, +Z at the top.
Vec2 direction_to_equirect(const Vec3& d) {
  float u = (std::atan2(d.y, d.x) - kPi) / (-2 * kPi);
  float v = 1 - std::acos(clamp(d.z, -1.0f, 1.0f)) * kInvPi;
  return {u, v};
}
Vec3 equirect_to_direction(Vec2 uv, float* sin_theta) {
  float phi = kPi - 2 * kPi * uv.x;
  float theta = kPi * (1 - uv.y);
  *sin_theta = std::sin(theta);
  return {*sin_theta * std::cos(phi), *sin_theta * std::sin(phi), std::cos(theta)};
}
Vec3 rotate_z(const Vec3& d, float angle) {
  float c = std::cos(angle), s = std::sin(angle);
  return {c * d.x - s * d.y, s * d.x + c * d.y, d.z};
}

}  // namespace

Spectrum World::radiance(const Vec3& dir) const {
  if (!image) return color;
  return color * image->lookup(direction_to_equirect(rotate_z(dir, rotation_z)));
}

void World::build_distribution() {
  const Image& img = *image;
  std::vector<float> f(size_t(img.width()) * img.height());
  for (int y = 0; y < img.height(); ++y) {
    float sin_theta = std::sin(kPi * (y + 0.5f) / img.height());
    for (int x = 0; x < img.width(); ++x) f[size_t(y) * img.width() + x] = luminance(img.texel(x, y)) * sin_theta;
  }
  distribution = Distribution2D(f, img.width(), img.height());
  double sum = 0, weight = 0;
  for (int y = 0; y < img.height(); ++y) {
    float sin_theta = std::sin(kPi * (y + 0.5f) / img.height());
    for (int x = 0; x < img.width(); ++x) {
      sum += f[size_t(y) * img.width() + x];
      weight += sin_theta;
    }
  }
  image_mean = weight > 0 ? float(sum / weight) : 0.0f;
}

bool world_sample(const World& w, Vec2 u, LightSample* s) {
  s->distance = INFINITY;
  s->n = Vec3(0.0f);
  s->on_surface = false;
  s->delta = false;
  if (w.image) {
    float pdf_uv;
    Vec2 uv = w.distribution.sample(u, &pdf_uv);
    float sin_theta;
    Vec3 tex_dir = equirect_to_direction(uv, &sin_theta);
    if (!(sin_theta > 0) || !(pdf_uv > 0)) return false;
    s->wi = rotate_z(tex_dir, -w.rotation_z);
    s->pdf = pdf_uv / (2 * kPi * kPi * sin_theta);
  } else {
    s->wi = sample_uniform_sphere(u);
    s->pdf = uniform_sphere_pdf();
  }
  s->radiance = w.radiance(s->wi);
  return true;
}

float world_pdf(const World& w, const Vec3& wi) {
  if (!w.image) return uniform_sphere_pdf();
  Vec3 tex_dir = rotate_z(wi, w.rotation_z);
  Vec2 uv = direction_to_equirect(tex_dir);
  float sin_theta = std::sqrt(tex_dir.x * tex_dir.x + tex_dir.y * tex_dir.y);  // exact near the poles
  if (!(sin_theta > 0)) return 0;
  return w.distribution.pdf(uv) / (2 * kPi * kPi * sin_theta);
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
