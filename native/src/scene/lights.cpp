#include "scene/lights.h"

#include <algorithm>

#include "scene/scene.h"

namespace lt {

namespace {

// Cycles' spot_attenuation: the cone edge is smoothed over (1 - cos(half)) * blend, and the
// intensity keeps an extra cos of the angle to the axis.
float spot_attenuation(const Light& l, const Vec3& from_light) {
  if (l.type != LightType::Spot) return 1.0f;
  float c = dot(from_light, l.direction);
  if (c <= l.cos_half_angle) return 0.0f;
  float t = c - l.cos_half_angle;
  if (l.smooth > 0 && t < l.smooth) {
    float x = t / l.smooth;
    c *= x * x * (3 - 2 * x);
  }
  return c;
}

// A point on an area light, uniform by area (rectangle: u over [-1, 1]^2 of the half axes).
Vec3 sample_area_point(const Light& l, Vec2 u) {
  if (l.shape == AreaShape::Rectangle) return l.position + l.axis_u * (2 * u.x - 1) + l.axis_v * (2 * u.y - 1);
  Vec2 d = sample_disk_concentric(u);
  return l.position + l.axis_u * d.x + l.axis_v * d.y;
}

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

Spectrum LightSet::sun_radiance(const Light& l) const {
  if (l.tan_half_angle == 0) return l.power;
  return l.power * (1.0f / (kPi * l.tan_half_angle * l.tan_half_angle));
}

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
      case LightType::Sun: p *= kPi * scene_radius_ * scene_radius_; break;
      case LightType::World: {
        float mean = average(world->color);
        if (world->image) mean *= world->image_mean;
        p = mean * 4 * kPi * kPi * scene_radius_ * scene_radius_;
        world_light_ = int(i);
        break;
      }
      case LightType::Triangle:
        triangle_index_.push_back({(uint64_t(uint32_t(l.instance)) << 32) | uint32_t(l.primitive), int(i)});
        break;
      default: break;
    }
    if (l.type == LightType::Area || ((l.type == LightType::Point || l.type == LightType::Spot) && l.radius > 0))
      hittable_.push_back(int(i));
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
    case LightType::Spot: {
      // Cycles 3.4: intensity P / (4 pi); with a radius, a disk of radiance P / (4 pi^2 r^2)
      // facing the shaded point, sampled by area.
      Vec3 q = l.position, n;
      if (l.radius > 0) {
        n = normalize(p - l.position);
        Frame f(n);
        Vec2 d = sample_disk_concentric(u);
        q = l.position + f.to_world(Vec3(d.x * l.radius, d.y * l.radius, 0));
      }
      Vec3 to = q - p;
      float d2 = length_squared(to);
      if (!(d2 > 0)) return false;
      s->distance = std::sqrt(d2);
      s->wi = to / s->distance;
      s->p = q;
      s->n = Vec3(0.0f);  // the disk faces each receiver: no surface of the scene
      float atten = spot_attenuation(l, -s->wi);
      if (atten == 0) return false;
      if (l.radius > 0) {
        float cos_l = dot(n, -s->wi);
        if (cos_l <= 0) return false;
        s->pdf = d2 / (kPi * l.radius * l.radius * cos_l);
        s->radiance = l.power * (atten / (4 * kPi * kPi * l.radius * l.radius));
        s->delta = false;
      } else {
        s->pdf = 1;
        s->radiance = l.power * (atten * kInv4Pi / d2);
        s->delta = true;
      }
      return true;
    }
    case LightType::Area: {
      // Cycles 3.4: one-sided, radiance P / (4 A); sampled uniformly by area.
      Vec3 q = sample_area_point(l, u);
      Vec3 to = q - p;
      float d2 = length_squared(to);
      if (!(d2 > 0)) return false;
      s->distance = std::sqrt(d2);
      s->wi = to / s->distance;
      s->p = q;
      s->n = l.direction;
      float cos_l = dot(l.direction, -s->wi);
      if (cos_l <= 0) return false;
      s->pdf = d2 / (l.area * cos_l);
      s->radiance = l.power * (0.25f / l.area);
      s->delta = false;
      return true;
    }
    case LightType::Sun: {
      s->distance = INFINITY;
      if (l.tan_half_angle == 0) {
        s->wi = -l.direction;
        s->pdf = 1;
        s->radiance = l.power;
        s->delta = true;
        return true;
      }
      // Cycles 3.4: a disk of radius tan(angle / 2) at unit distance, sampled by area.
      Frame f(-l.direction);
      Vec2 d = sample_disk_concentric(u);
      s->wi = normalize(f.to_world(Vec3(d.x * l.tan_half_angle, d.y * l.tan_half_angle, 1)));
      float c = dot(s->wi, -l.direction);
      s->pdf = 1 / (kPi * l.tan_half_angle * l.tan_half_angle * c * c * c);
      s->radiance = sun_radiance(l);
      s->delta = false;
      return true;
    }
    case LightType::Triangle: {
      Vec3 p0, p1, p2;
      scene.geometry.triangle(l.instance, l.primitive, &p0, &p1, &p2);
      Vec2 b = sample_triangle(u);
      Vec3 q = p0 * (1 - b.x - b.y) + p1 * b.x + p2 * b.y;
      Vec3 to = q - p;
      float d2 = length_squared(to);
      if (!(d2 > 0)) return false;
      s->distance = std::sqrt(d2);
      s->wi = to / s->distance;
      Vec3 ng = normalize(cross(p1 - p0, p2 - p0));
      float cos_l = std::abs(dot(ng, s->wi));
      if (!(cos_l > 0)) return false;
      s->pdf = d2 / (l.area * cos_l);
      s->p = q;
      s->n = ng;
      Hit h;
      h.instance = l.instance;
      h.primitive = l.primitive;
      h.u = b.x;
      h.v = b.y;
      SurfacePoint sp = scene.geometry.surface(h);
      s->radiance = scene.material(sp.material).emission(scene.images, sp.uv);
      s->delta = false;
      return !is_black(s->radiance);
    }
    case LightType::World: {
      const World& w = scene.world;
      s->distance = INFINITY;
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
  }
  return false;
}

