// Bidirectional path tracing's estimator (bdpt.cpp): internal to the integrators, declared here for
// the test hooks (bdpt_test_hooks.cpp), which read its densities and MIS weights.
#pragma once

#include <algorithm>
#include <optional>
#include <vector>

#include "integrators/integrator.h"
#include "integrators/media_transport.h"
#include "integrators/path_state.h"
#include "integrators/path_vertex.h"

namespace lt {

// The kinds of ray a light subpath's segments and BDPT's connections stand for: any indirect ray.
constexpr unsigned kVisLightRay = kVisDiffuse | kVisGlossy | kVisTransmission;

// What a camera walk's segment crossed that strategy s = 0 takes and that is no vertex of the
// subpath: an emitter (a lamp with a size crossed, the world or a sun escaped to), or the emission
// of the media along it (light < 0: `le` holds the segment's estimate, media_transport.h).
struct Crossed {
  int at = 0;      // the segment ends at camera[at]: s = 0 takes the emitter as that vertex (t = at + 1)
  int light = -1;  // the emitter
  bool infinite = false;
  unsigned vis = kVisAll;  // its ray visibility
  Vec3 p, n;
  Spectrum beta{1.0f}, le{0.0f};  // the walk's throughput up to it, and its radiance towards the walk
  float pdf_fwd = 0;              // the density of reaching it from camera[at - 1] (area measure)
  LightgroupShares groups;        // volume emission (light -1): the light groups it is filed under
};

// Per-thread scratch, allocated once and reused: no heap allocation per sample.
struct BdptScratch {
  std::vector<PathVertex> camera, light;  // the subpaths
  std::vector<Crossed> crossed;           // the camera walk's, in its order
  PathVertex endpoint;                    // the sampled light vertex of s = 1, the camera vertex of t = 1
  Camera::Projection projection, splat;   // camera_pdf_dir's and splat_t1's (not on the stack)
  std::vector<double> prob, next;         // kind_limit_factor's dynamic programming
};

// One BDPT sample (Veach 1997, ch. 10; pbrt-v4's BDPTIntegrator): subpaths by random walks,
// every (s, t) strategy connected and weighted by MIS.
class Bdpt {
 public:
  enum class Mode { Radiance, Importance };

  Bdpt(const RenderContext& ctx, const CameraSample& cs, Sampler& sampler, SampleStats& stats);

  // One sample: both subpaths, then every strategy (pbrt-v4's BDPTIntegrator::Li).
  SampleValue run(std::vector<Splat>& splats, Spectrum* strategies);
  // A sample the camera does not see (Integrator::trace_unseen): its light subpath's t = 1 splats.
  void run_light_tracing(std::vector<Splat>& splats);
  // Test hook (bdpt_test_hooks.cpp): see bdpt_mis_weight_sums.
  std::vector<float> weight_sums();

