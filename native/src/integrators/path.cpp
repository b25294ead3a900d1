// Unidirectional path tracing with next-event estimation and multiple importance sampling (power
// heuristic; Veach 1997, ch. 9), Russian roulette on the throughput and Cycles' bounce limits; with
// kMedia, volumetric path tracing (pbrt 3, 15.3; Assignment 4 of the sheet): a volume stack,
// free-flight sampling in the media along every segment, NEE from medium vertices with the phase
// function and from surfaces with transmittance through invisible boundaries, MIS against
// phase/BSDF sampling, and Cycles' volume bounce limit (0: single scattering). One template, so a
// scene without media runs none of the media code (make_integrator picks kMedia = false for it).
// Shadow catchers as Cycles 3.4 (integrator/shadow_catcher.h, intersect_closest.h): a camera path
// (through transparent passes) that meets a catcher splits there: the path goes on as usual, its
// light before the split also filed as the matte, and a second path from the same state and the
// same random numbers sees only catchers (catcher_only_visibility; lamps, the world and catchers'
// own emission light it), its light filed apart (SampleValue::catcher); the film divides them.
#include "core/room.h"
#include "integrators/light_passes.h"
#include "integrators/media_transport.h"
#include "integrators/path_state.h"
#include "integrators/subsurface.h"

