// Unidirectional path tracing with next-event estimation and multiple importance sampling (power
// heuristic; Veach 1997, ch. 9), Russian roulette on the throughput, and Cycles' bounce limits.
#include "integrators/integrator.h"
#include "integrators/path_state.h"

namespace lt {

namespace {


}  // namespace

SampleValue trace_path(const Scene& scene, const IntegratorSettings& s, const Ray& camera_ray, Sampler& sampler,
                       SampleStats& stats) {
  SampleValue out;
  const LightSet& lights = scene.lights;
  Spectrum L(0.0f), beta(1.0f);
  Ray ray = camera_ray;
  unsigned visibility = kVisCamera;
  Bounces b;
  // The previous scattering vertex, for MIS on emitters the BSDF-sampled ray reaches.
  float prev_pdf = 0;
  bool prev_delta = true;
  Vec3 prev_p = ray.o;
  Bsdf bsdf;

  auto add = [&](const Spectrum& c) {
    L += clamp_contribution(c, b.total == 0 ? s.clamp_direct : s.clamp_indirect);
  };
  auto mis_emitter = [&](int light, const Vec3& dir, float t) {
    if (prev_delta) return 1.0f;
    float light_pdf = lights.pmf(light) * lights.pdf(scene, light, prev_p, dir, t);
    return power_heuristic(prev_pdf, light_pdf);
  };

  for (;;) {
    Hit hit;
    ++stats.rays;
    bool found = scene.geometry.intersect(ray, visibility, &hit);
    // Lamps with a size are hit by rays but never occlude (as in Cycles).
    if (lights.has_hittable()) {
      Ray r = ray;
      r.tmax = found ? hit.t : ray.tmax;
      lights.intersect_lamps(r, visibility, [&](const LightSet::LampHit& h) {
        add(beta * h.radiance * mis_emitter(h.light, ray.d, h.t));
      });
    }
    if (!found) {
      bool background = b.from_camera();
      if (!(background && s.transparent_background)) {
        if (lights.world_light() >= 0 && (!background || scene.world.camera_visible))
          add(beta * scene.world.radiance(ray.d) * mis_emitter(lights.world_light(), ray.d, INFINITY));
        lights.escaped_suns(ray.d, visibility, [&](int i, const Spectrum& radiance) {
          add(beta * radiance * mis_emitter(i, ray.d, INFINITY));
        });
      }
      if (background) out.alpha = s.transparent_background ? 0.0f : 1.0f;
      break;
    }

    SurfacePoint sp = scene.geometry.surface(hit);
    const bool backface = dot(ray.d, sp.ng) > 0;
    const Vec3 ng = backface ? -sp.ng : sp.ng, ns = backface ? -sp.ns : sp.ns;
    const Material& material = scene.material(sp.material);
    Spectrum emitted = material.evaluate(scene.images, sp.uv, backface, &bsdf);
    if (b.from_camera()) {
      out.alpha = 1;
      out.depth = hit.t;  // distance along the camera ray; the caller converts it to Z depth
    }
    if (!is_black(emitted)) {
      int li = lights.triangle_light(sp.instance, sp.primitive);
      add(beta * emitted * (li >= 0 ? mis_emitter(li, ray.d, hit.t) : 1.0f));
    }
    if (b.from_camera()) {
      out.normal = ns;
      out.albedo = bsdf.albedo();
    }
    if (bsdf.count() == 0) break;
    if (b.exceeded(s)) break;

    const Frame frame(ns);
    const Vec3 wo = frame.to_local(-ray.d);

    // Next-event estimation: one light picked by power, MIS-weighted against BSDF sampling.
    if (bsdf.has_non_delta() && !lights.empty()) {
      float pmf, u_light;
      int li = lights.pick(sampler.next_1d(), &pmf, &u_light);
      Vec2 u = sampler.next_2d();
      LightSample ls;
      if (pmf > 0 && lights.sample(scene, li, sp.p, u, &ls) && ls.pdf > 0 && !is_black(ls.radiance)) {
        Vec3 wi = frame.to_local(ls.wi);
        float bsdf_pdf;
        Spectrum f = bsdf.eval(wo, wi, &bsdf_pdf);
        // The geometric normal decides which side the light is on; shading normals only shade.
        bool same_side_geo = dot(ls.wi, ng) > 0, same_side_shading = wi.z > 0;
        if (!is_black(f) && same_side_geo == same_side_shading) {
          Ray shadow;
          shadow.o = spawn_origin(sp, ls.wi);
          shadow.d = ls.wi;
          shadow.tmin = 0;
          shadow.tmax = std::isinf(ls.distance) ? INFINITY : ls.distance * (1 - 1e-4f);
          ++stats.rays;
          if (!scene.geometry.occluded(shadow)) {
            float light_pdf = pmf * ls.pdf;
            float w = ls.delta ? 1.0f : power_heuristic(light_pdf, bsdf_pdf);
            add(beta * f * ls.radiance * (std::abs(wi.z) * w / light_pdf));
          }
        }
      }
    }

    // Continue the path by sampling the BSDF.
    BsdfSample bs;
    float u_lobe = sampler.next_1d();
    Vec2 u = sampler.next_2d();
    if (!bsdf.sample(wo, u_lobe, u, &bs) || !(bs.pdf > 0) || is_black(bs.f)) break;
    Vec3 wi = frame.to_world(bs.wi);
    bool reflect_geo = dot(wi, ng) > 0;
    if (reflect_geo != ((bs.flags & kLobeReflection) != 0)) break;  // shading normal would leak light
    beta *= bs.f * (std::abs(bs.wi.z) / bs.pdf);
    if (!is_finite(beta)) break;

    b.count(bs, &visibility);
    prev_pdf = bs.pdf;
    prev_delta = (bs.flags & kLobeSpecular) != 0;
    prev_p = sp.p;
    ray.o = spawn_origin(sp, wi);
    ray.d = wi;
    ray.tmin = 0;
    ray.tmax = INFINITY;

    if (!russian_roulette(b.total, &beta, sampler)) break;
  }
  out.radiance = L;
  return out;
}

}  // namespace lt