 private:
  // ---- densities ---------------------------------------------------------------------------
  float convert_density(float pdf, const PathVertex& from, const PathVertex& to) const {
    if (to.infinite) return pdf;
    Vec3 w = to.p - from.p;
    float d2 = length_squared(w);
    if (!(d2 > 0)) return 0;
    if (to.on_surface()) pdf *= std::abs(dot(to.n, w)) / std::sqrt(d2);
    return pdf / d2;
  }
  // Solid-angle density (orthographic: per area across the rays) with which the camera, for the
  // pixel centred at `pixel`, shoots from the lens point o towards p, as MIS must see it: the filter's density at each
  // film position whose ray passes through p times the film's importance there (pixels per steradian, Camera::project),
  // summed over those positions. Each pixel has spp camera samples but N * spp light paths (N pixels in the region), so
  // the camera's per-pixel density is divided by N (Veach's sample-count-weighted heuristics; it equals pbrt's density
  // normalised over the whole film). The lens point's own density (uniform over the aperture) is the same for every
  // strategy (t = 1 samples it as the camera does) and no strategy moves it, so MIS leaves it out.
  float camera_pdf_dir(const Vec3& o, const Vec3& p, const Vec2& pixel) const {
    Camera::Projection& pr = scratch_.projection;
    if (!ctx_.camera.project(o, p, ctx_.filter.radius() + 1, &pr, time_)) return 0;
    return film_density(pr, pixel) / n_pixels_;
  }
  // Sum over the projection's film positions of the pixel's filter value times the importance.
  float film_density(const Camera::Projection& pr, const Vec2& pixel) const {
    float sum = 0;
    for (int k = 0; k < pr.count; ++k)
      sum +=
          ctx_.filter.pdf(pr.at[k].film.x - pixel.x) * ctx_.filter.pdf(pr.at[k].film.y - pixel.y) * pr.at[k].importance;
    return sum;
  }
  // The density of sampling to_next at v reached from to_prev: in the frame the path tracer shades
  // v in when it arrives from to_prev (either walk's; view_frame).
  float bsdf_pdf(const PathVertex& v, const Vec3& to_prev, const Vec3& to_next) const {
    if (v.type == VertexType::Medium) return phase(v).pdf(to_prev, to_next);
    const ViewFrame vf = view_frame(v, to_prev);
    return v.bsdf.pdf(vf.frame.to_local(to_prev), vf.frame.to_local(to_next));
  }
  const Phase& phase(const PathVertex& v) const { return scene_.media[v.medium].phase(); }
  // Density (area measure at `next`) that vertex v samples `next`, having been reached from prev
  // (a camera vertex: for the pixel centred at `pixel`).
  float pdf(const PathVertex& v, const PathVertex* prev, const PathVertex& next, const Vec2& pixel) const {
    if (v.type == VertexType::Light) return pdf_light(v, next);
    Vec3 wn = next.p - v.p;
    if (!(length_squared(wn) > 0)) return 0;
    float p;
    if (v.type == VertexType::Camera) {
      p = camera_pdf_dir(v.p, next.p, pixel);
      // An orthographic camera's is per area across its parallel rays: as a sun's (pdf_light).
      if (ctx_.camera.orthographic()) return next.on_surface() ? p * std::abs(dot(next.n, normalize(wn))) : p;
    } else {
      Vec3 wp = normalize(prev->p - v.p);
      p = bsdf_pdf(v, wp, normalize(wn));
    }
    return convert_density(p, v, next);
  }
  // Density that a light subpath starting at light vertex v continues to `to` (area at `to`).
  float pdf_light(const PathVertex& v, const PathVertex& to) const {
    Vec3 w = to.p - v.p;
    float d2 = length_squared(w);
    if (!(d2 > 0)) return 0;
    w = w / std::sqrt(d2);
    float p;
    if (v.infinite) {
      p = 1 / (kPi * lights_.scene_radius() * lights_.scene_radius());
    } else {
      float pdf_pos, pdf_dir;
      lights_.pdf_emission(scene_, v.light, v.p, v.n, w, &pdf_pos, &pdf_dir, time_);
      p = pdf_dir / d2;
    }
    if (to.on_surface()) p *= std::abs(dot(to.n, w));
    return p;
  }
  // Density that a light subpath starts at v (light choice included: by power, as light subpaths
  // pick; mis_weight corrects strategy s = 1's, which picks with the light tree).
  float pdf_light_origin(const PathVertex& v, const PathVertex& to) const {
    float pmf = lights_.pmf(v.light);
    if (v.infinite) {
      Vec3 w = normalize(v.p - to.p);
      return pmf * lights_.pdf(scene_, v.light, to.p, w, INFINITY, time_);
    }
    float pdf_pos, pdf_dir;
    lights_.pdf_emission(scene_, v.light, v.p, v.n, normalize(to.p - v.p), &pdf_pos, &pdf_dir, time_);
    return pmf * pdf_pos;
  }
  // The normal the light tree weighs at a vertex for next-event estimation: the geometric one at
  // surfaces (either side: it does not depend on the walk that reached the vertex), none in media.
  static Vec3 nee_normal(const PathVertex& v) { return v.type == VertexType::Surface ? v.n : Vec3(0.0f); }
  // PathVertex::nee_pick of light vertex v for next-event estimation from `from` (0 from the camera).
  float nee_pick(const PathVertex& from, const PathVertex& v) const {
    if (from.type == VertexType::Camera) return 0;
    return lights_.pmf_nee(from.p, nee_normal(from), v.light) *
           lights_.nee_position_ratio(scene_, v.light, from.p, v.p, time_);
  }
  bool is_delta_light(const PathVertex& v) const {
    return v.type == VertexType::Light && lights_.light(v.light).delta();
  }