namespace lt {

namespace {

template <bool kMedia>
SampleValue trace(const Scene& scene, const Camera& camera, const IntegratorSettings& s, const CameraSample& cs,
                  Sampler& sampler, SampleStats& stats) {
  const Ray& camera_ray = cs.ray;
  const float time = camera_ray.time;  // the whole path's (motion blur)
  SampleValue out;
  out.lightgroups = cs.lightgroups;
  out.aovs = cs.aovs;
  bool aovs_done = !cs.aovs;  // Cycles' PATH_RAY_SINGLE_PASS_DONE (single_pass_done)
  const LightSet& lights = scene.lights;
  const VolumeEstimator est = s.volume_estimator;
  const float step = s.volume_step;
  Spectrum L(0.0f);
  float transparent = 0;  // of the film, 1 - alpha (Cycles accumulates it so; hold_out)
  // The path's state along its segments, in one struct so that a shadow catcher's split copies it
  // whole (below); the names bind to its members.
  struct State {
    Ray ray;
    Spectrum beta{1.0f};
    unsigned visibility = kVisCamera;
    Bounces b;
    int nulls = 0;
    // The previous scattering vertex, for MIS on emitters the sampled direction reaches.
    float prev_pdf = 0;
    bool prev_delta = true;
    float min_pdf = INFINITY;   // Cycles' min_ray_pdf: the smallest pdf of the bounces so far (Bevel)
    Vec3 prev_p, prev_n{0.0f};  // prev_n: the geometric normal there (zero in a medium)
    float t_prev = 0;           // distance from prev_p to ray.o (the ray crossed invisible boundaries)
    // Cycles' compact ray differential: the footprint grows by the camera's dD per unit of path length.
    float footprint = 0;
    VolumeStack stack;
    bool diffuse_ancestor = false;  // a diffuse bounce before: BSSRDFs are diffuse (Cycles')
  } state;
  state.ray = camera_ray;
  state.prev_p = camera_ray.o;
  state.footprint = cs.dP;
  Ray& ray = state.ray;
  Spectrum& beta = state.beta;
  unsigned& visibility = state.visibility;
  Bounces& b = state.b;
  int& nulls = state.nulls;
  float &prev_pdf = state.prev_pdf, &t_prev = state.t_prev, &footprint = state.footprint, &min_pdf = state.min_pdf;
  bool& prev_delta = state.prev_delta;
  Vec3 &prev_p = state.prev_p, &prev_n = state.prev_n;
  VolumeStack& stack = state.stack;
  if (kMedia && scene.has_boundaries()) init_volume_stack(scene, camera_ray, &stack, stats);
  Bsdf bsdf;
  // Shadow catchers: whether the path has split (Cycles' PATH_RAY_SHADOW_CATCHER_HIT), whether this
  // is the catcher-only path (PATH_RAY_SHADOW_CATCHER_PASS), and the state at the start of the
  // camera segment that met the catcher, which that path starts from.
  const bool catchers = s.shadow_catcher;
  bool split = false, catcher_leg = false;
  float matte_transparent = 0;
  struct Snapshot {
    State state;
    Sampler sampler;
  };
  Room<Snapshot> snap;  // not std::optional, whose storage GCC zero-fills (core/room.h)
  // The world the camera ray sees along `r` (Cycles' background pass, for the approximate matte).
  auto add_background = [&](const Ray& r, const Spectrum& w, unsigned vis) {
    if (catchers) out.background += w * catcher_background(scene, s, r.d, b, vis);
  };

  // Light passes (light_passes.h): the first scattering vertex's split, and at the vertex being
  // lit, the split towards the light sampled (first vertex only).
  FirstBounce first, nee_first;
  // An emitter of light group `group` reached (environment: the world) and a next-event estimate
  // from the current vertex.
  // After a split neither path writes light passes, nor the light groups of light samples (Cycles'
  // film_write_direct_light and film_write_emission_or_background_pass).
  auto add = [&](const Spectrum& c, const auto& group, bool environment = false) {  // group: int or shares
    const Spectrum v = clamp_contribution(c, b.total == 0 ? s.clamp_direct : s.clamp_indirect);
    if (catcher_leg) {
      out.catcher += v;
      return;
    }
    L += v;
    if (catchers && !split) out.matte += v;
    out.add_lightgroup(group, v);
    if (s.light_passes && !split) add_light_part(out.light, v, b.total, first, environment);
  };
  auto add_nee = [&](const Spectrum& c, int group) {
    const Spectrum v = clamp_contribution(c, b.total == 0 ? s.clamp_direct : s.clamp_indirect);
    if (catcher_leg) {
      out.catcher += v;
      return;
    }
    L += v;
    if (split) return;
    if (catchers) out.matte += v;
    out.add_lightgroup(group, v);
    if (s.light_passes) add_light_part(out.light, v, b.total + 1, b.total == 0 ? nee_first : first, false);
  };
  auto mis_emitter = [&](int light, const Vec3& dir, float t) {
    if (prev_delta) return 1.0f;
    float light_pdf = lights.pmf_nee(prev_p, prev_n, light) * lights.pdf(scene, light, prev_p, dir, t, time);
    return power_heuristic(prev_pdf, light_pdf);
  };
  // NEE from p (a medium point when sp is null): one light picked by the light tree at p, MIS-weighted
  // against the scattering; f(wi, &pdf, excluded, offset) returns the BSDF x cos or phase value. `st` is the volume
  // stack on the side the path arrived from, whose geometric normal is `side`: a shadow ray leaving through the surface
  // crosses it (one on that side must not enter the surface's medium again). n: the shading normal facing the ray there
  // (the shadow terminator offset reads it).
  auto next_event = [&](const Vec3& p, const SurfacePoint* sp, const Vec3& side, const Vec3& n, const VolumeStack& st,
                        auto f) {
    float pmf;
    int li = lights.pick_nee(p, sp ? side : Vec3(0.0f), sampler.next_1d(), &pmf);
    Vec2 u = sampler.next_2d();
    LightSample ls;
    if (li < 0 || !(pmf > 0) || !lights.sample(scene, li, p, u, &ls, time) || !(ls.pdf > 0) || is_black(ls.radiance))
      return;
    // The catcher-only path leaves out the emission of other objects (Cycles' light_distribution_sample).
    if (catcher_leg && !lights_catchers(scene, li)) return;
    const unsigned shadow_vis = catcher_leg ? catcher_only_visibility(kVisShadow) : kVisShadow;
    bool offset = false;  // the shadow terminator offset moved the origin (Geometry::shadow_origin)
    const Vec3 origin = sp ? scene.geometry.shadow_origin(*sp, n, side, ls.wi, &offset) : p;
    float scatter_pdf;
    Spectrum fv = f(ls.wi, &scatter_pdf, excluded_kinds(scene.light_visibility(li)), offset);
    if (is_black(fv)) return;
    Ray shadow = shadow_ray(origin, ls, time);
    if (sp) skip_self(*sp, &shadow);
    Spectrum T(1.0f);
    if constexpr (kMedia) {
      VolumeStack shadow_stack = st;
      if (sp) leave_surface(scene, *sp, side, ls.wi, &shadow_stack);
      T = shadow_transmittance(scene, shadow_stack, shadow, sampler, est, step, stats, s.transparent_bounces,
                               shadow_vis);
    } else {
      T = shadow_transmittance(scene, VolumeStack{}, shadow, sampler, est, step, stats, s.transparent_bounces,
                               shadow_vis);
    }
    if (is_black(T)) return;
    float light_pdf = pmf * ls.pdf;
    float w = ls.delta ? 1.0f : power_heuristic(light_pdf, scatter_pdf);
    add_nee(beta * fv * T * ls.radiance * (w / light_pdf), lights.lightgroup(li));
  };

  for (;;) {
    for (;;) {
      Hit hit;
      ++stats.rays;
      // Only a scene with catchers keeps the state of each camera segment, for a split.
      if (catchers && !split && b.total == 0) snap.make(Snapshot{state, sampler});
      bool found = scene.geometry.intersect(ray, catcher_leg ? catcher_only_visibility(visibility) : visibility, &hit);
      const float t_end = found ? hit.t : ray.tmax;
      // Cycles' integrator_split_shadow_catcher: before the segment's volume and the surface are
      // shaded; the throughput there is the matte's transparency (film_write_shadow_catcher_bounce_data).
      if (catchers && !split && found && b.total == 0) {
        const Instance& hit_instance = scene.geometry.instance(hit.instance);
        if (hit_instance.shadow_catcher && !hit_instance.holdout) {
          split = true;
          out.catcher_split = 1;
          matte_transparent = transparent + average(beta);
          add_background(ray, beta, visibility);
        }
      }

      // Free flight through the media along [tmin, t_end]. A ray that escapes (even a camera ray cut
      // by the clip distance) crosses the media to infinity, as in Cycles 3.4: a World volume with
      // sigma_t > 0 hides the background completely (docs/volumes.md).
      const Spectrum beta_before = beta;
      MediumInteraction mi;
      int medium = -1;
      // Volume emission along the whole segment (closed form; before the free flight decides where
      // the path goes on, as Cycles 3.4 does).
      if (kMedia && scene.has_emissive_media()) {
        LightgroupShares groups;
        const Spectrum le = media_emission(scene, stack, ray, ray.tmin, found ? hit.t : INFINITY, sampler, est, step,
                                           out.lightgroups ? &groups : nullptr);
        if (!is_black(le)) add(beta * le, groups);
      }
      if constexpr (kMedia)
        medium = sample_media(scene, stack, ray, ray.tmin, found ? hit.t : INFINITY, sampler, est, step, &beta, &mi);
      const float t_seg = medium >= 0 ? std::min(mi.t, t_end) : t_end;
      // Lamps with a size are hit by rays but never occlude (as in Cycles); weighted as the segment
      // before the collision (exact for grey media).
      if (lights.has_hittable()) {
        Ray r = ray;
        r.tmax = t_seg;
        lights.intersect_lamps(r, prev_p, visibility, [&](const LightSet::LampHit& h) {
          add((medium >= 0 ? beta_before : beta) * h.radiance * mis_emitter(h.light, ray.d, t_prev + h.t),
              lights.lightgroup(h.light));
        });
      }
      if (kMedia && !is_finite(beta)) break;  // free-flight weights

      if (medium >= 0) {
        // A real collision: beta already holds sigma_s T / pdf (medium.h). Past any limit (a
        // diffuse one too) the path ends here without light, as at a surface (Cycles' volume
        // shading of a path marked to terminate has no closures and samples no light: the ray only
        // attenuates, which ending at a free-flight collision equals in expectation).
        if (is_black(beta) || b.exceeded(s)) break;
        const Phase& phase = scene.media[medium].phase();
        const Vec3 wo = normalize(-ray.d);
        if (b.total == 0) nee_first.set_volume();
        if (lights.pickable())
          next_event(mi.p, nullptr, Vec3(0.0f), Vec3(0.0f), stack, [&](const Vec3& wi, float* pdf, unsigned, bool) {
            float p = phase.eval(wo, wi);
            *pdf = p;
            return Spectrum(p);
          });
        Vec3 wi;
        float pdf;
        if (!phase.sample(wo, sampler.next_2d(), &wi, &pdf) || !(pdf > 0)) break;
        if (b.total == 0) first.set_volume();
        b.add(BounceKind::Volume);
        visibility = kVisDiffuse;
        prev_pdf = pdf;
        prev_delta = false;
        min_pdf = std::min(min_pdf, pdf);
        prev_p = mi.p;
        prev_n = Vec3(0.0f);
        t_prev = 0;
        start_at(mi.p, &ray);
        ray.d = wi;
        ray.tmin = 0;
        ray.tmax = INFINITY;
      } else if (!found) {
        bool background = b.from_camera();
        // Film > Transparent: the camera ray, through transparent passes too, ends transparent.
        const bool transparent_background = b.total == 0 && s.transparent_background;
        if (transparent_background && !catcher_leg) transparent += average(beta);
        if (b.total == 0 && !split) add_background(ray, beta, visibility);
        if (!transparent_background) {
          if (lights.world_light() >= 0 && (!background || scene.world.camera_visible)) {
            const Spectrum le = scene.world.escaped_radiance(ray.d, [&](ShadingContext* wc) {
              describe_ray(b, visibility, wc);
              // The World's AOV Outputs write where a camera ray escapes (Cycles' background shader
              // with PATH_RAY_TRANSPARENT_BACKGROUND, not PATH_RAY_SINGLE_PASS_DONE).
              if (b.total == 0 && !aovs_done && !catcher_leg) write_aovs_at(wc, cs.aovs, s);
            });
            add(beta * le * mis_emitter(lights.world_light(), ray.d, INFINITY), lights.lightgroup(lights.world_light()),
                true);
          }
          lights.escaped_suns(ray.d, visibility, [&](int i, const Spectrum& radiance) {
            add(beta * radiance * mis_emitter(i, ray.d, INFINITY), lights.lightgroup(i));
          });
        }
        break;
      } else {
        SurfacePoint sp = scene.geometry.surface(hit);
        if (kMedia && scene.null_surface(sp.material)) {
          // An invisible medium boundary: update the stack and continue along the same line.
          if (!pass_boundary(scene, sp, hit.t, &ray, &stack, &nulls)) break;
          t_prev += hit.t * length(ray.d);
          continue;
        }
        ShadingContext ctx = shading_context(scene.geometry, sp, ray.d, (hit.t - ray.tmin) * length(ray.d));
        describe_ray(b, visibility, &ctx);
        if (b.total == 0 && !aovs_done && !catcher_leg) write_aovs_at(&ctx, cs.aovs, s);
        const float footprint_here = footprint + ctx.ray_length * cs.dD;
        Vec3 ng = ctx.Ng;
        ShadingFrame sf{ctx.N};
        const Material& material = scene.material(sp.material);
        if (material.needs_differentials()) add_differentials(scene.geometry, sp, footprint_here, &ctx);
        if (material.traces_rays()) add_tracing(scene.geometry, sp, min_pdf, sampler, &ctx);
        ctx.subsurface = !state.diffuse_ancestor;
        Spectrum emitted = material.evaluate(ctx, scene.images, &bsdf, &sf);
        if (b.total == 0 && !aovs_done && !catcher_leg)
          aovs_done = single_pass_done(material.may_be_transparent(), bsdf, s.pass_alpha_threshold);
        if (b.total == 0 && !catcher_leg &&
            !hold_out(scene.geometry.instance(sp.instance).holdout, &bsdf, &emitted, beta, &transparent))
          break;
        bsdf.sample_below_shading(true);
        bsdf.set_terminator_frequency(scene.geometry.instance(sp.instance).terminator_frequency);
        if (!is_black(sf.smooth)) ctx.N = sf.smooth;  // a displacement's bump (Cycles' SetNormal)
        Frame frame = local_frame(sf, ng);
        const Vec3 ns = frame.n;
        if (length_squared(ns - facing_normal(ctx.N, ng)) > 0) bsdf.set_bump(frame.to_local(ctx.N), false);
        if (b.from_camera() && !catcher_leg) {
          out.depth = hit.t;  // distance along the camera ray; the caller converts it to Z depth
        }
        if (!is_black(emitted)) {
          int li = lights.triangle_light(sp.instance, sp.primitive);
          add(beta * emitted *
                  (li >= 0 ? mis_emitter(li, ray.d, kMedia || t_prev > 0 ? t_prev + hit.t * length(ray.d) : hit.t)
                           : 1.0f),
              scene.geometry.instance(sp.instance).lightgroup);
        }
        // A transparent pass continues the line as an invisible boundary does: the MIS state stays
        // the last scattering's (as Cycles' transparent bounces), which shadow rays see through.
        if (material.may_be_transparent() && bsdf.pass_transparent(sampler.next_1d(), &beta, b.from_camera())) {
          b.add(BounceKind::None);
          if (b.of(BounceKind::None) > s.transparent_bounces || !pass_boundary(scene, sp, hit.t, &ray, &stack, &nulls))
            break;
          t_prev += hit.t * length(ray.d);
          footprint = footprint_here;
          continue;
        }
        if (b.from_camera() && !catcher_leg) {
          out.normal = ns;
          out.albedo = bsdf.albedo();
        }
        Vec3 wo = frame.to_local(-ray.d);
        // Colours and data passes at the surface a camera path first scatters from (Cycles writes
        // them at every surface before the first bounce, transparent layers weighted by their
        // opacity; the choice to pass a layer above has that expectation).
        if (b.total == 0 && !catcher_leg) {
          if (s.light_passes) add_light_colors(&out, bsdf, wo, beta);
          if (s.data_passes) write_data_passes(scene, camera, s, sp, beta, &out);
          if (s.ao_pass)
            out.ao = beta * ambient_occlusion(scene, s, sp, ns, ng, kMedia ? &stack : nullptr, sampler, stats);
          if (s.vector_pass && motion_vector(scene, camera, sp, out.vector)) out.vector_weight = 1;
        }
        if (bsdf.count() == 0) break;
        if (b.exceeded(s)) break;
        // Russian roulette at a surface the path reached, after its emission, as Cycles 3.4 places
        // it (integrator_intersect_terminate; shade_surface divides by q after the emission): what
        // a sampled direction finds (the world, an emitter) is never thinned by the roulette, only
        // what the path gathers from here on. Under a white world that cut the error per sample by
        // 1.6x (bench/README.md). From the fourth bounce's vertex (Cycles: the second; there the
        // roulette thinned the second vertex's next-event estimate, +17 % error on the Cornell box,
        // and from the third it cost more in error than it saved in time: kPathRouletteBounce).
        if (!russian_roulette(b.total, kPathRouletteBounce, &beta, sampler)) break;

        // Once more from a subsurface walk's exit point (Cycles shades it with the exit lobe alone).
        bool alive = true;
        for (;;) {
          if (bsdf.has_non_delta() && lights.pickable())
            next_event(sp.p, &sp, ng, ctx.N, stack,
                       [&](const Vec3& wi_world, float* pdf, unsigned excluded, bool offset) {
                         Vec3 wi = frame.to_local(wi_world);
                         Spectrum f = bsdf.eval(wo, wi, pdf, excluded);
                         // The geometric normal decides which side the light is on; shading normals only shade
                         // (but for a shadow terminator offset, whose shadow ray decides).
                         if (!offset && (dot(wi_world, ng) > 0) != (wi.z > 0)) return Spectrum(0.0f);
                         if (s.light_passes && b.total == 0) {
                           Spectrum kinds[3];
                           bsdf.eval_kinds(wo, wi, kinds);
                           for (int k = 0; k < 3; ++k)
                             if (excluded & (1u << k)) kinds[k] = Spectrum(0.0f);
                           nee_first.set_surface(kinds);
                         }
                         return f * std::abs(wi.z);
                       });

          // Continue the path by sampling the BSDF.
          BsdfSample bs;
          float u_lobe = sampler.next_1d();
          Vec2 u = sampler.next_2d();
          alive = false;
          if (!bsdf.sample(wo, u_lobe, u, &bs) || !(bs.pdf > 0) || is_black(bs.f)) break;
          if (bs.flags & kLobeSubsurface) {
            // Cycles' subsurface_bounce and subsurface_scatter: no bounce counted; the exit point
            // is lit and scatters as a diffuse of weight 1, with no emission and no shader run
            // (but for its closure's normal where the program sets one: SD_HAS_BSSRDF_BUMP).
            if (s.light_passes && b.total == 0) first.set_kind(PassKind::Diffuse);
            beta *= bs.f / bs.pdf;
            const Lobe bssrdf = bsdf.lobe(bs.lobe);
            SubsurfaceExit exit;
            if (!subsurface_scatter(scene.geometry, sp, frame.n, ng, ctx.backfacing, bssrdf, time, sampler, &beta,
                                    &exit))
              break;
            sp = exit.sp;
            ctx = shading_context(scene.geometry, sp, -exit.wo, 0);
            ng = ctx.Ng;
            ShadingFrame exit_frame{ctx.N};
            const Material& exit_material = scene.material(sp.material);
            if (exit_material.program().sets_normal()) {
              ctx.subsurface = true;
              exit_material.evaluate(ctx, scene.images, &bsdf, &exit_frame);
            }
            bsdf.clear();
            bsdf.add(subsurface_exit_lobe(bssrdf));
            bsdf.set_terminator_frequency(scene.geometry.instance(sp.instance).terminator_frequency);
            frame = Frame(facing_normal(exit_frame.n, ng));
            if (length_squared(frame.n - facing_normal(ctx.N, ng)) > 0) bsdf.set_bump(frame.to_local(ctx.N), false);
            wo = frame.to_local(exit.wo);
            alive = true;
            continue;
          }
          Vec3 wi = frame.to_world(bs.wi);
          bool reflect_geo = dot(wi, ng) > 0;
          if (reflect_geo != ((bs.flags & kLobeReflection) != 0)) break;  // shading normal would leak light
          beta *= bs.f * (std::abs(bs.wi.z) / bs.pdf);
          if (!is_finite(beta)) break;
          if (s.light_passes && b.total == 0) {
            if (bs.flags & (kLobeSpecular | kLobeBelowShading)) {  // the sampled lobe's alone: eval() has none
              first.set_kind(flags_pass_kind(bs.flags));
            } else {
              Spectrum kinds[3];
              bsdf.eval_kinds(wo, bs.wi, kinds);
              first.set_surface(kinds);
            }
          }
          if (kMedia && !reflect_geo) cross_boundary(scene, sp, wi, &stack);  // refraction into / out of a medium

          b.count(bs, &visibility);
          if (bs.flags & kLobeDiffuse) state.diffuse_ancestor = true;
          prev_pdf = bs.pdf;
          prev_delta = (bs.flags & kLobeSpecular) != 0;
          if (!prev_delta) min_pdf = std::min(min_pdf, bs.pdf);
          prev_p = sp.p;
          prev_n = ng;
          t_prev = 0;
          footprint = footprint_here;
          ray.d = wi;
          leave(sp, &ray);
          ray.tmin = 0;
          ray.tmax = INFINITY;
          alive = true;
          break;
        }
        if (!alive) break;
      }

      // A medium vertex: the roulette before the ray it sampled (a surface has had its own).
      if (medium >= 0 && !russian_roulette(b.total, kPathRouletteBounce, &beta, sampler)) break;
    }
    if (!split || catcher_leg) break;
    // The catcher-only path, from the segment that met the catcher.
    catcher_leg = true;
    state = snap.get()->state;
    sampler = snap.get()->sampler;
    if constexpr (kMedia) stack = catcher_volume_stack(scene, ray, stats);
  }
  out.radiance = L;
  out.alpha = 1 - transparent;
  out.matte_transparent = split ? matte_transparent : transparent;
  return out;
}

template <bool kMedia>
class PathIntegrator final : public Integrator {
 public:
  using Integrator::Integrator;
  SampleValue trace(const CameraSample& cs, Sampler& sampler, SampleStats& stats, std::vector<Splat>&) const override {
    return lt::trace<kMedia>(ctx_.scene, ctx_.camera, ctx_.settings, cs, sampler, stats);
  }
};

}  // namespace

std::unique_ptr<Integrator> make_path_integrator(const RenderContext& ctx, bool media) {
  if (media) return std::make_unique<PathIntegrator<true>>(ctx);
  return std::make_unique<PathIntegrator<false>>(ctx);
}

}  // namespace lt
