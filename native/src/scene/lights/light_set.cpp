#include "scene/lights/light_set.h"

#include <algorithm>

#include "scene/lights/area.h"
#include "scene/lights/point.h"
#include "scene/lights/triangle.h"

namespace lt {

void LightSet::build(std::vector<Light> lights, const World* world, const Bounds& b) {
  lights_ = std::move(lights);
  hittable_.clear();
  suns_.clear();
  triangle_index_.clear();
  world_light_ = -1;
  scene_radius_ = b.empty() ? 1.0f : std::max(1e-3f, 0.5f * length(b.hi - b.lo));
  scene_center_ = b.empty() ? Vec3(0.0f) : (b.lo + b.hi) * 0.5f;
  std::vector<float> power(lights_.size());
  for (size_t i = 0; i < lights_.size(); ++i) {
    const Light& l = lights_[i];
    // Picked by the magnitude of the power: a negative light (Blender allows negative energy, Cycles
    // renders it as negative light) is sampled as often as its positive twin, its sign kept in the
    // radiance.
    float p = average(abs(l.power));
    switch (l.type) {
      case LightType::Sun:
        p *= kPi * scene_radius_ * scene_radius_;
        break;
      case LightType::World: {
        const float mean = world->mean();
        p = mean * 4 * kPi * kPi * scene_radius_ * scene_radius_;
        world_light_ = int(i);
        break;
      }
      case LightType::Triangle:
        triangle_index_.push_back({(uint64_t(uint32_t(l.instance)) << 32) | uint32_t(l.primitive), int(i)});
        break;
      default:
        break;
    }
    if (l.hittable()) hittable_.push_back(int(i));
    if (l.type == LightType::Sun && l.tan_half_angle > 0) suns_.push_back(int(i));
    power[i] = std::isfinite(p) && p > 0 ? p : 0.0f;
  }
  std::sort(triangle_index_.begin(), triangle_index_.end());
  distribution_ = Distribution1D(power);
}

int LightSet::pick(float u, float* pmf, float* u_remapped) const {
  return distribution_.sample_discrete(u, pmf, u_remapped);
}

int LightSet::triangle_light(int instance, int primitive) const {
  uint64_t key = (uint64_t(uint32_t(instance)) << 32) | uint32_t(primitive);
  auto it = std::lower_bound(triangle_index_.begin(), triangle_index_.end(), std::make_pair(key, -1));
  return it != triangle_index_.end() && it->first == key ? it->second : -1;
}

bool LightSet::sample(const Scene& scene, int i, const Vec3& p, Vec2 u, LightSample* s) const {
  const Light& l = lights_[i];
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot:
      return point_lamp_sample(l, p, u, s);
    case LightType::Area:
      return area_lamp_sample(l, p, u, s);
    case LightType::Sun:
      return sun_sample(l, u, s);
    case LightType::Triangle:
      return triangle_light_sample(scene, l, p, u, s);
    case LightType::World:
      return world_sample(scene.world, u, s);
  }
  return false;
}

float LightSet::pdf(const Scene& scene, int i, const Vec3& p, const Vec3& wi, float t) const {
  const Light& l = lights_[i];
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot:
      return point_lamp_pdf(l, p, wi, t);
    case LightType::Area:
      return area_lamp_pdf(l, wi, t);
    case LightType::Sun:
      return sun_pdf(l, wi);
    case LightType::Triangle:
      return triangle_light_pdf(scene, l, wi, t);
    case LightType::World:
      return world_pdf(scene.world, wi);
  }
  return 0;
}

bool LightSet::sample_emission(const Scene& scene, int i, Vec2 up, Vec2 ud, EmissionSample* e) const {
  const Light& l = lights_[i];
  e->delta_pos = e->delta_dir = false;
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot:
      return point_lamp_sample_emission(l, ud, e);
    case LightType::Area:
      return area_lamp_sample_emission(l, up, ud, e);
    case LightType::Triangle:
      return triangle_light_sample_emission(scene, l, up, ud, e);
    case LightType::Sun:
      return sun_sample_emission(l, scene_center_, scene_radius_, up, ud, e);
    case LightType::World:
      return world_sample_emission(scene.world, scene_center_, scene_radius_, up, ud, e);
  }
  return false;
}

void LightSet::pdf_emission(const Scene& scene, int i, const Vec3& origin, const Vec3& n, const Vec3& dir,
                            float* pdf_pos, float* pdf_dir) const {
  const Light& l = lights_[i];
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot:
      return point_lamp_pdf_emission(l, dir, pdf_pos, pdf_dir);
    case LightType::Area:
      return area_lamp_pdf_emission(l, dir, pdf_pos, pdf_dir);
    case LightType::Triangle:
      return triangle_light_pdf_emission(l, n, dir, pdf_pos, pdf_dir);
    case LightType::Sun:
    case LightType::World:
      *pdf_pos = scene_disk_pdf(scene_radius_);
      *pdf_dir = pdf(scene, i, origin, -dir, INFINITY);
      return;
  }
  *pdf_pos = *pdf_dir = 0;
}

bool LightSet::intersect_lamp(int i, const Ray& ray, LampHit* hit) const {
  const Light& l = lights_[i];
  hit->light = i;
  return l.type == LightType::Area ? area_lamp_intersect(l, ray, hit) : point_lamp_intersect(l, ray, hit);
}

}  // namespace lt