  // ---- scattering ----------------------------------------------------------------------------
  // Cycles tilts a shading normal for its viewer (ensure_valid_reflection with sd->I, the
  // direction a camera path arrives from; kernel/closure/bsdf_util.h), so a surface's BSDF depends
  // on the camera-side direction, which a light vertex learns only when connected. Each walk
  // shades its vertices for the side it reached them from (v.frame); every f is taken in the frame
  // for its camera-side direction (the path tracer's BSDF, for every strategy) and every density
  // in the frame for the direction the sampling walk arrived from (bsdf_pdf), both from view_frame.
  struct ViewFrame {
    Frame frame;
    bool own;  // v.frame itself (v.bsdf's bump normal is in it)
  };
  // The frame the program would have made at v for a ray arriving from `view` (world, unit, away
  // from v): the untilted normal tilted for it, on the side of view (Cycles flips N and Ng for a
  // back face), z then turned to v's side as v.frame's.
  ViewFrame view_frame(const PathVertex& v, const Vec3& view) const {
    if (!v.tilts) return {v.frame, true};
    const float side = dot(view, v.n) < 0 ? -1.0f : 1.0f;
    Vec3 n = ensure_valid_reflection(side * v.n, view, side * v.raw_n);
    if (!is_finite(n)) n = side * v.raw_n;
    n = facing_normal(side * n, v.n);
    if (same_vector(n, v.frame.n)) return {v.frame, true};
    return {is_black(v.tangent) ? Frame(n) : Frame(n, v.tangent), false};
  }
  // v's BSDF in vf: v.bsdf, or for another frame a copy with its bump normal moved there.
  static const Bsdf& bsdf_in(const PathVertex& v, const ViewFrame& vf, std::optional<Bsdf>* copy) {
    if (vf.own) return v.bsdf;
    copy->emplace(v.bsdf);
    (*copy)->set_smooth(length_squared(vf.frame.n - facing_normal(v.smooth_n, v.n)) > 0, vf.frame.to_local(v.smooth_n));
    return **copy;
  }
  // f at v times the cosine the path tracer weighs it with, towards `to` (world), in the frame for
  // the camera side. Radiance: v is on the camera's walk (v.wo the camera side), `to` the light
  // side: f |cos_s(to)|. Importance: v is on the light's walk (v.wo the light side, l), `to` the
  // camera side, with pbrt's shading-normal correction for importance transport:
  // f |cos_s(l)| |cos_g(to)| / |cos_g(l)| (pbrt 3, sec. 16.1). excluded: lobes the light the path
  // ends on leaves out (excluded_kinds; at the vertex next to it).
  // any_side: the shadow ray decides the geometric side (a shadow terminator offset, s = 1).
  Spectrum f_cos(const PathVertex& v, const Vec3& to, Mode mode, unsigned excluded = 0, bool any_side = false) const {
    if (v.type == VertexType::Medium) return Spectrum(phase(v).eval(v.wo, to));
    if (v.type != VertexType::Surface) return Spectrum(0.0f);
    const bool camera_walk = mode == Mode::Radiance;
    const ViewFrame vf = camera_walk ? ViewFrame{v.frame, true} : view_frame(v, to);
    const Vec3 light_side = camera_walk ? to : v.frame.to_world(v.wo);
    const Vec3 l = vf.frame.to_local(light_side);
    // The geometric normal decides which side the light is on; shading normals only shade.
    if (!any_side && (dot(light_side, v.n) > 0) != (l.z > 0)) return Spectrum(0.0f);
    std::optional<Bsdf> copy;
    const Bsdf& bsdf = bsdf_in(v, vf, &copy);
    if (camera_walk) return bsdf.eval(v.wo, l, nullptr, excluded) * std::abs(l.z);
    const float cos_l = std::abs(dot(light_side, v.n));
    if (!(cos_l > 0)) return Spectrum(0.0f);
    return bsdf.eval(l, vf.frame.to_local(to), nullptr, excluded) * (std::abs(l.z) * std::abs(dot(to, v.n)) / cos_l);
  }
  // Transmittance of the segment from a to b: 0 or 1 without media; with media the product of
  // the media's transmittances (through invisible boundaries), 0 if a surface is in the way.
  Spectrum transmittance(const PathVertex& a, const PathVertex& b, unsigned visibility) const {
    Ray r;
    r.time = time_;
    Vec3 d = b.p - a.p;
    float dist = length(d);
    if (!(dist > 0)) return Spectrum(0.0f);
    r.d = d / dist;
    r.o = a.type == VertexType::Surface ? leave_origin(a.sp, r.d) : a.p;
    r.tmin = 0;
    if (!b.infinite) r = spawn_ray_to(r.o, b.type == VertexType::Surface ? spawn_origin(b.sp, -r.d) : b.p, time_);
    if (a.type == VertexType::Surface) skip_self(a.sp, &r);
    return transmittance(a, r, visibility);
  }
  // The same along a ray leaving a: a's volume stack is the side a was reached from. `visibility`:
  // the kind of ray the segment stands for (shadow rays for s = 1, as the path tracer's).
  Spectrum transmittance(const PathVertex& a, const Ray& r, unsigned visibility) const {
    if (media_) {
      VolumeStack stack = a.stack;
      if (a.type == VertexType::Surface) leave_surface(scene_, a.sp, a.n, r.d, &stack);
      return shadow_transmittance(scene_, stack, r, sampler_, s_.volume_estimator, s_.volume_step, stats_,
                                  s_.transparent_bounces, vis(visibility));
    }
    return shadow_transmittance(scene_, VolumeStack{}, r, sampler_, s_.volume_estimator, s_.volume_step, stats_,
                                s_.transparent_bounces, vis(visibility));
  }
  // Cycles' compact footprint of a camera ray from the camera's centre to p (bump on light
  // subpaths).
  float light_footprint(const Vec3& p) const {
    float dP, dD;
    ctx_.camera.differentials(0.5f * ctx_.camera.width(), 0.5f * ctx_.camera.height(), &dP, &dD);
    // dP is the footprint at the near clip, where camera rays start.
    return dP + dD * std::max(0.0f, length(p - ctx_.camera.position()) - ctx_.camera.clip_start());
  }
  static bool scatters(const PathVertex& v) {
    return v.type == VertexType::Medium || (v.type == VertexType::Surface && v.bsdf.has_non_delta());
  }