float LightSet::pdf(const Scene& scene, int i, const Vec3& p, const Vec3& wi, float t) const {
  const Light& l = lights_[i];
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot: {
      if (l.radius == 0) return 0;
      Vec3 n = normalize(p - l.position);
      float cos_l = dot(n, -wi);
      return cos_l > 0 ? t * t / (kPi * l.radius * l.radius * cos_l) : 0;
    }
    case LightType::Area: {
      float cos_l = dot(l.direction, -wi);
      return cos_l > 0 ? t * t / (l.area * cos_l) : 0;
    }
    case LightType::Sun: {
      if (l.tan_half_angle == 0) return 0;
      float c = dot(wi, -l.direction);
      if (c <= l.cos_half_angle_sun) return 0;
      return 1 / (kPi * l.tan_half_angle * l.tan_half_angle * c * c * c);
    }
    case LightType::Triangle: {
      Vec3 p0, p1, p2;
      scene.geometry.triangle(l.instance, l.primitive, &p0, &p1, &p2);
      Vec3 ng = normalize(cross(p1 - p0, p2 - p0));
      float cos_l = std::abs(dot(ng, wi));
      return cos_l > 0 ? t * t / (l.area * cos_l) : 0;
    }
    case LightType::World: {
      const World& w = scene.world;
      if (!w.image) return uniform_sphere_pdf();
      Vec3 tex_dir = rotate_z(wi, w.rotation_z);
      Vec2 uv = direction_to_equirect(tex_dir);
      float sin_theta = std::sqrt(tex_dir.x * tex_dir.x + tex_dir.y * tex_dir.y);  // exact near the poles
      if (!(sin_theta > 0)) return 0;
      return w.distribution.pdf(uv) / (2 * kPi * kPi * sin_theta);
    }
  }
  return 0;
}

