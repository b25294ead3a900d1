// Bidirectional path tracing (Veach 1997, ch. 10; pbrt 3, section 16.3): a camera subpath and a
// light subpath per sample, every camera vertex connected with every light vertex, and all (s, t)
// strategies combined by multiple importance sampling. MIS weights are sums of products of ratios
// of neighbouring vertices' densities (pbrt's MISWeight), never products of whole-path pdfs, so
// they stay finite on paths of hundreds of vertices.
//
// Strategies: s = 0 (the camera subpath reaches an emitter: a mesh light, a lamp, the sun or the
// world, or crosses an emitting medium: volume emission, found by s = 0 only, weight 1), s = 1 (a
// fresh light sample at the camera vertex, as next-event estimation), s >= 2, and t = 1 (a light
// vertex connected to the pinhole, or to a point sampled on the lens, or for an orthographic
// camera to the point of its plane whose ray passes through it, and splatted through the pixel
// filter; not for panoramas with depth of field, which are not connectable).
//
// Media (scenes with volumes; pbrt 3, section 16.3): both walks sample free flights along every
// segment as the volumetric path tracer does and scatter at medium vertices with the phase
// function; invisible boundaries update the walks' volume stacks and make no vertex; connections
// multiply by the transmittance of their segment. The MIS densities of medium vertices hold the
// phase function's directional density only, as pbrt's: the distance densities are left out of
// every strategy alike, so the weights still sum to one (unbiased), at some cost in variance.
#include "integrators/bdpt.h"