  // ---- subpaths (pbrt-v4's GenerateCameraSubpath, GenerateLightSubpath, RandomWalk) ----------
  // How the camera ray's first segment ended, for the data passes: escaped to the background, or
  // at the first vertex, t along the last ray (as the path tracer's depth).
  struct FirstSegment {
    float t = 1e30f;
    float transparent = 0;   // of the film (1 - alpha): held out, or escaped to a transparent film
    bool aovs_done = false;  // single_pass_done
  };
  int random_walk(Ray ray, Spectrum beta, int max_depth, Mode mode, VolumeStack stack, std::vector<PathVertex>& path,
                  FirstSegment* first);
  int generate_camera_subpath(std::vector<PathVertex>& path);
  int generate_light_subpath(std::vector<PathVertex>& path);
  // The catcher-only camera subpath: camera[0], then a walk from the segment that met the catcher.
  int generate_catcher_subpath(std::vector<PathVertex>& path);
  // Every strategy with t >= 2 of the subpaths (s = 0 included); t = 1 is splat_t1.
  void connect_all(std::vector<PathVertex>& camera, int nt, std::vector<PathVertex>& light, int ns);

  // ---- strategies (pbrt-v4's ConnectBDPT and MISWeight) ----------------------------------------
  // Strategy s = 0 for every t, after the walks: the camera subpath's emitting surface vertices
  // and what its segments crossed (scratch_.crossed), in the walk's order.
  void add_emitters_reached(std::vector<PathVertex>& camera, int nt);
  // s = 0 with the emitter at camera vertex t - 1: that vertex itself, or `crossed`, one the walk
  // crossed that stands in for it.
  void emitter_reached(std::vector<PathVertex>& camera, int t, PathVertex* crossed, const Spectrum& le);
  float mis_weight(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, PathVertex* sampled, int s, int t,
                   const Vec2& pixel, double* light_sum = nullptr);
  // A light or camera vertex for a strategy's sampled endpoint (or an emitter the camera walk
  // crossed), reset without constructing a PathVertex (whose BSDF those types never use).
  PathVertex& endpoint(VertexType type) {
    PathVertex& v = scratch_.endpoint;
    v.type = type;
    v.delta = v.infinite = v.delta_direction = false;
    v.light = -1;
    v.kind = BounceKind::None;
    v.beta = Spectrum(1.0f);
    v.pdf_fwd = v.pdf_rev = 0;
    v.nee_pick = 0;
    v.vis = kVisAll;
    v.n = Vec3(0.0f);
    return v;
  }
  Spectrum connect(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, int s, int t);
  void splat_t1(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, int s, std::vector<Splat>& splats);