bool LightSet::sample_emission(const Scene& scene, int i, Vec2 up, Vec2 ud, EmissionSample* e) const {
  const Light& l = lights_[i];
  e->delta_pos = e->delta_dir = false;
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot: {
      Vec3 dir;
      if (l.type == LightType::Spot) {
        // Directions inside the cone only: outside it the spot emits nothing.
        dir = Frame(l.direction).to_world(sample_uniform_cone(ud, l.cos_half_angle));
        e->pdf_dir = uniform_cone_pdf(l.cos_half_angle);
      } else {
        dir = sample_uniform_sphere(ud);
        e->pdf_dir = uniform_sphere_pdf();
      }
      if (l.faces_receiver()) return false;  // see Light::faces_receiver
      e->ray.o = l.position;
      e->ray.d = dir;
      e->n = Vec3(0.0f);
      e->pdf_pos = 1;
      e->delta_pos = true;
      e->radiance = l.power * (spot_attenuation(l, dir) * kInv4Pi);
      return !is_black(e->radiance);
    }
    case LightType::Area: {
      Vec3 q = sample_area_point(l, up);
      Vec3 local = sample_cosine_hemisphere(ud);
      e->ray.o = q;
      e->ray.d = Frame(l.direction).to_world(local);
      e->n = l.direction;
      e->pdf_pos = 1 / l.area;
      e->pdf_dir = cosine_hemisphere_pdf(local.z);
      e->radiance = l.power * (0.25f / l.area);
      return e->pdf_dir > 0;
    }
    case LightType::Triangle: {
      Vec3 p0, p1, p2;
      scene.geometry.triangle(l.instance, l.primitive, &p0, &p1, &p2);
      Vec2 b = sample_triangle(up);
      Vec3 ng = normalize(cross(p1 - p0, p2 - p0));
      // Mesh lights emit from both sides: pick a side with the first half of u.
      float ux = ud.x < 0.5f ? 2 * ud.x : 2 * ud.x - 1;
      Vec3 n = ud.x < 0.5f ? ng : -ng;
      Vec3 local = sample_cosine_hemisphere({std::min(ux, kOneMinusEpsilon), ud.y});
      Hit h;
      h.instance = l.instance;
      h.primitive = l.primitive;
      h.u = b.x;
      h.v = b.y;
      SurfacePoint sp = scene.geometry.surface(h);
      e->ray.o = sp.p;
      e->ray.d = Frame(n).to_world(local);
      e->n = n;
      e->pdf_pos = 1 / l.area;
      e->pdf_dir = 0.5f * cosine_hemisphere_pdf(local.z);
      e->radiance = scene.material(sp.material).emission(scene.images, sp.uv);
      return e->pdf_dir > 0 && !is_black(e->radiance);
    }
    case LightType::Sun:
    case LightType::World: {
      Vec3 dir;  // direction light travels
      if (l.type == LightType::Sun) {
        if (l.tan_half_angle == 0) {
          dir = l.direction;
          e->pdf_dir = 1;
          e->delta_dir = true;
          e->radiance = l.power;
        } else {
          LightSample ls;
          sample(scene, i, Vec3(0.0f), ud, &ls);
          dir = -ls.wi;
          e->pdf_dir = ls.pdf;
          e->radiance = ls.radiance;
        }
      } else {
        LightSample ls;
        if (!sample(scene, i, Vec3(0.0f), ud, &ls)) return false;
        dir = -ls.wi;
        e->pdf_dir = ls.pdf;
        e->radiance = ls.radiance;
      }
      Frame f(dir);
      Vec2 d = sample_disk_concentric(up);
      e->ray.o = scene_center_ + (f.to_world(Vec3(d.x, d.y, 0)) - dir) * scene_radius_;
      e->ray.d = dir;
      e->n = dir;
      e->pdf_pos = 1 / (kPi * scene_radius_ * scene_radius_);
      return e->pdf_dir > 0 && !is_black(e->radiance);
    }
  }
  return false;
}

