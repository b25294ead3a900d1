#include "scene/lights/light_set.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "scene/lights/area.h"
#include "scene/lights/point.h"
#include "scene/lights/triangle.h"

namespace lt {

namespace {

// What a bounded light can emit, for the light tree: its box, its flux as the tree weighs it
// (pbrt-v4's Light::Bounds: 4 pi I for points, L A pi for one-sided cosine emitters, twice that
// for two-sided ones) and its cones.
LightBounds bounds_of(const Light& l, const Geometry& geometry) {
  LightBounds b;
  const float power = average(abs(l.power));
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot:
      // A lamp with a radius is a disk facing the receiver: anywhere within its sphere.
      b.box.extend(l.position - Vec3(l.radius));
      b.box.extend(l.position + Vec3(l.radius));
      b.phi = power;  // intensity P / (4 pi), spots as the point they are cut from
      if (l.type == LightType::Spot) {
        // The cone of the spot (widened by a little against rounding at a hard edge).
        b.w = l.direction;
        b.cos_o = 1;
        b.cos_e = std::cos(std::min(std::acos(clamp(l.cos_half_angle, -1.0f, 1.0f)) + 1e-3f, kPi));
      } else {
        b.cos_o = -1;  // every direction
        b.cos_e = 0;
      }
      break;
    case LightType::Area:
      for (float su : {-1.0f, 1.0f})
        for (float sv : {-1.0f, 1.0f}) b.box.extend(l.position + l.axis_u * su + l.axis_v * sv);
      b.phi = power * 0.25f * kPi;  // radiance P / (4 A) over A, one-sided cosine
      b.w = l.direction;
      b.cos_o = 1;
      b.cos_e = 0;
      break;
    case LightType::Triangle: {
      Vec3 p0, p1, p2;
      geometry.triangle(l.instance, l.primitive, &p0, &p1, &p2);
      b.box.extend(p0);
      b.box.extend(p1);
      b.box.extend(p2);
      b.phi = 2 * power;  // power: the emission estimate x area x pi; both sides emit
      b.w = normalize(cross(p1 - p0, p2 - p0));
      b.cos_o = 1;
      const Instance& inst = geometry.instance(l.instance);
      const int steps = std::max(int(inst.motion.size()), geometry.mesh(inst.mesh).motion_steps);
      if (steps > 1) {
        // A moving emitter: its box over the motion steps (at and between them, by linearity
        // of each step's motion up to the rotation's arc, widened below), facing any way.
        Bounds box;
        for (int k = 0; k < steps; ++k) {
          geometry.triangle(l.instance, l.primitive, &p0, &p1, &p2, float(k) / float(steps - 1));
          for (const Vec3* q : {&p0, &p1, &p2}) box.extend(*q);
        }
        const Vec3 margin = (box.hi - box.lo) * 0.5f;
        b.box.extend(box.lo - margin);
        b.box.extend(box.hi + margin);
        b.cos_o = -1;
      }
      b.cos_e = 0;
      b.two_sided = true;
      break;
    }
    case LightType::Sun:
    case LightType::World:
      break;  // infinite: not in the tree
  }
  if (!std::isfinite(b.phi) ||
      !std::isfinite(b.box.lo.x + b.box.lo.y + b.box.lo.z + b.box.hi.x + b.box.hi.y + b.box.hi.z) ||
      !(std::isfinite(b.w.x) && std::isfinite(b.w.y) && std::isfinite(b.w.z)))
    b.phi = 0;
  return b;
}

LightSelection selection_from_environment(LightSelection s) {
  const char* e = std::getenv("LANTERN_LIGHT_SELECTION");
  if (e && std::strcmp(e, "power") == 0) return LightSelection::Power;
  if (e && std::strcmp(e, "tree") == 0) return LightSelection::Tree;
  return s;
}

}  // namespace

void LightSet::build(std::vector<Light> lights, const World* world, const Bounds& b, const Geometry* geometry) {
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
        // As Cycles (its World sampling Auto skips a world without spatial variation): a constant
        // World is never picked, only reached by escaping rays, which then weigh it 1. For a
        // constant sky BSDF sampling alone is the better estimator and saves a shadow ray a bounce.
        const float mean = world->has_map() ? world->mean() : 0.0f;
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

  // Next-event estimation: the infinite lights keep their power share, the tree gets the rest.
  tree_ = LightTree();
  infinite_ = Distribution1D();
  infinite_lights_.clear();
  infinite_slot_.assign(lights_.size(), -1);
  tree_share_ = 0;
  double total = 0, bounded = 0;
  for (size_t i = 0; i < lights_.size(); ++i) {
    total += power[i];
    if (!lights_[i].infinite()) bounded += power[i];
  }
  // Without any power to go by, the power pick is uniform; the tree has nothing to weigh.
  tree_used_ = selection_from_environment(selection_) == LightSelection::Tree && total > 0 && geometry;
  if (!tree_used_) return;
  std::vector<LightTree::Item> items;
  std::vector<float> infinite_power;
  for (size_t i = 0; i < lights_.size(); ++i) {
    if (lights_[i].infinite()) {
      infinite_slot_[i] = int(infinite_lights_.size());
      infinite_lights_.push_back(int(i));
      infinite_power.push_back(power[i]);
      continue;
    }
    if (!(power[i] > 0)) continue;  // never picked by power either
    LightTree::Item it{int(i), bounds_of(lights_[i], *geometry)};
    if (it.bounds.phi > 0) items.push_back(it);
  }
  tree_.build(std::move(items), lights_.size());
  tree_share_ = bounded == total ? 1.0f : float(bounded / total);
  if (!infinite_lights_.empty()) infinite_ = Distribution1D(infinite_power);
}