  // Adds a strategy's weighted contribution to the sample and to the strategy view.
  // Light passes: s + t - 2 scattering vertices; the first is camera[1] (t >= 2), whose split
  // is the walk's sampled direction's (t >= 3) or the connection's (t = 2, set by connect()).
  // Shadow catchers: the catcher-only estimate's light is its own sum; the full estimate's goes to the
  // matte and the light passes only from paths that did not meet a catcher (as path.cpp files it).
  template <class Group>  // int, or LightgroupShares
  void add(const Spectrum& c, int s, int t, const Group& group, bool environment = false) {
    if (catcher_leg_) {
      out_.catcher += c;
      return;
    }
    L_ += c;
    out_.add_lightgroup(group, c);
    if (pre_split_ && s_.shadow_catcher) out_.matte += c;
    if (s_.light_passes && pre_split_)
      add_light_part(out_.light, c, s + t - 2, t == 2 ? first_connect_ : first_walk_, environment);
    if (strategies_) {
      int cell = strategy_cell(s, t, s_.strategy_depth);
      if (cell >= 0) strategies_[cell] += c;
    }
  }

  float heuristic(float r) const {
    switch (s_.mis) {
      case MisHeuristic::Power:
        return r * r;
      case MisHeuristic::Balance:
        return r;
      case MisHeuristic::Uniform:
        return r != 0 ? 1.0f : 0.0f;
    }
    return r;
  }
  int max_depth() const { return s_.max_bounces + 1; }  // s + t - 2: the path tracer's limit
  // Cycles' per-kind bounce limits, as its path tracer (and path.cpp) applies them to this path.
  // It scatters at every vertex but x[k-1], the last before the light x[k] (next-event estimation
  // there, or the emitter hit by the ray it samples there), so the kinds of x[1..k-2] count. The
  // kind of a bounce is that of the lobe the path tracer sampled at the vertex, coming from the
  // camera side: given the direction towards the light side, lobe j with probability
  // part_j / pdf (Bsdf::lobe_pdfs; the one-sample mixture of Bsdf::sample). The path tracer's
  // estimate of this path is therefore f / p times the probability that the kinds stay within
  // the limits; that factor, returned here, is a property of the path alone (it reads only the
  // path's vertices and the directions between them), so every strategy applies the same one
  // and the MIS weights still sum to one over the strategies (Veach 1997, eq. 9.3). Counting
  // one fixed kind per vertex instead (the dominant lobe's, as before) cuts paths the path
  // tracer keeps: the door_slabs scene (walls a Mix of Diffuse and Glossy) came out 16 % dark
  // (test_bdpt.cpp, DoorSlabsBounceKindsAgreeWithPathTracing).
  float kind_limit_factor(const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera, int s,
                          int t) const;
  // The probabilities (diffuse, glossy, transmission) that the path tracer counts a bounce at a
  // surface vertex of kind Mixed as each kind, scattering from the neighbour at `camera_side`
  // towards the one at `light_side` (delta: through a delta lobe). False if no lobe can.
  bool mixed_kind(const PathVertex& v, const Vec3& camera_side, const Vec3& light_side, bool delta, float* p) const;
  int camera_depth() const { return std::min(s_.max_camera_length, s_.max_bounces + 2); }