namespace lt {

namespace {

// The bounce kind of a surface vertex: its lobes' (path_state.h), or Mixed if they differ or a
// dielectric may reflect or refract there; the path tracer's count then depends on the lobe it
// samples (kind_limit_factor).
BounceKind kind_of(const Bsdf& bsdf) {
  BounceKind kind = BounceKind::None;
  for (int k = 0; k < bsdf.count(); ++k) {
    const Lobe& l = bsdf.lobe(k);
    if (glass_reflects_and_refracts(l)) return BounceKind::Mixed;  // reflection or refraction
    BounceKind lk = bounce_kind(l, glass_only_refracts(l));
    if (k > 0 && lk != kind) return BounceKind::Mixed;
    kind = lk;
  }
  return kind;
}

BdptScratch& thread_scratch() {
  thread_local BdptScratch s;
  return s;
}

}  // namespace

Bdpt::Bdpt(const RenderContext& ctx, const CameraSample& cs, Sampler& sampler, SampleStats& stats)
    : ctx_(ctx),
      scene_(ctx.scene),
      lights_(ctx.scene.lights),
      s_(ctx.settings),
      cs_(cs),
      time_(cs.ray.time),
      sampler_(sampler),
      stats_(stats),
      scratch_(thread_scratch()),
      pixel_center_(cs.pixel_center),
      n_pixels_(float(ctx.width) * float(ctx.height)),
      media_(ctx.scene.has_media()) {}

float Bdpt::kind_limit_factor(const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera, int s,
                              int t) const {
  const int k = s + t - 1;  // x[0] the camera ... x[k] the light
  auto x = [&](int i) -> const PathVertex& { return i < t ? camera[i] : light[k - i]; };
  Bounces n;  // the vertices whose kind is certain
  // Vertices whose kind depends on the lobe: the probabilities of diffuse, glossy, transmission.
  constexpr int kMaxMixed = 64;
  float mixed[kMaxMixed][3];
  int m = 0, m_kind[3] = {0, 0, 0};
  for (int i = 1; i <= k - 2; ++i) {
    const PathVertex& v = x(i);
    if (v.type == VertexType::Medium) {
      n.add(BounceKind::Volume);
      continue;
    }
    if (v.type != VertexType::Surface) continue;
    if (v.kind != BounceKind::Mixed) {
      n.add(v.kind);
      continue;
    }
    // The walks stored the probabilities of vertices inside a subpath; the connection vertices
    // x[t-1] and x[t] scatter (by their non-delta lobes) towards the other subpath.
    float p[3];
    if (i == t - 1 || i == t) {
      if (!mixed_kind(v, x(i - 1).p, x(i + 1).p, false, p)) return 0;
    } else {
      if (v.kind_p[0] < 0) return 0;
      p[0] = v.kind_p[0], p[1] = v.kind_p[1], p[2] = v.kind_p[2];
    }
    int only = -1, nonzero = 0;
    for (int j = 0; j < 3; ++j)
      if (p[j] > 0) ++nonzero, only = j;
    if (nonzero == 0) continue;  // transparent
    if (nonzero == 1) {
      n.add(BounceKind(int(BounceKind::Diffuse) + only));
      continue;
    }
    if (m == kMaxMixed) return 0;
    for (int j = 0; j < 3; ++j) {
      mixed[m][j] = p[j];
      if (p[j] > 0) ++m_kind[j];
    }
    ++m;
  }
  if (n.kind_exceeded(s_)) return 0;
  int cap[3];  // what the mixed vertices may add to each of diffuse, glossy, transmission
  for (int j = 0; j < 3; ++j) {
    const BounceKind k = BounceKind(int(BounceKind::Diffuse) + j);
    cap[j] = Bounces::limit(s_, k) - n.of(k);
  }
  if (m == 0) return 1;
  // Probability that the mixed vertices' kinds keep within the remaining capacities: dynamic
  // programming over their counts, tracking only the kinds that could exceed their capacity.
  int dim[3], stride[3], states = 1;
  for (int j = 0; j < 3; ++j) {
    dim[j] = m_kind[j] > cap[j] ? cap[j] + 1 : 1;
    stride[j] = states;
    states *= dim[j];
  }
  if (states == 1) return 1;
  std::vector<double>& prob = scratch_.prob;
  std::vector<double>& next = scratch_.next;
  if (prob.size() < size_t(states)) {
    prob.resize(size_t(states));
    next.resize(size_t(states));
  }
  std::fill(prob.begin(), prob.begin() + states, 0.0);
  prob[0] = 1;
  for (int v = 0; v < m; ++v) {
    std::fill(next.begin(), next.begin() + states, 0.0);
    for (int st = 0; st < states; ++st) {
      if (prob[st] == 0) continue;
      for (int j = 0; j < 3; ++j) {
        if (mixed[v][j] == 0) continue;
        if (dim[j] == 1) {
          next[st] += prob[st] * mixed[v][j];
          continue;
        }
        int c = (st / stride[j]) % dim[j];
        if (c + 1 < dim[j]) next[st + stride[j]] += prob[st] * mixed[v][j];  // else past the limit
      }
    }
    std::swap(prob, next);
  }
  double sum = 0;
  for (int st = 0; st < states; ++st) sum += prob[st];
  return float(std::min(1.0, sum));
}

bool Bdpt::mixed_kind(const PathVertex& v, const Vec3& camera_side, const Vec3& light_side, bool delta,
                      float* p) const {
  const Vec3 wo_w = normalize(camera_side - v.p), wi_w = normalize(light_side - v.p);
  const bool transmit = (dot(wo_w, v.n) > 0) != (dot(wi_w, v.n) > 0);
  const Frame fr = view_frame(v, wo_w).frame;  // the path tracer's, reached from the camera side
  const Vec3 wo = fr.to_local(wo_w), wi = fr.to_local(wi_w);
  float part[kMaxLobes];
  float total = 0;
  if (delta) {
    // Only delta lobes reach this direction: each with its selection probability (Fresnel's
    // split inside a dielectric lobe does not change its kind).
    float sel[kMaxLobes];
    if (!v.bsdf.selection(wo, sel)) return false;
    for (int j = 0; j < v.bsdf.count(); ++j) {
      const uint32_t f = lobe_flags(v.bsdf.lobe(j));
      const bool can = (f & kLobeSpecular) && (f & (transmit ? kLobeTransmission : kLobeReflection));
      total += (part[j] = can ? sel[j] : 0.0f);
    }
  } else {
    total = v.bsdf.lobe_pdfs(wo, wi, part);
  }
  p[0] = p[1] = p[2] = 0;
  if (!(total > 0)) return false;
  for (int j = 0; j < v.bsdf.count(); ++j) {
    const int kind = int(bounce_kind(v.bsdf.lobe(j), transmit));
    if (kind >= int(BounceKind::Diffuse) && kind <= int(BounceKind::Transmission))
      p[kind - int(BounceKind::Diffuse)] += part[j] / total;
  }
  return true;
}

void Bdpt::add_emitters_reached(std::vector<PathVertex>& camera, int nt) {
  const std::vector<Crossed>& crossed = scratch_.crossed;
  size_t r = 0;
  for (int at = 1; at <= nt; ++at) {
    // The segment before camera[at], then that vertex.
    for (; r < crossed.size() && crossed[r].at == at; ++r) {
      const Crossed& c = crossed[r];
      pre_split_ = !split_ || r < split_->crossed;  // crossed before the segment that met a catcher
      if (c.light >= 0) {
        PathVertex& v = endpoint(VertexType::Light);
        v.light = c.light;
        v.infinite = c.infinite;
        v.vis = c.vis;
        v.p = c.p;
        v.n = c.n;
        v.beta = c.beta;
        v.pdf_fwd = c.pdf_fwd;
        emitter_reached(camera, at + 1, &v, c.le);
        continue;
      }
      // Volume emission: light that only camera subpaths find (no light subpath starts in a
      // medium, and connections never end on one), so strategy s = 0 is its only estimator and
      // takes it with MIS weight 1, within the same depth and per-kind limits as an emitter there.
      if (at - 1 > max_depth()) continue;
      const float kinds_within = kind_limit_factor(camera, camera, 0, at + 1);
      if (kinds_within > 0) add(c.le * kinds_within, 0, at + 1, c.groups);
    }
    pre_split_ = !split_;
    if (at < nt && !is_black(camera[at].le)) emitter_reached(camera, at + 1, nullptr, camera[at].le);
  }
  pre_split_ = !split_;
}

void Bdpt::emitter_reached(std::vector<PathVertex>& camera, int t, PathVertex* crossed, const Spectrum& le) {
  PathVertex& v = crossed ? *crossed : camera[t - 1];
  if (v.type == VertexType::Surface && v.light < 0) {
    // Emission no light sampler knows: s = 0 alone finds it, with no MIS partner.
    if (!is_black(le)) add(v.beta * le, 0, t, scene_.geometry.instance(v.sp.instance).lightgroup);
    return;
  }
  if (t - 2 > max_depth() || is_black(le)) return;
  Spectrum c = v.beta * le;
  if (is_black(c)) return;
  c *= kind_limit_factor(camera /*unused light*/, camera, 0, t);
  if (is_black(c)) return;
  // Strategy s = 1 would have picked this light from the vertex before (mis_weight).
  const PathVertex& before = camera[t - 2];
  v.nee_pick = nee_pick(before, v);
  add(c * mis_weight(camera /*unused light*/, camera, crossed, 0, t, pixel_center_), 0, t, lights_.lightgroup(v.light),
      v.infinite && v.light == lights_.world_light());
}

// Extends `path` from vertex 0 by sampling the BSDFs and phase functions (pbrt-v4's RandomWalk),
// with free flights through the media. It only builds the subpath: the camera walk (mode
// Radiance) records for strategy s = 0 what its rays reach, emitting surfaces in their vertices
// (PathVertex::le) and, per segment, what makes no vertex (scratch_.crossed: lamps crossed, the
// world and suns escaped to, the emission of the media along it, estimated with the walk's own
// sampler); add_emitters_reached evaluates them after the walks.
int Bdpt::random_walk(Ray ray, Spectrum beta, int max_depth, Mode mode, VolumeStack stack,
                      std::vector<PathVertex>& path, FirstSegment* first) {
  if (max_depth <= 0) return 1;
  // Densities are computed from the vertices' positions with the same pdf() the MIS weights use,
  // not from the sampled directions (rays leave from offset origins): every strategy then sees
  // exactly the same numbers and the weights sum to one.
  auto density_of = [&](int count, const PathVertex& v) {
    const PathVertex& prev = path[count - 1];
    if (prev.delta) return 0.0f;
    return pdf(prev, count >= 2 ? &path[count - 2] : nullptr, v, pixel_center_);
  };
  // The density of the vertex before prev as sampled from prev, arriving from v (the other
  // direction). Every vertex of the walk sets it; for an emitter crossed, which is none,
  // mis_weight does.
  auto reverse_density = [&](int count, const PathVertex& v) {
    if (count >= 2)
      path[count - 2].pdf_rev = path[count - 1].delta ? 0.0f : pdf(path[count - 1], &v, path[count - 2], pixel_center_);
  };
  // A light subpath's first segment is the path tracer's last, which its shadow rays trace: surfaces
  // that cast shadows stop it, and one that indirect rays do not see ends the subpath there.
  unsigned visibility = mode == Mode::Radiance ? kVisCamera : kVisShadow;
  int count = 1, bounces = 0, nulls = 0, transparent = 0;
  // Bump's ray footprint: along camera subpaths Cycles' compact differential (the camera's dP, then
  // its dD per unit of path length); a light subpath's vertex takes the one a camera ray reaching
  // it straight from the camera's centre would have (Cycles has no light paths).
  float footprint = mode == Mode::Radiance ? cs_.dP : 0.0f;
  // A camera ray's count, for the Light Path node of the world it sees (catcher_background).
  auto camera_bounces = [&] {
    Bounces b;
    b.n[int(BounceKind::None)] = transparent;
    return b;
  };
  // The catcher-only camera walk resumes the first segment where the full walk met the catcher.
  if (catcher_leg_ && mode == Mode::Radiance) {
    nulls = split_->nulls;
    transparent = split_->transparent;
    footprint = split_->footprint;
  }
  const float beta_start = max_abs_component(beta);
  // Bounce kinds counted so far towards Cycles' per-kind limits (path_state.h): the walk stops
  // where every strategy using its further vertices would fail them (kind_limit_factor 0; only
  // kinds that are certain count, Mixed ones may be any of theirs). The stop stays in the walk,
  // as its length limit does (pbrt-v4's maxDepth in RandomWalk): it is where the work on vertices
  // no strategy can use is saved, and it changes no estimate.
  Bounces kinds;
  // Cycles' min_ray_pdf along the walk (Bevel traces nothing on a path that was blurry before); a
  // light subpath's walk keeps its own, as if it were a camera path starting at its first vertex.
  float min_pdf = INFINITY;
  std::vector<Crossed>& crossed = scratch_.crossed;
  for (;;) {
    PathVertex& prev = path[count - 1];
    PathVertex& v = path[count];
    Hit hit;
    ++stats_.rays;
    bool found = scene_.geometry.intersect(ray, vis(visibility), &hit);
    // Shadow catchers: the camera ray (through transparent passes) meeting a catcher splits the
    // sample before the segment's media and the surface are shaded, as path.cpp (Cycles'
    // integrator_split_shadow_catcher); the throughput there is the matte's transparency.
    if (first && count == 1 && found && !split_ && splits_on(hit.instance)) {
      split_ = CatcherSplit{ray, beta, footprint, first->transparent, nulls, transparent, crossed.size(), sampler_};
      out_.background += beta * catcher_background(scene_, s_, ray.d, camera_bounces(), kVisCamera);
    }
    // Free flight through the media, as the volumetric path tracer (path.cpp) samples it.
    const Spectrum beta_before = beta;
    MediumInteraction mi;
    int medium = -1;
    if (mode == Mode::Radiance && media_ && scene_.has_emissive_media()) {
      Crossed c;
      c.at = count;
      c.le = beta * media_emission(scene_, stack, ray, ray.tmin, found ? hit.t : INFINITY, sampler_,
                                   s_.volume_estimator, s_.volume_step, out_.lightgroups ? &c.groups : nullptr);
      if (!is_black(c.le)) crossed.push_back(c);
    }
    if (media_)
      medium = sample_media(scene_, stack, ray, ray.tmin, found ? hit.t : INFINITY, sampler_, s_.volume_estimator,
                            s_.volume_step, &beta, &mi);
    if (mode == Mode::Radiance) {
      // An emitter the segment reaches that makes no vertex: recorded for s = 0, with its density
      // from prev as the walk's vertices have theirs.
      auto reach = [&](int light, bool infinite, const Vec3& p, const Vec3& n, const Spectrum& b, const Spectrum& le) {
        if (is_black(le)) return;
        Crossed c;
        c.at = count;
        c.light = light;
        c.infinite = infinite;
        c.vis = scene_.light_visibility(light);
        c.p = p;
        c.n = n;
        c.beta = b;
        c.le = le;
        PathVertex& e = endpoint(VertexType::Light);
        e.infinite = infinite;
        e.p = p;
        e.n = n;
        c.pdf_fwd = density_of(count, e);
        crossed.push_back(c);
      };
      // Lamps with a size are crossed, not hit: each one crossed ends a path of strategy s = 0.
      if (lights_.has_hittable()) {
        Ray r = ray;
        r.tmax = medium >= 0 ? std::min(mi.t, found ? hit.t : ray.tmax) : (found ? hit.t : ray.tmax);
        lights_.intersect_lamps(r, prev.p, visibility, [&](const LightSet::LampHit& h) {
          reach(h.light, false, ray.o + ray.d * h.t, h.n,
                medium >= 0 ? beta_before : beta,  // the segment before the collision (exact for grey media)
                h.radiance);
        });
      }
      if (!found && medium < 0) {
        bool background = count == 1;
        if (background && first && s_.transparent_background) first->transparent += average(beta);
        if (background && first && !split_)
          out_.background += beta * catcher_background(scene_, s_, ray.d, camera_bounces(), kVisCamera);
        if (!(background && s_.transparent_background)) {
          auto escape = [&](int light, const Spectrum& le) {
            reach(light, true, prev.p + ray.d, Vec3(0.0f), beta, le);
          };
          if (lights_.world_light() >= 0 && (!background || scene_.world.camera_visible)) {
            escape(lights_.world_light(), scene_.world.escaped_radiance(ray.d, [&](ShadingContext* wc) {
              Bounces b;  // a camera ray stays one through transparent passes, as at surfaces here
              b.total = bounces;
              describe_ray(b, visibility, wc);
              wc->transparent_depth = transparent;
              if (background && first && !first->aovs_done) write_aovs_at(wc, cs_.aovs, s_);  // as path.cpp
            }));
          }
          lights_.escaped_suns(ray.d, visibility, escape);
        }
      }
    }
    if (!is_finite(beta) || is_black(beta)) break;

    SurfacePoint sp;
    Spectrum le(0.0f);
    ShadingFrame sf;
    Vec3 smooth_n(0.0f);  // the interpolated normal, for Cycles' bump shadowing term
    if (medium < 0) {
      if (!found) break;
      sp = scene_.geometry.surface(hit);
      if (media_ && scene_.null_surface(sp.material)) {
        // An invisible medium boundary: update the stack and continue along the same line.
        if (!pass_boundary(scene_, sp, hit.t, &ray, &stack, &nulls)) break;
        continue;
      }
      ShadingContext ctx = shading_context(scene_.geometry, sp, ray.d, (hit.t - ray.tmin) * length(ray.d));
      ctx.camera_ray = mode == Mode::Radiance && visibility == kVisCamera;
      ctx.ray_depth = bounces;
      const bool aovs_here = mode == Mode::Radiance && count == 1 && first && !first->aovs_done && cs_.aovs;
      if (aovs_here) write_aovs_at(&ctx, cs_.aovs, s_);
      sf.n = smooth_n = ctx.N;
      const Material& material = scene_.material(sp.material);
      const float footprint_here = mode == Mode::Radiance ? footprint + ctx.ray_length * cs_.dD : light_footprint(sp.p);
      if (material.needs_differentials()) add_differentials(scene_.geometry, sp, footprint_here, &ctx);
      if (material.traces_rays()) add_tracing(scene_.geometry, sp, min_pdf, sampler_, &ctx);
      le = material.evaluate(ctx, scene_.images, &v.bsdf, &sf);
      v.bsdf.set_terminator_frequency(scene_.geometry.instance(sp.instance).terminator_frequency);
      if (aovs_here)
        first->aovs_done = single_pass_done(material.may_be_transparent(), v.bsdf, s_.pass_alpha_threshold);
      // Holdout on the camera's side of the path (light subpaths see surfaces as they are; their
      // t = 1 splats onto holdout objects are dropped in splat_t1).
      if (mode == Mode::Radiance && count == 1 && first &&
          !hold_out(scene_.geometry.instance(sp.instance).holdout, &v.bsdf, &le, beta, &first->transparent))
        break;
      if (!is_black(sf.smooth)) smooth_n = sf.smooth;  // a displacement's bump (Cycles' SetNormal)
      // A transparent pass makes no vertex (connections see the surface through
      // shadow_transmittance); an emitting surface stays a vertex.
      if (is_black(le) && material.may_be_transparent() &&
          v.bsdf.pass_transparent(sampler_.next_1d(), &beta,
                                  mode == Mode::Radiance && count == 1 && transparent == 0)) {
        if (++transparent > s_.transparent_bounces || !pass_boundary(scene_, sp, hit.t, &ray, &stack, &nulls)) break;
        footprint = footprint_here;
        continue;
      }
    }
    // The vertex: a medium vertex at a real collision (beta holds sigma_s T / pdf, medium.h), else
    // a surface vertex.
    const bool backface = medium < 0 && dot(ray.d, sp.ng) > 0;
    v.delta = false;
    v.infinite = false;
    v.stack = stack;
    v.beta = beta;
    v.pdf_rev = 0;
    v.vis = medium >= 0 ? kVisAll : scene_.geometry.instance_visibility(sp.instance);
    if (mode == Mode::Importance && !(v.vis & kVisLightRay)) break;
    if (medium >= 0) {
      v.type = VertexType::Medium;
      v.p = mi.p;
      v.n = Vec3(0.0f);
      v.wo = normalize(-ray.d);
      v.medium = medium;
    } else {
      v.type = VertexType::Surface;
      v.sp = sp;
      v.p = sp.p;
      v.n = backface ? -sp.ng : sp.ng;
      v.frame = local_frame(sf, v.n);
      v.ns = smooth_n;
      v.bsdf.set_light_is_wo(mode == Mode::Importance);  // light subpaths: the adjoint BSDF
      if (length_squared(v.frame.n - facing_normal(smooth_n, v.n)) > 0)
        v.bsdf.set_bump(v.frame.to_local(smooth_n), mode == Mode::Importance);
      v.wo = v.frame.to_local(-ray.d);
      v.raw_n = is_black(sf.raw) ? sf.n : sf.raw;
      v.smooth_n = smooth_n;
      v.tangent = sf.tangent;
      // Hair lobes keep their tangent in this frame; an untilted normal along Ng never tilts.
      v.tilts = sp.curve < 0 && !same_vector(v.raw_n, v.n);
    }
    v.pdf_fwd = density_of(count, v);
    reverse_density(count, v);
    // prev's neighbours are known now: the kind probabilities of a vertex of several kinds, seen
    // from the camera side (the camera walk's path[count - 2], the light walk's v).
    if (count >= 2 && prev.type == VertexType::Surface && prev.kind == BounceKind::Mixed) {
      const bool camera_walk = mode == Mode::Radiance;
      if (!mixed_kind(prev, camera_walk ? path[count - 2].p : v.p, camera_walk ? v.p : path[count - 2].p, prev.delta,
                      prev.kind_p))
        prev.kind_p[0] = -1;
    }
    if (medium >= 0) {
      v.light = -1;
      v.kind = BounceKind::Volume;
    } else {
      v.light = is_black(le) ? -1 : lights_.triangle_light(sp.instance, sp.primitive);
      v.kind = kind_of(v.bsdf);
    }
    v.le = le;
    // Light subpaths: strategies with s >= count + 1 count the kinds of light[2..count].
    if (mode == Mode::Importance && count >= 2) {
      kinds.add(v.kind);
      if (kinds.kind_exceeded(s_)) break;
    }
    ++count;
    if (count == 2 && first) first->t = hit.t;
    if (++bounces >= max_depth || (medium < 0 && v.bsdf.count() == 0)) break;
    // Camera subpaths: every strategy using vertex `count` counts the kinds of camera[1..count-2].
    if (mode == Mode::Radiance && count >= 3) {
      kinds.add(path[count - 2].kind);
      if (kinds.kind_exceeded(s_)) break;
    }

    Vec3 wi;
    if (medium >= 0) {
      float pdf_dir;  // HG sampling is exact: beta *= p / pdf = 1
      if (!phase(v).sample(v.wo, sampler_.next_2d(), &wi, &pdf_dir) || !(pdf_dir > 0)) break;
      min_pdf = std::min(min_pdf, pdf_dir);
      if (mode == Mode::Radiance && count == 2) first_walk_.set_volume();
      visibility = kVisDiffuse;
      start_at(mi.p, &ray);
    } else {
      BsdfSample bs;
      float u_lobe = sampler_.next_1d();
      Vec2 u = sampler_.next_2d();
      if (!v.bsdf.sample(v.wo, u_lobe, u, &bs) || !(bs.pdf > 0) || is_black(bs.f)) break;
      wi = v.frame.to_world(bs.wi);
      const bool reflect_geo = dot(wi, v.n) > 0;
      if (reflect_geo != ((bs.flags & kLobeReflection) != 0)) break;
      v.delta = (bs.flags & kLobeSpecular) != 0;
      if (!v.delta) min_pdf = std::min(min_pdf, bs.pdf);
      if (mode == Mode::Radiance) {
        beta *= bs.f * (std::abs(bs.wi.z) / bs.pdf);
      } else {
        // The light subpath's first bounce leaves out the lobes its light excludes (excluded_kinds).
        const unsigned excluded = count == 2 ? excluded_kinds(path[0].vis) : 0;
        if (v.delta) {
          // A delta lobe's direction is the one it sampled in v.frame (kept so where the camera
          // side would tilt the normal otherwise), with the shading-normal correction there.
          const float cos_l = std::abs(dot(ray.d, v.n)), cos_s = std::abs(dot(ray.d, v.frame.n));
          const float correction = cos_l > 0 ? cos_s * std::abs(dot(wi, v.n)) / cos_l : 0.0f;
          beta *= (1u << int(flags_pass_kind(bs.flags))) & excluded ? Spectrum(0.0f) : bs.f * (correction / bs.pdf);
        } else {
          // Sampled in the light side's frame, weighed with the BSDF the camera side sees (f_cos).
          beta *= f_cos(v, wi, Mode::Importance, excluded) / bs.pdf;
        }
      }
      if (s_.light_passes && mode == Mode::Radiance && count == 2) {
        if (v.delta)
          first_walk_.set_kind(flags_pass_kind(bs.flags));
        else
          first_walk_ = split_at(v, wi);
      }
      if (!is_finite(beta) || is_black(beta)) break;
      if (!is_transparent(bs.flags, bs.eta)) visibility = visibility_of(bs.flags);
      if (media_ && !reflect_geo) cross_boundary(scene_, sp, wi, &stack);  // into / out of a medium
      footprint += (hit.t - ray.tmin) * length(ray.d) * cs_.dD;
      ray.d = wi;
      leave(sp, &ray);
    }
    ray.d = wi;
    ray.tmin = 0;
    ray.tmax = INFINITY;
    // MIS weights need not account for Russian roulette (it keeps every strategy unbiased).
    if (!russian_roulette(bounces, kBdptRouletteBounce, &beta, sampler_, beta_start)) break;
  }
  return count;
}

// z0 on the pinhole or the lens; z1's density is the filter's choice of film position seen from it.
int Bdpt::generate_camera_subpath(std::vector<PathVertex>& path) {
  PathVertex& z0 = path[0];
  z0 = PathVertex();
  z0.type = VertexType::Camera;
  z0.p = cs_.ray.o;
  // On the lens (camera_sample_perspective's ray origin), or the orthographic camera's plane.
  // Panoramas with a lens are not connectable: t = 1 cannot reach them (Camera::connectable).
  z0.delta = !ctx_.camera.connectable();
  if (media_ && scene_.has_boundaries()) init_volume_stack(scene_, cs_.ray, &z0.stack, stats_);
  FirstSegment first;
  scratch_.crossed.clear();
  const int count = random_walk(cs_.ray, Spectrum(1.0f), camera_depth(), Mode::Radiance, z0.stack, path, &first);
  // The data passes, from the first vertex (Cycles': none behind a medium vertex).
  out_.alpha = 1 - first.transparent;
  out_.matte_transparent = split_ ? split_->film_transparent + average(split_->beta) : first.transparent;
  out_.catcher_split = split_ ? 1.0f : 0.0f;
  if (count >= 2) {
    if (path[1].type == VertexType::Surface) {
      out_.depth = first.t;
      out_.normal = path[1].frame.n;
      out_.albedo = path[1].bsdf.albedo();
      if (s_.light_passes) add_light_colors(&out_, path[1].bsdf, path[1].wo, path[1].beta);
      if (s_.data_passes) write_data_passes(scene_, ctx_.camera, s_, path[1].sp, path[1].beta, &out_);
      if (s_.ao_pass)
        out_.ao = path[1].beta * ambient_occlusion(scene_, s_, path[1].sp, path[1].frame.n, path[1].n,
                                                   media_ ? &path[1].stack : nullptr, sampler_, stats_);
      if (s_.vector_pass && motion_vector(scene_, ctx_.camera, path[1].sp, out_.vector)) out_.vector_weight = 1;
    }
  }
  return count;
}

int Bdpt::generate_catcher_subpath(std::vector<PathVertex>& path) {
  const VolumeStack stack = media_ ? catcher_volume_stack(scene_, split_->ray, stats_) : VolumeStack{};
  scratch_.crossed.clear();
  return random_walk(split_->ray, split_->beta, camera_depth(), Mode::Radiance, stack, path, nullptr);
}

int Bdpt::generate_light_subpath(std::vector<PathVertex>& path) {
  // Without a subpath light[0] is an empty light vertex, of no light (none of a previous sample).
  PathVertex& y0 = path[0];
  y0 = PathVertex();
  y0.type = VertexType::Light;
  if (!lights_.pickable() || s_.max_light_length <= 0) return 0;
  float pmf, u_remapped;
  int li = lights_.pick(sampler_.next_1d(), &pmf, &u_remapped);
  Vec2 up = sampler_.next_2d(), ud = sampler_.next_2d();
  if (li < 0) return 0;
  if (catcher_leg_ && !lights_catchers(scene_, li)) return 0;  // the emission of an absent object
  const Light& l = lights_.light(li);
  if (l.faces_receiver()) return 0;
  // Light arriving from infinity through a World volume is gone (as for s = 0 and s = 1, which
  // cross it to infinity); a subpath from the scene's bounding disk would cross a finite stretch.
  // The catcher-only estimate has no World volume.
  if (l.infinite() && scene_.has_world_volume() && !catcher_leg_) return 0;
  EmissionSample e;
  if (!(pmf > 0) || !lights_.sample_emission(scene_, li, up, ud, &e, time_) || !(e.pdf_pos > 0) || !(e.pdf_dir > 0))
    return 0;
  y0.light = li;
  y0.vis = scene_.light_visibility(li);
  y0.infinite = l.infinite();
  y0.delta_direction = e.delta_dir;
  y0.p = e.ray.o;
  y0.n = y0.infinite ? Vec3(0.0f) : e.n;
  y0.beta = e.radiance;
  y0.pdf_fwd = pmf * e.pdf_pos;
  float cos_l = is_black(e.n) ? 1.0f : std::abs(dot(e.n, e.ray.d));
  Spectrum beta = e.radiance * (cos_l / (pmf * e.pdf_pos * e.pdf_dir));
  Ray ray = e.ray;
  ray.tmin = 0;
  if (y0.on_surface()) ray.o = offset_ray_origin(e.ray.o, e.n);
  if (media_ && catcher_leg_)
    y0.stack = catcher_volume_stack(scene_, ray, stats_);
  else if (media_ && scene_.has_boundaries())
    init_volume_stack(scene_, ray, &y0.stack, stats_);
  // No strategy uses more than max_depth() + 2 light vertices (t = 1: s - 1 <= max_depth()).
  int count = random_walk(ray, beta, std::min(s_.max_light_length - 1, max_depth() + 1), Mode::Importance, y0.stack,
                          path, nullptr);
  // An infinite light's vertex is a direction: its density is the direction's (pbrt 3, 16.3.2);
  // y1's is the disk's (pdf_light handles it).
  if (y0.infinite) y0.pdf_fwd = pmf * lights_.pdf(scene_, li, Vec3(0.0f), -e.ray.d, INFINITY, time_);
  // Strategy s = 1 would have picked this light from y1 with the light tree (mis_weight).
  y0.nee_pick = count >= 2 ? nee_pick(path[1], y0) : 0.0f;
  return count;
}

// The MIS weight of strategy (s, t) for the path light[0..s-1] camera[t-1..0] (Veach 1997,
// eq. 10.9; pbrt-v4's MISWeight). With p_i the density of the same path sampled by strategy
// (i, s + t - i) and beta the heuristic's exponent (power 2, balance 1),
//   w_{s,t} = p_s^beta / sum_i p_i^beta = 1 / sum_i (p_i / p_s)^beta,
// and neighbouring strategies' ratios are the moved vertex's two densities (area measure):
//   p_{s+j} / p_s = prod_{i=t-j}^{t-1} pdf_rev(camera[i]) / pdf_fwd(camera[i])   (j = 1 .. t-1),
//   p_{s-j} / p_s = prod_{i=s-j}^{s-1} pdf_rev(light[i]) / pdf_fwd(light[i])     (j = 1 .. s),
// skipping strategies that cannot sample the path (a delta vertex at either end of the connection,
// or beyond the subpath limits). Uniform counts the strategies that can. Sums of ratios of
// neighbouring densities, never whole-path pdfs, stay finite on paths of hundreds of vertices.
// `pixel`: the camera's pixel for t = 1; light_sum, if given, receives the light side's share of
// the sum (see splat_t1).
float Bdpt::mis_weight(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, PathVertex* sampled, int s,
                       int t, const Vec2& pixel, double* light_sum) {
  if (s + t == 2) return 1;
  // The sampled endpoint (s = 1: a light sample; t = 1: the camera; s = 0: an emitter the camera
  // walk crossed, which is no vertex of it) stands in for light[0], camera[0] or camera[t - 1].
  // The densities this strategy implies are assigned temporarily (pbrt's ScopedAssignment), then
  // restored.
  PathVertex* qs = s == 1 ? sampled : (s > 1 ? &light[s - 1] : nullptr);
  PathVertex* pt = s != 1 && sampled ? sampled : (t > 1 ? &camera[t - 1] : nullptr);
  PathVertex* qs_minus = s > 1 ? &light[s - 2] : nullptr;
  PathVertex* pt_minus = t > 1 ? &camera[t - 2] : nullptr;
  auto L = [&](int i) -> const PathVertex& { return i == s - 1 ? *qs : light[i]; };
  auto C = [&](int i) -> const PathVertex& { return i == t - 1 ? *pt : camera[i]; };
  struct Saved {
    float* where;
    float value;
  };
  Saved saved[5];
  int n_saved = 0;
  auto assign = [&](float* where, float value) {
    saved[n_saved++] = {where, *where};
    *where = value;
  };
  bool pt_delta = pt ? pt->delta : false, qs_delta = qs ? qs->delta : false;
  if (pt) pt->delta = false;
  if (qs) qs->delta = false;
  if (pt) assign(&pt->pdf_rev, s > 0 ? pdf(*qs, qs_minus, *pt, pixel) : pdf_light_origin(*pt, *pt_minus));
  if (pt_minus) assign(&pt_minus->pdf_rev, s > 0 ? pdf(*pt, qs, *pt_minus, pixel) : pdf_light(*pt, *pt_minus));
  if (qs) assign(&qs->pdf_rev, pdf(*pt, pt_minus, *qs, pixel));
  if (qs_minus) assign(&qs_minus->pdf_rev, pdf(*qs, pt, *qs_minus, pixel));
  // A crossed emitter: the walk set camera[t - 3]'s reverse density towards its own next vertex.
  if (s == 0 && sampled && t >= 3)
    assign(&camera[t - 3].pdf_rev, pt_minus->delta ? 0.0f : pdf(*pt_minus, pt, camera[t - 3], pixel));

  // Strategy (s', t') exists only if the subpath limits let both walks produce it, and light
  // subpaths (s' >= 2) never start on a lamp that faces its receiver.
  const PathVertex& light_end = s > 1 ? light[0] : (s == 1 ? *qs : *pt);
  const bool subpaths_from_light = light_end.light < 0 || !lights_.light(light_end.light).faces_receiver();
  // Light tracing (t = 1) is left out for paths that split at a catcher (splat_t1 makes none): its
  // splats would need catcher sums of their own. Whether a path splits is the camera ray's, the
  // same for every strategy.
  const bool splits = t >= 2 && split_;
  auto exists = [&](int s2, int t2) {
    return s2 <= s_.max_light_length && t2 - 1 <= camera_depth() && (s2 <= 1 || subpaths_from_light) &&
           (t2 > 1 || !splits);
  };
  auto remap0 = [](float f) { return f != 0 ? f : 1.0f; };
  // A zero reverse density stands for a delta vertex sampling (remapped to 1, pbrt's remap0; the
  // strategies it would count are skipped below) or for a strategy that cannot sample the path:
  // the frames of one vertex differ with the walk's direction (view_frame), so a direction one
  // walk reaches can lie outside the other's hemisphere. That strategy and every one beyond it
  // (they all sample that vertex from the same side) have weight 0; remapped, they took a share
  // of the path that no sample of theirs ever brings back.
  auto ratio_of = [&](const PathVertex& v, bool from_delta) {
    return v.pdf_rev == 0 && !from_delta ? 0.0 : double(remap0(v.pdf_rev)) / remap0(v.pdf_fwd);
  };
  // The light endpoint's densities above hold the light subpaths' power pick and area density
  // (pdf_light_origin); strategy s' = 1 samples it with the light tree from x[1] and its own
  // density instead (nee_pick), so its ratio takes the factor lambda = nee_pick / pick_power, and
  // when s = 1 is the strategy weighed, every other's takes 1 / lambda.
  const float pick_power = light_end.light >= 0 ? lights_.pmf(light_end.light) : 0.0f;
  const double lambda = pick_power > 0 ? double(light_end.nee_pick) / pick_power : 1.0;
  auto ratio = [&](double r, int s2) { return s == 1 ? r / lambda : (s2 == 1 ? r * lambda : r); };
  // Ray visibility: a strategy whose walk would reach a vertex with a ray kind that does not see it
  // cannot sample the path, nor can any strategy moving further vertices across. The light walk
  // reaches light[1] through surfaces that cast no shadow (random_walk) and its other vertices
  // with rays of kind kVisLightRay; the camera walk reaches its first vertex with a camera ray and
  // the others with the scattering vertex's kind (taken as any of kVisLightRay: exact for objects
  // seen by all of diffuse, glossy and transmission rays or by none).
  double sum = 0, r = 1;
  for (int i = t - 1; i > 0; --i) {
    const PathVertex& c = C(i);
    const int as_light = s + t - 1 - i;  // its index on the light side
    if (as_light > 0 && !((c.vis & kVisLightRay) && (as_light > 1 || (c.vis & kVisShadow)))) break;
    // A light nothing picks (a constant World, LightSet::build) ends only strategy s = 0's paths.
    if (as_light == 0 && !(c.light >= 0 && lights_.pmf(c.light) > 0)) break;
    r *= ratio_of(c, i < t - 1 && C(i + 1).delta);
    if (!c.delta && !C(i - 1).delta && exists(s + t - i, i)) sum += heuristic(float(ratio(r, s + t - i)));
  }
  const double camera_sum = sum;
  r = 1;
  for (int i = s - 1; i >= 0; --i) {
    const PathVertex& l = L(i);
    if (!(l.vis & (t == 1 && i == s - 1 ? kVisCamera : kVisLightRay))) break;
    r *= ratio_of(l, (i < s - 1 && L(i + 1).delta) || (i == 0 && is_delta_light(l)));
    bool delta_light_vertex = i > 0 ? L(i - 1).delta : is_delta_light(l);
    if (!l.delta && !delta_light_vertex && exists(i, s + t - i)) sum += heuristic(float(ratio(r, i)));
  }
  if (light_sum) *light_sum = sum - camera_sum;

  for (int k = n_saved - 1; k >= 0; --k) *saved[k].where = saved[k].value;
  if (pt) pt->delta = pt_delta;
  if (qs) qs->delta = qs_delta;
  double w = 1 / (1 + sum);
  return std::isfinite(w) ? float(w) : 0.0f;
}

Spectrum Bdpt::connect(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, int s, int t) {
  PathVertex& pt = camera[t - 1];
  if (!scatters(pt)) return Spectrum(0.0f);
  const float kinds = kind_limit_factor(light, camera, s, t);
  if (!(kinds > 0)) return Spectrum(0.0f);
  if (s == 1) {
    // A fresh light sample at the camera vertex: exactly the path tracer's next-event estimation.
    float pmf;
    int li = lights_.pick_nee(pt.p, nee_normal(pt), sampler_.next_1d(), &pmf);
    Vec2 u = sampler_.next_2d();
    LightSample ls;
    if (li < 0 || !(pmf > 0) || !lights_.sample(scene_, li, pt.p, u, &ls, time_) || !(ls.pdf > 0) ||
        is_black(ls.radiance) || (catcher_leg_ && !lights_catchers(scene_, li)))
      return Spectrum(0.0f);
    const Light& l = lights_.light(li);
    PathVertex& sampled = endpoint(VertexType::Light);
    sampled.light = li;
    sampled.vis = scene_.light_visibility(li);
    connect_group_ = lights_.lightgroup(li);
    sampled.infinite = l.infinite();
    sampled.p = sampled.infinite ? pt.p + ls.wi : pt.p + ls.wi * ls.distance;
    sampled.nee_pick = pmf * lights_.nee_position_ratio(scene_, li, pt.p, sampled.p, time_);
    sampled.n = ls.n;
    sampled.beta = ls.radiance / (pmf * ls.pdf);
    // The shadow terminator offset applies here, where the path tracer's next-event estimation
    // would apply it, and to no other connection (README, departures).
    bool offset = false;
    const Vec3 origin =
        pt.type == VertexType::Surface ? scene_.geometry.shadow_origin(pt.sp, pt.ns, pt.n, ls.wi, &offset) : pt.p;
    Spectrum c = pt.beta * f_cos(pt, ls.wi, Mode::Radiance, excluded_kinds(sampled.vis), offset) * sampled.beta;
    if (is_black(c)) return c;
    Ray shadow = shadow_ray(origin, ls, time_);
    if (pt.type == VertexType::Surface) skip_self(pt.sp, &shadow);
    c *= transmittance(pt, shadow, kVisShadow);
    if (is_black(c)) return c;
    sampled.pdf_fwd = pdf_light_origin(sampled, pt);
    if (s_.light_passes && t == 2) first_connect_ = split_at(pt, ls.wi);
    return c * (kinds * mis_weight(light, camera, &sampled, 1, t, pixel_center_));
  }
  // s >= 2: join two surface vertices with a shadow ray.
  PathVertex& qs = light[s - 1];
  if (!scatters(qs)) return Spectrum(0.0f);
  Vec3 d = pt.p - qs.p;
  float d2 = length_squared(d);
  if (!(d2 > 0)) return Spectrum(0.0f);
  Vec3 w = d / std::sqrt(d2);  // from the light vertex towards the camera vertex
  Spectrum c = qs.beta * f_cos(qs, w, Mode::Importance, s == 2 ? excluded_kinds(light[0].vis) : 0) *
               f_cos(pt, -w, Mode::Radiance) * pt.beta;
  if (is_black(c)) return c;
  c /= d2;
  if (is_black(c)) return c;
  c *= transmittance(qs, pt, kVisLightRay);  // the camera walk's kind of ray
  if (is_black(c)) return c;
  if (s_.light_passes && t == 2) first_connect_ = split_at(pt, -w);
  return c * (kinds * mis_weight(light, camera, nullptr, s, t, pixel_center_));
}

void Bdpt::splat_t1(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, int s,
                    std::vector<Splat>& splats) {
  const PathVertex& qs = light[s - 1];
  if (!scatters(qs)) return;
  // The camera sees a holdout object as its Transparent lobes alone (hold_out), which no
  // connection reaches: light it reflects never splats.
  if (qs.type == VertexType::Surface && scene_.geometry.instance(qs.sp.instance).holdout) return;
  const float kinds = kind_limit_factor(light, camera, s, 1);
  if (!(kinds > 0)) return;
  const Camera& cam = ctx_.camera;
  if (!cam.connectable() || !(qs.vis & kVisCamera)) return;  // a camera ray would pass through qs
  // A point on the lens, uniform over the aperture as the camera's rays sample it (pbrt-v4's
  // PerspectiveCamera::SampleWi): no draw for a pinhole, whose renders stay as they were. An
  // orthographic camera's lens sample fixes its rays' direction, and the vertex is on its plane.
  const Vec3 lens = cam.connection_point(qs.p, cam.has_lens() ? sampler_.next_2d() : Vec2{0.5f, 0.5f}, time_);
  Camera::Projection& pr = scratch_.splat;
  if (!cam.project(lens, qs.p, ctx_.filter.radius(), &pr, time_)) return;
  const Vec3 dir = pr.dir;
  const float dist = pr.distance;
  // The camera ray through qs starts at the near clip (pr.near), as the camera walk's rays do:
  // the media and surfaces between the lens and the clip are not on the path (world_fog read
  // 0.5 % dark when t = 1 alone crossed its World volume there).
  const Vec3 clip = lens + dir * pr.near;
  if (splits_towards(clip, qs)) return;  // the path meets a catcher: no t = 1 (mis_weight)
  Spectrum base = qs.beta * f_cos(qs, -dir, Mode::Importance, s == 2 ? excluded_kinds(light[0].vis) : 0) * kinds;
  if (is_black(base)) return;
  // Light passes: qs is the path's first bounce seen from the camera (towards -dir), lit from its
  // predecessor on the light subpath (qs.wo).
  FirstBounce first;
  if (s_.light_passes) {
    if (qs.type == VertexType::Medium) {
      first.set_volume();
    } else {
      Spectrum k[3];
      const ViewFrame vf = view_frame(qs, -dir);
      std::optional<Bsdf> copy;
      bsdf_in(qs, vf, &copy).eval_kinds(vf.frame.to_local(-dir), vf.frame.to_local(qs.frame.to_world(qs.wo)), k);
      first.set_surface(k);
    }
  }
  PathVertex& z0 = endpoint(VertexType::Camera);
  z0.p = lens;
  base *= transmittance(
      qs, spawn_ray_to(qs.type == VertexType::Surface ? spawn_origin(qs.sp, -dir) : qs.p, clip, time_), kVisCamera);
  if (is_black(base)) return;
  // Pixel j's estimate is the integral over the film of its filter h_j times the radiance of the
  // film position's ray; over directions instead, h_j times the film's importance J (pixels per
  // steradian, summed over the film positions that see the direction: film_density), and over
  // qs's surface d omega = cos_qs dA / d^2 (f_cos holds cos_qs; pbrt-v4's PerspectiveCamera::We and SampleWi: for a
  // perspective camera J = 1 / (a cos^3), a the view-plane area of a pixel; with a lens, seen
  // from the lens point, whose density 1 / A_lens cancels We's). The film divides the sum of
  // splats by the number of light paths. An orthographic camera's importance is per area across
  // its parallel rays, cos_qs dA: a sun's measure, without the distance (Projection::parallel).
  if (!pr.parallel) base /= dist * dist;
  const float r = ctx_.filter.radius();
  // The MIS weight depends on the pixel only through the camera's density at qs, which is the
  // pixel's film_density times a common factor; that density is a factor of every ratio on the
  // light side (the camera side is empty for t = 1). So the first pixel's sum of ratios, scaled by
  // heuristic(D / D_first), gives the others' (the heuristics are multiplicative).
  float d_first = 0;
  double sum_first = 0;
  auto in_box = [&](int px, int py, const Vec2& film) {
    return px >= int(std::ceil(film.x - r - 0.5f)) && px <= int(std::floor(film.x + r - 0.5f)) &&
           py >= int(std::ceil(film.y - r - 0.5f)) && py <= int(std::floor(film.y + r - 0.5f));
  };
  for (int k = 0; k < pr.count; ++k) {
    const Vec2 film = pr.at[k].film;
    const int px0 = std::max(ctx_.x0, int(std::ceil(film.x - r - 0.5f))),
              px1 = std::min(ctx_.x0 + ctx_.width - 1, int(std::floor(film.x + r - 0.5f)));
    const int py0 = std::max(ctx_.y0, int(std::ceil(film.y - r - 0.5f))),
              py1 = std::min(ctx_.y0 + ctx_.height - 1, int(std::floor(film.y + r - 0.5f)));
    for (int py = py0; py <= py1; ++py)
      for (int px = px0; px <= px1; ++px) {
        // A pixel near two film positions (a panorama's) is splatted once, with both.
        bool done = false;
        for (int j = 0; j < k && !done; ++j) done = in_box(px, py, pr.at[j].film);
        if (done) continue;
        const Vec2 pixel{px + 0.5f, py + 0.5f};
        const float d = film_density(pr, pixel);
        if (!(d > 0)) continue;
        float w;
        if (d_first > 0) {
          w = float(1 / (1 + heuristic(d / d_first) * sum_first));
        } else {
          w = mis_weight(light, camera, &z0, s, 1, pixel, &sum_first);
          // The shortcut needs that density to be non-zero (not remapped to 1).
          if (pdf(z0, nullptr, qs, pixel) > 0) d_first = d;
        }
        Spectrum v = base * (d * w);
        if (in_range(v) && !is_black(v))
          splats.push_back({uint32_t((py - ctx_.y0) * ctx_.width + (px - ctx_.x0)), v,
                            strategies_ ? strategy_cell(s, 1, s_.strategy_depth) : -1, s - 1, first,
                            lights_.lightgroup(light[0].light)});
      }
  }
}

SampleValue Bdpt::run(std::vector<Splat>& splats, Spectrum* strategies) {
  strategies_ = strategies;
  out_.lightgroups = cs_.lightgroups;
  out_.aovs = cs_.aovs;
  const size_t capacity = size_t(std::max(s_.max_camera_length, s_.max_light_length)) + size_t(s_.max_bounces) + 4;
  std::vector<PathVertex>& camera = scratch_.camera;
  std::vector<PathVertex>& light = scratch_.light;
  if (camera.size() < capacity) camera.resize(capacity);
  if (light.size() < capacity) light.resize(capacity);

  int nt = generate_camera_subpath(camera);
  int ns = generate_light_subpath(light);
  connect_all(camera, nt, light, ns);
  for (int s = 2; s <= ns; ++s)
    if (s - 1 <= max_depth()) splat_t1(light, camera, s, splats);
  out_.radiance = L_;
  // Shadow catchers: the catcher-only estimate, a BDPT sample of the scene with the other objects
  // absent, from the segment that met the catcher with the random numbers the full one had there.
  if (split_) {
    catcher_leg_ = true;
    sampler_ = *split_->sampler;
    nt = generate_catcher_subpath(camera);
    ns = generate_light_subpath(light);
    connect_all(camera, nt, light, ns);
    catcher_leg_ = false;
  }
  return out_;
}

void Bdpt::connect_all(std::vector<PathVertex>& camera, int nt, std::vector<PathVertex>& light, int ns) {
  add_emitters_reached(camera, nt);
  // s = 1 takes a fresh light sample and needs no light subpath (there is none when the picked
  // lamp faces its receiver, or emission sampling failed); a scene without lights has no s >= 1
  // (fuzz_abi: picking from the empty light set read through a null pointer), nor one whose only
  // light is a constant World (never picked).
  const int s_max = s_.max_light_length >= 1 && lights_.pickable() ? std::max(ns, 1) : 0;
  for (int t = 2; t <= nt; ++t)
    for (int s = 1; s <= s_max; ++s) {
      if (s + t - 2 > max_depth()) break;
      connect_group_ = lights_.lightgroup(light[0].light);  // s = 1: connect() sets its sample's
      Spectrum c = connect(light, camera, s, t);
      if (!is_black(c)) add(c, s, t, connect_group_);
    }
}

void Bdpt::run_light_tracing(std::vector<Splat>& splats) {
  strategies_ = nullptr;
  const size_t capacity = size_t(std::max(s_.max_camera_length, s_.max_light_length)) + size_t(s_.max_bounces) + 4;
  std::vector<PathVertex>& camera = scratch_.camera;
  std::vector<PathVertex>& light = scratch_.light;
  if (camera.size() < capacity) camera.resize(capacity);
  if (light.size() < capacity) light.resize(capacity);
  camera[0] = PathVertex();  // no camera subpath: t = 1 reads none of it
  camera[0].type = VertexType::Camera;
  camera[0].p = ctx_.camera.position(time_);
  const int ns = generate_light_subpath(light);
  for (int s = 2; s <= ns; ++s)
    if (s - 1 <= max_depth()) splat_t1(light, camera, s, splats);
}

namespace {

class BdptIntegrator final : public Integrator {
 public:
  using Integrator::Integrator;
  void begin_pass(Film& film) override {
    film_ = &film;
    cells_ = film.strategy_cells();
  }
  SampleValue trace(const CameraSample& cs, Sampler& sampler, SampleStats& stats,
                    std::vector<Splat>& splats) const override {
    Bdpt b(ctx_, cs, sampler, stats);
    if (!cells_) return b.run(splats, nullptr);
    // The strategy view: this sample's weighted contribution per cell, added to its pixel.
    thread_local std::vector<Spectrum> strategies;
    strategies.assign(size_t(cells_), Spectrum(0.0f));
    SampleValue v = b.run(splats, strategies.data());
    if (is_finite(v.radiance))
      film_->add_strategies(int(cs.pixel_center.x) - ctx_.x0, int(cs.pixel_center.y) - ctx_.y0, strategies.data());
    return v;
  }
  void trace_unseen(const CameraSample& cs, Sampler& sampler, SampleStats& stats,
                    std::vector<Splat>& splats) const override {
    if (!ctx_.camera.connectable()) return;
    Bdpt b(ctx_, cs, sampler, stats);
    b.run_light_tracing(splats);
  }
  void end_pass(Film& film, const PassSplats& p) override {
    // Merge the splats tile by tile in a fixed order (deterministic for any thread count).
    for (size_t i = 0; i < p.tiles.size(); ++i)
      for (const Splat& sp : p.tiles[i]) {
        film.add_splat(sp.pixel, sp.value, int(i & 1));
        film.add_lightgroup_splat(sp.pixel, sp.lightgroup, sp.value);
        if (ctx_.settings.light_passes) {
          Spectrum parts[kLightParts];
          add_light_part(parts, sp.value, sp.bounces, sp.first, false);
          for (int k = 0; k < kLightParts; ++k)
            if (!is_black(parts[k])) film.add_light_splat(sp.pixel, k, parts[k]);
        }
        if (sp.strategy >= 0) film.add_strategy_splat(sp.pixel, sp.strategy, sp.value);
      }
    // One light path per camera sample traced (fewer than the region's pixels when adaptive
    // sampling has stopped some, or when the pass was cut short): dividing by the paths actually
    // traced keeps the splat estimate unbiased, as every light path is independent of the pixel
    // whose sample traced it.
    film.add_light_paths(p.samples, p.samples_half);
  }

 private:
  Film* film_ = nullptr;  // the strategy view's, during a pass
  int cells_ = 0;         // strategy view cells (0: off)
};

}  // namespace

std::unique_ptr<Integrator> make_bdpt_integrator(const RenderContext& ctx) {
  return std::make_unique<BdptIntegrator>(ctx);
}

IntegratorNeeds bdpt_needs(const IntegratorSettings& s) {
  IntegratorNeeds n;
  n.splats = true;
  if (s.strategy_depth > 0) n.strategy_cells = s.strategy_depth * strategy_columns(s.strategy_depth);
  n.bytes_per_pixel = sizeof(Splat);  // a pass's splats: about one per camera sample
  return n;
}

}  // namespace lt