int LightSet::pick_nee(const Vec3& p, const Vec3& n, float u, float* pmf) const {
  if (!tree_used_) return pick(u, pmf, nullptr);
  if (u < tree_share_) {
    float tree_pmf;
    const int light = tree_.sample(p, n, std::min(u / tree_share_, kOneMinusEpsilon), &tree_pmf);
    *pmf = tree_share_ * tree_pmf;
    return light;
  }
  const float v = std::min((u - tree_share_) / (1 - tree_share_), kOneMinusEpsilon);
  float infinite_pmf;
  const int k = infinite_.sample_discrete(v, &infinite_pmf);
  *pmf = (1 - tree_share_) * infinite_pmf;
  return infinite_lights_[k];
}

float LightSet::pmf_nee(const Vec3& p, const Vec3& n, int light) const {
  if (!tree_used_) return pmf(light);
  const int slot = infinite_slot_[light];
  if (slot >= 0) return (1 - tree_share_) * infinite_.discrete_pmf(slot);
  return tree_share_ * tree_.pmf(p, n, light);
}

int LightSet::pick(float u, float* pmf, float* u_remapped) const {
  if (!(distribution_.integral() > 0)) return -1;  // nothing to pick (a constant World alone)
  return distribution_.sample_discrete(u, pmf, u_remapped);
}

int LightSet::triangle_light(int instance, int primitive) const {
  uint64_t key = (uint64_t(uint32_t(instance)) << 32) | uint32_t(primitive);
  auto it = std::lower_bound(triangle_index_.begin(), triangle_index_.end(), std::make_pair(key, -1));
  return it != triangle_index_.end() && it->first == key ? it->second : -1;
}

bool LightSet::sample(const Scene& scene, int i, const Vec3& p, Vec2 u, LightSample* s, float time) const {
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
      return triangle_light_sample(scene, l, p, u, time, s);
    case LightType::World:
      return world_sample(scene.world, u, s);
  }
  return false;
}

float LightSet::pdf(const Scene& scene, int i, const Vec3& p, const Vec3& wi, float t, float time) const {
  const Light& l = lights_[i];
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot:
      return point_lamp_pdf(l, p, wi, t);
    case LightType::Area:
      return area_lamp_pdf(l, p, wi, t);
    case LightType::Sun:
      return sun_pdf(l, wi);
    case LightType::Triangle:
      return triangle_light_pdf(scene, l, p, wi, t, time);
    case LightType::World:
      return world_pdf(scene.world, wi);
  }
  return 0;
}

float LightSet::nee_position_ratio(const Scene& scene, int i, const Vec3& p, const Vec3& q, float time) const {
  const Light& l = lights_[i];
  const bool rectangle = l.type == LightType::Area && l.shape == AreaShape::Rectangle;
  if (!rectangle && l.type != LightType::Triangle) return 1;
  const Vec3 d = q - p;
  const float t = length(d);
  if (!(t > 0)) return 0;
  const Vec3 wi = d / t;
  if (rectangle) return area_lamp_pdf(l, p, wi, t) * dot(l.direction, -wi) / (t * t) * l.area;
  Vec3 p0, p1, p2;
  float area;
  const Vec3 ng = triangle_light_corners(scene, l, time, &p0, &p1, &p2, &area);
  return triangle_light_pdf(scene, l, p, wi, t, time) * std::abs(dot(ng, wi)) / (t * t) * area;
}

bool LightSet::sample_emission(const Scene& scene, int i, Vec2 up, Vec2 ud, EmissionSample* e, float time) const {
  const Light& l = lights_[i];
  e->delta_pos = e->delta_dir = false;
  e->ray.time = time;
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot:
      return point_lamp_sample_emission(l, ud, e);
    case LightType::Area:
      return area_lamp_sample_emission(l, up, ud, e);
    case LightType::Triangle:
      return triangle_light_sample_emission(scene, l, up, ud, time, e);
    case LightType::Sun:
      return sun_sample_emission(l, scene_center_, scene_radius_, up, ud, e);
    case LightType::World:
      return world_sample_emission(scene.world, scene_center_, scene_radius_, up, ud, e);
  }
  return false;
}

void LightSet::pdf_emission(const Scene& scene, int i, const Vec3& origin, const Vec3& n, const Vec3& dir,
                            float* pdf_pos, float* pdf_dir, float time) const {
  const Light& l = lights_[i];
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot:
      return point_lamp_pdf_emission(l, dir, pdf_pos, pdf_dir);
    case LightType::Area:
      return area_lamp_pdf_emission(l, dir, pdf_pos, pdf_dir);
    case LightType::Triangle:
      return triangle_light_pdf_emission(scene, l, n, dir, time, pdf_pos, pdf_dir);
    case LightType::Sun:
    case LightType::World:
      *pdf_pos = scene_disk_pdf(scene_radius_);
      *pdf_dir = pdf(scene, i, origin, -dir, INFINITY);
      return;
  }
  *pdf_pos = *pdf_dir = 0;
}

bool LightSet::intersect_lamp(int i, const Ray& ray, const Vec3& from, LampHit* hit) const {
  const Light& l = lights_[i];
  hit->light = i;
  return l.type == LightType::Area ? area_lamp_intersect(l, ray, hit) : point_lamp_intersect(l, ray, from, hit);
}

}  // namespace lt