  const RenderContext& ctx_;
  const Scene& scene_;
  const LightSet& lights_;
  const IntegratorSettings& s_;
  const CameraSample& cs_;
  // The sample's shutter time (motion blur): both subpaths, their connections and the camera.
  const float time_;
  Sampler& sampler_;
  SampleStats& stats_;
  BdptScratch& scratch_;
  const Vec2 pixel_center_;  // of the pixel this sample estimates
  float n_pixels_;           // the render region's pixels
  bool media_;               // the scene has media: walks sample free flights, connections transmittance
  SampleValue out_;
  Spectrum L_{0.0f};
  Spectrum* strategies_ = nullptr;
  int connect_group_ = -1;  // the light group of connect()'s light endpoint
  // Shadow catchers (IntegratorSettings::shadow_catcher; docs/passes.md): the camera walk's segment
  // that met a catcher through transparent passes only, with the walk's state and sampler there
  // (the catcher-only estimate starts from it with the same random numbers), and the number of
  // emitters it had crossed before (the matte's).
  struct CatcherSplit {
    Ray ray;
    Spectrum beta{1.0f};
    float footprint = 0, film_transparent = 0;
    int nulls = 0, transparent = 0;
    size_t crossed = 0;
    std::optional<Sampler> sampler;
  };
  std::optional<CatcherSplit> split_;
  bool catcher_leg_ = false;  // the catcher-only estimate is running: rays see catchers alone
  bool pre_split_ = true;     // add(): the contribution's path met no catcher (or not yet)
  unsigned vis(unsigned visibility) const { return catcher_leg_ ? catcher_only_visibility(visibility) : visibility; }
  // Whether a camera ray meeting this instance splits there (a catcher, no holdout).
  bool splits_on(int instance) const {
    const Instance& in = scene_.geometry.instance(instance);
    return s_.shadow_catcher && in.shadow_catcher && !in.holdout;
  }
  // Whether the path of a t = 1 strategy splits: the camera ray from `start` (its near clip) to its
  // first vertex qs meets a catcher (qs itself, or one it passes through). A walk's path splits as
  // the walk found.
  bool splits_towards(const Vec3& start, const PathVertex& qs) const {
    if (!s_.shadow_catcher) return false;
    if (qs.type == VertexType::Surface && splits_on(qs.sp.instance)) return true;
    const Vec3 to = qs.type == VertexType::Surface ? spawn_origin(qs.sp, normalize(start - qs.p)) : qs.p;
    return scene_.geometry.occluded(spawn_ray_to(start, to, time_), catcher_only_visibility(kVisCamera));
  }
  FirstBounce first_walk_, first_connect_;
  // The split of a scattering vertex between its predecessor (v.wo) and direction `to`.
  FirstBounce split_at(const PathVertex& v, const Vec3& to) const {
    FirstBounce fb;
    if (v.type == VertexType::Medium) {
      fb.set_volume();
    } else {
      Spectrum kinds[3];
      v.bsdf.eval_kinds(v.wo, v.frame.to_local(to), kinds);
      fb.set_surface(kinds);
    }
    return fb;
  }
};

}  // namespace lt
