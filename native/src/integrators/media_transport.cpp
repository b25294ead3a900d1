#include "integrators/media_transport.h"

#include <functional>

#include "integrators/path_state.h"

namespace lt {

namespace {

// Calls f(medium) for every non-empty medium the ray is in: the stack's, then the global ones.
template <class F>
void for_each_medium(const Scene& scene, const VolumeStack& stack, F f) {
  for (int i = 0; i < stack.size; ++i)
    if (!scene.media[stack.media[i]].empty()) f(stack.media[i]);
  if (stack.global)
    for (int m : scene.global_media) f(m);
}

}  // namespace

void init_volume_stack(const Scene& scene, const Ray& camera_ray, VolumeStack* stack, SampleStats& stats,
                       unsigned visibility) {
  stack->size = 0;
  if (!scene.may_be_inside_boundary(camera_ray.o)) return;
  Ray r = camera_ray;
  r.tmin = 0;
  r.tmax = INFINITY;
  int decided[VolumeStack::kCapacity * 4], n_decided = 0;
  for (int i = 0; i < kMaxBoundaryCrossings; ++i) {
    Hit hit;
    ++stats.rays;
    if (!scene.geometry.intersect(r, visibility, &hit)) break;
    SurfacePoint sp = scene.geometry.surface(hit);
    int m = scene.medium_of(sp.material);
    if (m >= 0) {
      bool seen = false;
      for (int k = 0; k < n_decided; ++k) seen = seen || decided[k] == m;
      if (!seen && n_decided < int(sizeof(decided) / sizeof(int))) {
        decided[n_decided++] = m;
        if (dot(r.d, sp.ng) > 0) stack->cross(m, true, scene.geometry.instance(sp.instance).lightgroup);  // from inside
      }
    }
    r.o = spawn_origin(sp, r.d);
  }
}

VolumeStack catcher_volume_stack(const Scene& scene, const Ray& ray, SampleStats& stats) {
  VolumeStack stack;
  if (scene.has_boundaries()) init_volume_stack(scene, ray, &stack, stats, catcher_only_visibility(kVisAll));
  stack.global = false;
  return stack;
}

void cross_boundary(const Scene& scene, const SurfacePoint& sp, const Vec3& dir, VolumeStack* stack) {
  int m = scene.medium_of(sp.material);
  if (m >= 0) stack->cross(m, dot(dir, sp.ng) < 0, scene.geometry.instance(sp.instance).lightgroup);
}

bool pass_boundary(const Scene& scene, const SurfacePoint& sp, float hit_t, Ray* ray, VolumeStack* stack,
                   int* crossings) {
  if (++*crossings > kMaxBoundaryCrossings) return false;
  cross_boundary(scene, sp, ray->d, stack);
  ray->o = spawn_origin(sp, ray->d);
  ray->tmax -= hit_t;
  ray->tmin = 0;
  return true;
}

void leave_surface(const Scene& scene, const SurfacePoint& sp, const Vec3& side, const Vec3& dir, VolumeStack* stack) {
  if (dot(dir, side) < 0) cross_boundary(scene, sp, dir, stack);
}

Spectrum media_transmittance(const Scene& scene, const VolumeStack& stack, const Ray& ray, float t0, float t1,
                             Sampler& sampler, VolumeEstimator est, float step) {
  Spectrum T(1.0f);
  for_each_medium(scene, stack, [&](int m) {
    if (!is_black(T)) T *= scene.media[m].transmittance(ray, t0, t1, sampler, est, step);
  });
  return T;
}

namespace {

// Adds `value` (a part of the emission estimate) to light group `group` of *g.
void add_share(LightgroupShares* g, int group, const Spectrum& value) {
  int k = 0;
  while (k < g->n && g->group[k] != group) ++k;
  if (k == g->n) {
    if (g->n == LightgroupShares::kMax) return;  // more groups on one segment than a sample holds
    g->group[g->n] = group;
    g->share[g->n++] = Spectrum(0.0f);
  }
  g->share[k] += value;
}

}  // namespace

Spectrum media_emission(const Scene& scene, const VolumeStack& stack, const Ray& ray, float t0, float t1,
                        Sampler& sampler, VolumeEstimator est, float step, LightgroupShares* groups) {
  if (groups) groups->n = 0;
  if (!(t1 > t0)) return Spectrum(0.0f);
  // The emitting media the ray is in, with the light group each one's emission belongs to.
  struct Emitter {
    int medium, group;
  };
  Emitter emitters[VolumeStack::kCapacity + 8];
  int n = 0;
  bool homogeneous_emission = false;
  auto add_emitter = [&](int m, int group) {
    if (!scene.media[m].emissive() || n == int(sizeof(emitters) / sizeof(emitters[0]))) return;
    emitters[n++] = Emitter{m, group};
    homogeneous_emission = homogeneous_emission || scene.media[m].is_homogeneous();
  };
  for (int i = 0; i < stack.size; ++i) add_emitter(stack.media[i], stack.groups[i]);
  if (stack.global)
    for (int m : scene.global_media) add_emitter(m, scene.medium_lightgroup(m));
  if (n == 0) return Spectrum(0.0f);

  Spectrum sigma(0.0f);  // extinction of the homogeneous media the ray is in
  int heterogeneous = 0;
  for_each_medium(scene, stack, [&](int i) {
    const Medium& m = scene.media[i];
    if (m.is_homogeneous())
      sigma += m.sigma_a_unit() + m.sigma_s_unit();
    else
      ++heterogeneous;
  });
  const double len = length(ray.d), d = double(t1 - t0) * len;  // d may be infinite
  Spectrum total(0.0f);

  // Homogeneous emitters: closed form over the homogeneous media (Cycles' volume_emission_integrate).
  if (homogeneous_emission) {
    Spectrum E(0.0f);
    for (int k = 0; k < n; ++k)
      if (scene.media[emitters[k].medium].is_homogeneous()) E += scene.media[emitters[k].medium].emission();
    Spectrum L(0.0f);
    for (int k = 0; k < 3; ++k) {
      if (sigma[k] > 0)
        L[k] = float(E[k] * -std::expm1(-double(sigma[k]) * d) / sigma[k]);
      else if (std::isfinite(d))
        L[k] = float(E[k] * d);  // no extinction: E d (an infinite segment without extinction adds nothing)
    }
    if (heterogeneous > 0 && !is_black(L)) {
      // Heterogeneous media too: sample s in [0, d] with pdf proportional to exp(-sbar s) (sbar
      // the channel-averaged homogeneous sigma_t; uniform if 0), and weight each channel by
      // exp(-sigma_k s) T_het(s) / pdf(s) against its closed form.
      const double sbar = (double(sigma.x) + sigma.y + sigma.z) / 3;
      const double u = sampler.next_1d();
      double s = 0, pdf = 0;
      if (sbar > 0) {
        const double norm = std::isfinite(d) ? -std::expm1(-sbar * d) : 1.0;
        s = -std::log1p(-u * norm) / sbar;
        pdf = sbar * std::exp(-sbar * s) / norm;
      } else if (std::isfinite(d)) {
        s = u * d;
        pdf = 1 / d;
      }
      L = Spectrum(0.0f);
      if (pdf > 0 && std::isfinite(s)) {
        Spectrum T_het(1.0f);
        const float ts = t0 + float(s / len);
        for_each_medium(scene, stack, [&](int i) {
          const Medium& m = scene.media[i];
          if (!m.is_homogeneous() && !is_black(T_het)) T_het *= m.transmittance(ray, t0, ts, sampler, est, step);
        });
        for (int k = 0; k < 3; ++k) L[k] = float(E[k] * std::exp(-double(sigma[k]) * s) * T_het[k] / pdf);
      }
    }
    total += L;
    if (groups && !is_black(L))
      for (int k = 0; k < n; ++k) {
        const Medium& m = scene.media[emitters[k].medium];
        if (!m.is_homogeneous()) continue;
        Spectrum part;
        for (int c = 0; c < 3; ++c) part[c] = E[c] > 0 ? L[c] * m.emission()[c] / E[c] : 0.0f;
        add_share(groups, emitters[k].group, part);
      }
  }

  // Heterogeneous emitters (Volume objects): each estimates its own emission against its own
  // transmittance, the homogeneous media's closed form and the other heterogeneous media's
  // transmittance estimated to each point it scores.
  for (int k = 0; k < n; ++k) {
    const Medium& m = scene.media[emitters[k].medium];
    if (m.is_homogeneous()) continue;
    std::function<Spectrum(float)> others = [&](float t) {
      Spectrum T(1.0f);
      for_each_medium(scene, stack, [&](int i) {
        if (i != emitters[k].medium && !scene.media[i].is_homogeneous() && !is_black(T))
          T *= scene.media[i].transmittance(ray, t0, t, sampler, est, step);
      });
      return T;
    };
    const Spectrum L =
        m.emission_integral(ray, t0, t1, sampler, est, step, sigma, heterogeneous > 1 ? &others : nullptr);
    total += L;
    if (groups && !is_black(L)) add_share(groups, emitters[k].group, L);
  }
  if (groups) {
    for (int k = 0; k < groups->n; ++k)
      for (int c = 0; c < 3; ++c)
        groups->share[k][c] = total[c] != 0 ? groups->share[k][c] / total[c] : 0.0f;  // may be negative (blackbody)
    if (groups->n == 1) groups->share[0] = Spectrum(1.0f);  // exactly the whole, the common case
  }
  return total;
}

int sample_media(const Scene& scene, const VolumeStack& stack, const Ray& ray, float t0, float t1, Sampler& sampler,
                 VolumeEstimator est, float step, Spectrum* beta, MediumInteraction* mi) {
  int winner = -1;
  float end = t1;
  Spectrum w(1.0f);
  for_each_medium(scene, stack, [&](int m) {
    MediumInteraction cur;
    if (!(end > t0)) return;
    if (scene.media[m].sample_distance(ray, t0, end, sampler, est, step, &cur)) {
      if (winner >= 0) {  // the previous collision lies beyond: it survived to cur.t
        Spectrum st = scene.media[winner].sigma_t(mi->p, ray.time);
        for (int k = 0; k < 3; ++k) w[k] *= mi->sigma_s[k] > 0 ? mi->weight[k] * st[k] / mi->sigma_s[k] : 0.0f;
      }
      winner = m;
      *mi = cur;
      end = cur.t;
    } else {
      w *= cur.weight;
    }
  });
  *beta *= winner >= 0 ? w * mi->weight : w;
  return winner;
}

Spectrum shadow_transmittance(const Scene& scene, VolumeStack stack, Ray ray, Sampler& sampler, VolumeEstimator est,
                              float step, SampleStats& stats, int max_transparent, unsigned visibility) {
  if (!scene.has_media() && !scene.has_transparent_shadows()) {
    ++stats.rays;
    return scene.geometry.occluded(ray, visibility) ? Spectrum(0.0f) : Spectrum(1.0f);
  }
  Spectrum T(1.0f);
  Bsdf bsdf;
  for (int crossings = 0, transparent = 0;;) {
    Hit hit;
    ++stats.rays;
    bool found = scene.geometry.intersect(ray, visibility, &hit);
    T *= media_transmittance(scene, stack, ray, ray.tmin, found ? hit.t : ray.tmax, sampler, est, step);
    if (!found || is_black(T)) return T;
    const int material_id = scene.geometry.material(hit);
    const bool null = scene.null_surface(material_id);
    const Material& material = scene.material(material_id);
    if (!null && !material.may_be_transparent()) return Spectrum(0.0f);  // opaque: no surface to work out
    SurfacePoint sp = scene.geometry.surface(hit);
    if (!null) {
      if (++transparent > max_transparent) return Spectrum(0.0f);
      ShadingContext ctx = shading_context(scene.geometry, sp, ray.d, hit.t);
      ctx.camera_ray = false;
      ctx.shadow_ray = true;
      if (material.needs_differentials()) add_differentials(scene.geometry, sp, 0.0f, &ctx);  // no footprint
      material.evaluate(ctx, scene.images, &bsdf, nullptr);
      T *= bsdf.transparency();
      if (is_black(T)) return T;
    }
    if (!pass_boundary(scene, sp, hit.t, &ray, &stack, &crossings)) return Spectrum(0.0f);
  }
}

}  // namespace lt