void LightSet::pdf_emission(const Scene& scene, int i, const Vec3& origin, const Vec3& n, const Vec3& dir,
                            float* pdf_pos, float* pdf_dir) const {
  const Light& l = lights_[i];
  *pdf_pos = *pdf_dir = 0;
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot:
      *pdf_pos = l.radius > 0 ? 1 / (kPi * l.radius * l.radius) : 1;
      if (l.type == LightType::Spot)
        *pdf_dir = dot(dir, l.direction) > l.cos_half_angle ? uniform_cone_pdf(l.cos_half_angle) : 0;
      else
        *pdf_dir = uniform_sphere_pdf();
      return;
    case LightType::Area:
      *pdf_pos = 1 / l.area;
      *pdf_dir = cosine_hemisphere_pdf(dot(dir, l.direction));
      return;
    case LightType::Triangle:
      *pdf_pos = 1 / l.area;
      *pdf_dir = 0.5f * std::abs(dot(dir, n)) * kInvPi;
      return;
    case LightType::Sun:
    case LightType::World:
      *pdf_pos = 1 / (kPi * scene_radius_ * scene_radius_);
      *pdf_dir = pdf(scene, i, origin, -dir, INFINITY);
      return;
  }
}

Spectrum LightSet::emitted(const Scene& scene, int i, const Vec3& origin, const Vec3& n, const Vec3& dir) const {
  const Light& l = lights_[i];
  switch (l.type) {
    case LightType::Point:
    case LightType::Spot: {
      float atten = spot_attenuation(l, dir);
      if (l.radius > 0) return l.power * (atten / (4 * kPi * kPi * l.radius * l.radius));
      return l.power * (atten * kInv4Pi);
    }
    case LightType::Area:
      return dot(dir, l.direction) > 0 ? l.power * (0.25f / l.area) : Spectrum(0.0f);
    case LightType::Triangle: {
      Hit h;  // the emission is looked up at the origin's barycentrics
      Vec3 p0, p1, p2;
      scene.geometry.triangle(l.instance, l.primitive, &p0, &p1, &p2);
      Vec3 e1 = p1 - p0, e2 = p2 - p0, q = origin - p0;
      float d00 = dot(e1, e1), d01 = dot(e1, e2), d11 = dot(e2, e2), d20 = dot(q, e1), d21 = dot(q, e2);
      float den = d00 * d11 - d01 * d01;
      h.instance = l.instance;
      h.primitive = l.primitive;
      h.u = den != 0 ? (d11 * d20 - d01 * d21) / den : 0;
      h.v = den != 0 ? (d00 * d21 - d01 * d20) / den : 0;
      SurfacePoint sp = scene.geometry.surface(h);
      return scene.material(sp.material).emission(scene.images, sp.uv);
    }
    case LightType::Sun:
      return sun_radiance(l);
    case LightType::World:
      return scene.world.radiance(-dir);
  }
  return Spectrum(0.0f);
}

bool LightSet::intersect_lamp(int i, const Ray& ray, LampHit* hit) const {
  const Light& l = lights_[i];
  if (l.type == LightType::Area) {
    float denom = dot(ray.d, l.direction);
    if (denom >= 0) return false;  // one-sided: seen only from the side it lights
    float t = dot(l.position - ray.o, l.direction) / denom;
    if (!(t > ray.tmin && t < ray.tmax)) return false;
    Vec3 q = ray.o + ray.d * t - l.position;
    float a = dot(q, l.axis_u) / length_squared(l.axis_u), b = dot(q, l.axis_v) / length_squared(l.axis_v);
    bool inside = l.shape == AreaShape::Rectangle ? (std::abs(a) <= 1 && std::abs(b) <= 1) : (a * a + b * b <= 1);
    if (!inside) return false;
    hit->light = i;
    hit->t = t;
    hit->radiance = l.power * (0.25f / l.area);
    return true;
  }
  // Point and spot with a radius: the disk facing the ray's origin.
  Vec3 n = ray.o - l.position;
  float dist = length(n);
  if (!(dist > l.radius)) return false;
  n = n / dist;
  float denom = dot(ray.d, n);
  if (denom >= 0) return false;
  float t = dot(l.position - ray.o, n) / denom;
  if (!(t > ray.tmin && t < ray.tmax)) return false;
  Vec3 q = ray.o + ray.d * t - l.position;
  if (length_squared(q) > l.radius * l.radius) return false;
  float atten = spot_attenuation(l, -ray.d);
  if (atten == 0) return false;
  hit->light = i;
  hit->t = t;
  hit->radiance = l.power * (atten / (4 * kPi * kPi * l.radius * l.radius));
  return true;
}

}  // namespace lt
