// Bidirectional path tracing (Veach 1997, ch. 10; pbrt 3, section 16.3): a camera subpath and a
// light subpath per sample, every camera vertex connected with every light vertex, and all (s, t)
// strategies combined by multiple importance sampling. MIS weights are sums of products of ratios
// of neighbouring vertices' densities (pbrt's MISWeight), never products of whole-path pdfs, so
// they stay finite on paths of hundreds of vertices.
//
// Strategies: s = 0 (the camera subpath reaches an emitter: a mesh light, a lamp, the sun or the
// world, or crosses an emitting medium: volume emission, found by s = 0 only, weight 1), s = 1 (a
// fresh light sample at the camera vertex, as next-event estimation), s >= 2, and t = 1 (a light
// vertex connected to the pinhole and splatted through the pixel filter).
//
// Media (scenes with volumes; pbrt 3, section 16.3): both walks sample free flights along every
// segment as the volumetric path tracer does and scatter at medium vertices with the phase
// function; invisible boundaries update the walks' volume stacks and make no vertex; connections
// multiply by the transmittance of their segment. The MIS densities of medium vertices hold the
// phase function's directional density only, as pbrt's: the distance densities are left out of
// every strategy alike, so the weights still sum to one (unbiased), at some cost in variance.
#include <algorithm>
#include <vector>

#include "integrators/integrator.h"
#include "integrators/media_transport.h"
#include "integrators/path_state.h"
#include "integrators/path_vertex.h"

namespace lt {

namespace {

constexpr unsigned kVisLightRay = kVisDiffuse | kVisGlossy | kVisTransmission;

enum class Mode { Radiance, Importance };

// Bounce kinds, as Cycles limits them. Cycles' path tracer (and path.cpp) counts a bounce as the
// kind of the lobe (closure) it sampled: at a vertex whose BSDF has lobes of several kinds (the
// Principled BSDF's diffuse and specular, a Mix of Diffuse and Glossy) the same path is counted
// as a diffuse bounce by some samples and as a glossy one by others. kMixed marks such vertices;
// the others count as one kind whatever the directions.
enum Kind : uint8_t { kNone = 0, kDiffuse = 1, kGlossy = 2, kTransmission = 3, kVolume = 4, kMixed = 5 };
// The kind of a scattering by lobe l, by reflection or transmission (path.cpp's Bounces::count:
// a pass-through without refraction is transparent, not a bounce).
uint8_t lobe_kind(const Lobe& l, bool transmit) {
  switch (l.type) {
    case LobeType::Diffuse: return kDiffuse;
    case LobeType::GlossyGGX:
    case LobeType::SpecularGGX: return kGlossy;
    case LobeType::Dielectric: return transmit ? (l.eta == 1 && (lobe_flags(l) & kLobeSpecular) ? kNone : kTransmission) : kGlossy;
    case LobeType::Transparent: return kNone;
  }
  return kNone;
}
uint8_t kind_of(const Bsdf& bsdf) {
  uint8_t kind = kNone;
  for (int k = 0; k < bsdf.count(); ++k) {
    const Lobe& l = bsdf.lobe(k);
    if (l.type == LobeType::Dielectric) return kMixed;  // reflection or refraction
    uint8_t lk = lobe_kind(l, false);
    if (k > 0 && lk != kind) return kMixed;
    kind = lk;
  }
  return kind;
}

// Scratch subpaths, allocated once per thread and reused: no heap allocation per sample.
struct Scratch {
  std::vector<PathVertex> camera, light;
  PathVertex endpoint;  // the sampled light vertex of s = 1, the camera vertex of t = 1
};
Scratch& scratch(size_t n) {
  thread_local Scratch s;
  if (s.camera.size() < n) s.camera.resize(n);
  if (s.light.size() < n) s.light.resize(n);
  return s;
}

class Bdpt {
 public:
  Bdpt(const RenderContext& ctx, const CameraSample& cs, Sampler& sampler, SampleStats& stats)
      : ctx_(ctx), scene_(ctx.scene), lights_(ctx.scene.lights), s_(ctx.settings), cs_(cs), sampler_(sampler),
        stats_(stats),
        pixel_center_(cs.pixel_center),
        film_area_(ctx.camera.pixel_plane_area() * float(ctx.width) * float(ctx.height)),
        media_(ctx.scene.has_media()) {}

  SampleValue run(std::vector<Splat>& splats, Spectrum* strategies);
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
  // Solid-angle density with which the camera, for the pixel being estimated, shoots towards p,
  // as MIS must see it: each pixel has spp camera samples but N * spp light paths (N pixels in the
  // region), so the camera's per-pixel density is divided by N (Veach's sample-count-weighted
  // heuristics; it equals pbrt's density normalised over the whole film).
  float camera_pdf_dir(const Vec3& p) const {
    Vec2 film;
    Vec3 dir;
    float dist;
    if (!ctx_.camera.project(p, ctx_.filter.radius() + 1, &film, &dir, &dist)) return 0;
    float h = ctx_.filter.pdf(film.x - pixel_center_.x) * ctx_.filter.pdf(film.y - pixel_center_.y);
    float c = dot(dir, ctx_.camera.forward());
    return h / (film_area_ * c * c * c);
  }
  float bsdf_pdf(const PathVertex& v, const Vec3& to_prev, const Vec3& to_next) const {
    if (v.type == VertexType::Medium) return phase(v).pdf(to_prev, to_next);
    return v.bsdf.pdf(v.frame.to_local(to_prev), v.frame.to_local(to_next));
  }
  const Phase& phase(const PathVertex& v) const { return scene_.media[v.medium].phase(); }
  // Density (area measure at `next`) that vertex v samples `next`, having been reached from prev.
  float pdf(const PathVertex& v, const PathVertex* prev, const PathVertex& next) const {
    if (v.type == VertexType::Light) return pdf_light(v, next);
    Vec3 wn = next.p - v.p;
    if (!(length_squared(wn) > 0)) return 0;
    float p;
    if (v.type == VertexType::Camera) {
      p = camera_pdf_dir(next.p);
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
      lights_.pdf_emission(scene_, v.light, v.p, v.n, w, &pdf_pos, &pdf_dir);
      p = pdf_dir / d2;
    }
    if (to.on_surface()) p *= std::abs(dot(to.n, w));
    return p;
  }
  // Density that a light subpath starts at v (light choice included).
  float pdf_light_origin(const PathVertex& v, const PathVertex& to) const {
    float pmf = lights_.pmf(v.light);
    if (v.infinite) {
      Vec3 w = normalize(v.p - to.p);
      return pmf * lights_.pdf(scene_, v.light, to.p, w, INFINITY);
    }
    float pdf_pos, pdf_dir;
    lights_.pdf_emission(scene_, v.light, v.p, v.n, normalize(to.p - v.p), &pdf_pos, &pdf_dir);
    return pmf * pdf_pos;
  }
  bool is_delta_light(const PathVertex& v) const {
    return v.type == VertexType::Light && lights_.light(v.light).delta();
  }

  // ---- scattering ----------------------------------------------------------------------------
  // BSDF towards `to` at a vertex, with pbrt's shading-normal correction for importance transport.
  Spectrum f(const PathVertex& v, const Vec3& to_world, Mode mode) const {
    if (v.type == VertexType::Medium) return Spectrum(phase(v).eval(v.wo, to_world));
    if (v.type != VertexType::Surface) return Spectrum(0.0f);
    Vec3 wi = v.frame.to_local(to_world);
    if ((dot(to_world, v.n) > 0) != (wi.z > 0)) return Spectrum(0.0f);  // shading normal would leak
    Spectrum r = v.bsdf.eval(v.wo, wi, nullptr);
    if (mode == Mode::Importance) r *= shading_correction(v, v.frame.to_world(v.wo), to_world);
    return r;
  }
  static float shading_correction(const PathVertex& v, const Vec3& wo, const Vec3& wi) {
    float num = std::abs(dot(wo, v.frame.n)) * std::abs(dot(wi, v.n));
    float den = std::abs(dot(wo, v.n)) * std::abs(dot(wi, v.frame.n));
    return den > 0 ? num / den : 0.0f;
  }
  float cos_at(const PathVertex& v, const Vec3& w) const {
    if (v.type == VertexType::Surface) return std::abs(dot(v.frame.n, w));
    if (v.type == VertexType::Light && v.on_surface()) return std::abs(dot(v.n, w));
    return 1.0f;
  }
  // Transmittance of the segment from a to b: 0 or 1 without media; with media the product of
  // the media's transmittances (through invisible boundaries), 0 if a surface is in the way.
  Spectrum transmittance(const PathVertex& a, const PathVertex& b) const {
    Ray r;
    Vec3 d = b.p - a.p;
    float dist = length(d);
    if (!(dist > 0)) return Spectrum(0.0f);
    r.d = d / dist;
    r.o = a.type == VertexType::Surface ? spawn_origin(a.sp, r.d) : a.p;
    r.tmin = 0;
    if (!b.infinite) r = spawn_ray_to(r.o, b.type == VertexType::Surface ? spawn_origin(b.sp, -r.d) : b.p);
    return transmittance(a, r);
  }
  // The same along a shadow ray leaving a: a's volume stack is the side a was reached from.
  Spectrum transmittance(const PathVertex& a, const Ray& r) const {
    if (media_) {
      VolumeStack stack = a.stack;
      if (a.type == VertexType::Surface) leave_surface(scene_, a.sp, a.n, r.d, &stack);
      return shadow_transmittance(scene_, stack, r, sampler_, s_.volume_estimator, s_.volume_step, stats_);
    }
    ++stats_.rays;
    return scene_.geometry.occluded(r) ? Spectrum(0.0f) : Spectrum(1.0f);
  }
  static bool scatters(const PathVertex& v) {
    return v.type == VertexType::Medium || (v.type == VertexType::Surface && v.bsdf.has_non_delta());
  }

  int random_walk(Ray ray, Spectrum beta, int max_depth, Mode mode, VolumeStack stack, std::vector<PathVertex>& path);
  void emitter_reached(std::vector<PathVertex>& camera, int t, const Spectrum& le);
  int generate_camera_subpath(std::vector<PathVertex>& path);
  int generate_light_subpath(std::vector<PathVertex>& path);
  float mis_weight(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, PathVertex* sampled, int s, int t,
                   double* light_sum = nullptr);
  // A light or camera vertex for a strategy's sampled endpoint, reset without constructing a
  // PathVertex (whose BSDF those types never use).
  PathVertex& endpoint(VertexType type) {
    PathVertex& v = scratch(0).endpoint;
    v.type = type;
    v.delta = v.infinite = v.delta_direction = false;
    v.light = -1;
    v.kind = 0;
    v.beta = Spectrum(1.0f);
    v.pdf_fwd = v.pdf_rev = 0;
    v.n = Vec3(0.0f);
    return v;
  }
  Spectrum connect(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, int s, int t);
  void splat_t1(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, int s, std::vector<Splat>& splats);

  // Adds a strategy's weighted contribution to the sample and to the strategy view.
  void add(const Spectrum& c, int s, int t) {
    L_ += c;
    if (strategies_) {
      int cell = strategy_cell(s, t, s_.strategy_depth);
      if (cell >= 0) strategies_[cell] += c;
    }
  }

  float heuristic(float r) const {
    switch (s_.mis) {
      case MisHeuristic::Power: return r * r;
      case MisHeuristic::Balance: return r;
      case MisHeuristic::Uniform: return r != 0 ? 1.0f : 0.0f;
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
                          int t) const {
    const int k = s + t - 1;  // x[0] the camera ... x[k] the light
    auto x = [&](int i) -> const PathVertex& { return i < t ? camera[i] : light[k - i]; };
    int n[6] = {0, 0, 0, 0, 0, 0};
    // Vertices whose kind depends on the lobe: the probabilities of diffuse, glossy, transmission.
    constexpr int kMaxMixed = 64;
    float mixed[kMaxMixed][3];
    int m = 0, m_kind[3] = {0, 0, 0};
    for (int i = 1; i <= k - 2; ++i) {
      const PathVertex& v = x(i);
      if (v.type == VertexType::Medium) {
        ++n[kVolume];
        continue;
      }
      if (v.type != VertexType::Surface) continue;
      if (v.kind != kMixed) {
        ++n[v.kind];
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
        ++n[kDiffuse + only];
        continue;
      }
      if (m == kMaxMixed) return 0;
      for (int j = 0; j < 3; ++j) {
        mixed[m][j] = p[j];
        if (p[j] > 0) ++m_kind[j];
      }
      ++m;
    }
    const int limit[3] = {s_.diffuse_bounces, s_.glossy_bounces, s_.transmission_bounces};
    int cap[3];
    for (int j = 0; j < 3; ++j)
      if ((cap[j] = limit[j] - n[kDiffuse + j]) < 0) return 0;
    if (n[kVolume] > s_.volume_bounces) return 0;
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
    thread_local std::vector<double> prob, next;
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
  // The probabilities (diffuse, glossy, transmission) that the path tracer counts a bounce at a
  // surface vertex of kind kMixed as each kind, scattering from the neighbour at `camera_side`
  // towards the one at `light_side` (delta: through a delta lobe). False if no lobe can.
  bool mixed_kind(const PathVertex& v, const Vec3& camera_side, const Vec3& light_side, bool delta, float* p) const {
    const Vec3 wo_w = normalize(camera_side - v.p), wi_w = normalize(light_side - v.p);
    const bool transmit = (dot(wo_w, v.n) > 0) != (dot(wi_w, v.n) > 0);
    const Vec3 wo = v.frame.to_local(wo_w), wi = v.frame.to_local(wi_w);
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
      uint8_t kind = lobe_kind(v.bsdf.lobe(j), transmit);
      if (kind >= kDiffuse && kind <= kTransmission) p[kind - kDiffuse] += part[j] / total;
    }
    return true;
  }
  // Adds a vertex of kind k to the counts; true if that takes them past its limit. A walk counts
  // only the vertices whose kind is certain (kMixed ones may count as any of theirs), so it stops
  // only where every strategy using its further vertices would fail the limits.
  bool exceeds_kind_limit(int* n, uint8_t k) const {
    if (k == kMixed) return false;
    ++n[k];
    return (k == kDiffuse && n[k] > s_.diffuse_bounces) || (k == kGlossy && n[k] > s_.glossy_bounces) ||
           (k == kTransmission && n[k] > s_.transmission_bounces) || (k == kVolume && n[k] > s_.volume_bounces);
  }
  int camera_depth() const { return std::min(s_.max_camera_length, s_.max_bounces + 2); }

  const RenderContext& ctx_;
  const Scene& scene_;
  const LightSet& lights_;
  const IntegratorSettings& s_;
  const CameraSample& cs_;
  Sampler& sampler_;
  SampleStats& stats_;
  Vec2 pixel_center_;
  float film_area_;  // view-plane area of the render region at unit distance
  bool media_;       // the scene has media: walks sample free flights, connections transmittance
  SampleValue out_;
  Spectrum L_{0.0f};
  Spectrum* strategies_ = nullptr;
  int camera_count_ = 0;
};

// Adds the s = 0 strategy for a camera subpath whose vertex t - 1 is on an emitter.
void Bdpt::emitter_reached(std::vector<PathVertex>& camera, int t, const Spectrum& le) {
  if (t - 2 > max_depth() || is_black(le)) return;
  const PathVertex& v = camera[t - 1];
  Spectrum c = v.beta * le;
  if (is_black(c)) return;
  c *= kind_limit_factor(camera /*unused light*/, camera, 0, t);
  if (is_black(c)) return;
  add(c * mis_weight(camera /*unused light*/, camera, nullptr, 0, t), 0, t);
}

int Bdpt::random_walk(Ray ray, Spectrum beta, int max_depth, Mode mode, VolumeStack stack,
                      std::vector<PathVertex>& path) {
  if (max_depth <= 0) return 1;
  // Densities are computed from the vertices' positions with the same pdf() the MIS weights use,
  // not from the sampled directions (rays leave from offset origins): every strategy then sees
  // exactly the same numbers and the weights sum to one.
  auto density_of = [&](int count, const PathVertex& v) {
    const PathVertex& prev = path[count - 1];
    if (prev.delta) return 0.0f;
    return pdf(prev, count >= 2 ? &path[count - 2] : nullptr, v);
  };
  // The density of the vertex before prev as sampled from prev, arriving from v (the other
  // direction). Every vertex the walk reaches sets it, emitters ended on included: the s = 0 weight
  // of a path that escapes to the world or crosses a lamp reads it.
  auto reverse_density = [&](int count, const PathVertex& v) {
    if (count >= 2) path[count - 2].pdf_rev = path[count - 1].delta ? 0.0f : pdf(path[count - 1], &v, path[count - 2]);
  };
  unsigned visibility = mode == Mode::Radiance ? kVisCamera : kVisLightRay;
  int count = 1, bounces = 0, nulls = 0;
  const float beta_start = max_abs_component(beta);
  // Bounce kinds counted so far towards Cycles' per-kind limits (see kind_limit_factor): a walk
  // stops where every strategy using its further vertices would fail them, so no work is spent
  // on vertices no strategy can use.
  int kinds[5] = {0, 0, 0, 0, 0};
  for (;;) {
    PathVertex& prev = path[count - 1];
    PathVertex& v = path[count];
    Hit hit;
    ++stats_.rays;
    bool found = scene_.geometry.intersect(ray, visibility, &hit);
    // Free flight through the media, as the volumetric path tracer (path.cpp) samples it.
    const Spectrum beta_before = beta;
    MediumInteraction mi;
    int medium = -1;
    // Volume emission along this segment (media_transport.h): light that only camera subpaths find
    // (no light subpath starts in a medium, and connections never end on one), so strategy
    // s = 0, t = count + 1 is its only estimator and takes it with MIS weight 1. The same depth and
    // per-kind limits (kind_limit_factor) as an emitter reached at vertex count (emitter_reached).
    if (mode == Mode::Radiance && media_ && scene_.has_emissive_media() && stack.size > 0 &&
        count - 1 <= this->max_depth()) {
      v.type = VertexType::Light;  // the emission point: not a scattering vertex for the kind limits
      const float kinds_within = kind_limit_factor(path, path, 0, count + 1);
      if (kinds_within > 0) {
        Spectrum le = media_emission(scene_, stack, ray, ray.tmin, found ? hit.t : INFINITY, sampler_,
                                     s_.volume_estimator, s_.volume_step);
        if (!is_black(le)) add(beta * le * kinds_within, 0, count + 1);
      }
    }
    if (media_)
      medium = sample_media(scene_, stack, ray, ray.tmin, found ? hit.t : INFINITY, sampler_, s_.volume_estimator,
                            s_.volume_step, &beta, &mi);
    if (mode == Mode::Radiance) {
      // Lamps with a size are crossed, not hit: each one crossed ends a path of strategy s = 0.
      if (lights_.has_hittable()) {
        Ray r = ray;
        r.tmax = medium >= 0 ? std::min(mi.t, found ? hit.t : ray.tmax) : (found ? hit.t : ray.tmax);
        lights_.intersect_lamps(r, visibility, [&](const LightSet::LampHit& h) {
          const Light& l = lights_.light(h.light);
          v = PathVertex();
          v.type = VertexType::Light;
          v.light = h.light;
          v.p = ray.o + ray.d * h.t;
          v.n = l.type == LightType::Area ? l.direction : -ray.d;
          v.beta = medium >= 0 ? beta_before : beta;  // the segment before the collision (exact for grey media)
          v.pdf_fwd = density_of(count, v);
          reverse_density(count, v);
          emitter_reached(path, count + 1, h.radiance);
        });
      }
      if (!found && medium < 0) {
        bool background = count == 1;
        if (background) out_.alpha = s_.transparent_background ? 0.0f : 1.0f;
        if (!(background && s_.transparent_background)) {
          auto reach = [&](int light, const Spectrum& le) {
            v = PathVertex();
            v.type = VertexType::Light;
            v.infinite = true;
            v.light = light;
            v.p = prev.p + ray.d;
            v.beta = beta;
            v.pdf_fwd = density_of(count, v);
            reverse_density(count, v);
            emitter_reached(path, count + 1, le);
          };
          if (lights_.world_light() >= 0 && (!background || scene_.world.camera_visible))
            reach(lights_.world_light(), scene_.world.radiance(ray.d));
          lights_.escaped_suns(ray.d, visibility, reach);
        }
      }
    }
    if (!is_finite(beta) || is_black(beta)) break;

    SurfacePoint sp;
    if (medium < 0) {
      if (!found) break;
      sp = scene_.geometry.surface(hit);
      if (media_ && scene_.null_surface(sp.material)) {
        // An invisible medium boundary: update the stack and continue along the same line.
        if (!pass_boundary(scene_, sp, hit.t, &ray, &stack, &nulls)) break;
        continue;
      }
    }
    // The vertex: a medium vertex at a real collision (beta holds sigma_s T / pdf, medium.h), else
    // a surface vertex.
    const bool backface = medium < 0 && dot(ray.d, sp.ng) > 0;
    Spectrum le(0.0f);
    v.delta = false;
    v.infinite = false;
    v.stack = stack;
    v.beta = beta;
    v.pdf_rev = 0;
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
      v.frame = Frame(backface ? -sp.ns : sp.ns);
      v.wo = v.frame.to_local(-ray.d);
    }
    v.pdf_fwd = density_of(count, v);
    reverse_density(count, v);
    // prev's neighbours are known now: the kind probabilities of a vertex of several kinds, seen
    // from the camera side (the camera walk's path[count - 2], the light walk's v).
    if (count >= 2 && prev.type == VertexType::Surface && prev.kind == kMixed) {
      const bool camera_walk = mode == Mode::Radiance;
      if (!mixed_kind(prev, camera_walk ? path[count - 2].p : v.p, camera_walk ? v.p : path[count - 2].p, prev.delta,
                      prev.kind_p))
        prev.kind_p[0] = -1;
    }
    if (medium >= 0) {
      v.light = -1;
      v.kind = kVolume;
    } else {
      le = scene_.material(sp.material).evaluate(scene_.images, sp.uv, backface, &v.bsdf);
      v.light = is_black(le) ? -1 : lights_.triangle_light(sp.instance, sp.primitive);
      v.kind = kind_of(v.bsdf);
    }
    // Light subpaths: strategies with s >= count + 1 count the kinds of light[2..count].
    if (mode == Mode::Importance && count >= 2 && exceeds_kind_limit(kinds, v.kind)) break;
    ++count;
    if (mode == Mode::Radiance) {
      if (count == 2) {
        out_.alpha = 1;
        if (medium < 0) {
          out_.depth = hit.t;
          out_.normal = v.frame.n;
          out_.albedo = v.bsdf.albedo();
        }
      }
      if (v.light >= 0) emitter_reached(path, count, le);
      else if (!is_black(le)) add(beta * le, 0, count);  // emission no light sampler knows: no MIS partner
    }
    if (++bounces >= max_depth || (medium < 0 && v.bsdf.count() == 0)) break;
    // Camera subpaths: every strategy using vertex `count` counts the kinds of camera[1..count-2].
    if (mode == Mode::Radiance && count >= 3 && exceeds_kind_limit(kinds, path[count - 2].kind)) break;

    Vec3 wi;
    if (medium >= 0) {
      float pdf_dir;  // HG sampling is exact: beta *= p / pdf = 1
      if (!phase(v).sample(v.wo, sampler_.next_2d(), &wi, &pdf_dir) || !(pdf_dir > 0)) break;
      visibility = kVisDiffuse;
      ray.o = mi.p;
    } else {
      BsdfSample bs;
      float u_lobe = sampler_.next_1d();
      Vec2 u = sampler_.next_2d();
      if (!v.bsdf.sample(v.wo, u_lobe, u, &bs) || !(bs.pdf > 0) || is_black(bs.f)) break;
      wi = v.frame.to_world(bs.wi);
      const bool reflect_geo = dot(wi, v.n) > 0;
      if (reflect_geo != ((bs.flags & kLobeReflection) != 0)) break;
      v.delta = (bs.flags & kLobeSpecular) != 0;
      beta *= bs.f * (std::abs(bs.wi.z) / bs.pdf);
      if (mode == Mode::Importance) beta *= shading_correction(v, -ray.d, wi);
      if (!is_finite(beta) || is_black(beta)) break;
      if (!(bs.flags == (kLobeSpecular | kLobeTransmission) && bs.eta == 1)) visibility = visibility_of(bs.flags);
      if (media_ && !reflect_geo) cross_boundary(scene_, sp, wi, &stack);  // into / out of a medium
      ray.o = spawn_origin(sp, wi);
    }
    ray.d = wi;
    ray.tmin = 0;
    ray.tmax = INFINITY;
    // MIS weights need not account for Russian roulette (it keeps every strategy unbiased).
    if (!russian_roulette(bounces, &beta, sampler_, beta_start)) break;
  }
  return count;
}

// z0 on the pinhole; z1's density is the filter's choice of film position.
int Bdpt::generate_camera_subpath(std::vector<PathVertex>& path) {
  PathVertex& z0 = path[0];
  z0 = PathVertex();
  z0.type = VertexType::Camera;
  z0.p = cs_.ray.o;
  z0.delta = ctx_.camera.orthographic();  // a delta direction: t = 1 cannot reach it
  if (media_ && scene_.has_boundaries()) init_volume_stack(scene_, cs_.ray, &z0.stack, stats_);
  return random_walk(cs_.ray, Spectrum(1.0f), camera_depth(), Mode::Radiance, z0.stack, path);
}

int Bdpt::generate_light_subpath(std::vector<PathVertex>& path) {
  if (lights_.empty() || s_.max_light_length <= 0) return 0;
  float pmf, u_remapped;
  int li = lights_.pick(sampler_.next_1d(), &pmf, &u_remapped);
  Vec2 up = sampler_.next_2d(), ud = sampler_.next_2d();
  const Light& l = lights_.light(li);
  if (l.faces_receiver()) return 0;
  // Light arriving from infinity through a World volume is gone (as for s = 0 and s = 1, which
  // cross it to infinity); a subpath from the scene's bounding disk would cross a finite stretch.
  if (l.infinite() && scene_.has_world_volume()) return 0;
  EmissionSample e;
  if (!(pmf > 0) || !lights_.sample_emission(scene_, li, up, ud, &e) || !(e.pdf_pos > 0) || !(e.pdf_dir > 0))
    return 0;
  PathVertex& y0 = path[0];
  y0 = PathVertex();
  y0.type = VertexType::Light;
  y0.light = li;
  y0.infinite = l.infinite();
  y0.delta_direction = e.delta_dir;
  y0.p = e.ray.o;
  y0.n = (l.type == LightType::Area || l.type == LightType::Triangle || (l.radius > 0 && !l.infinite())) ? e.n : Vec3(0.0f);
  y0.beta = e.radiance;
  y0.pdf_fwd = pmf * e.pdf_pos;
  float cos_l = is_black(e.n) ? 1.0f : std::abs(dot(e.n, e.ray.d));
  Spectrum beta = e.radiance * (cos_l / (pmf * e.pdf_pos * e.pdf_dir));
  Ray ray = e.ray;
  ray.tmin = 0;
  if (l.type == LightType::Area || l.type == LightType::Triangle) ray.o = offset_ray_origin(e.ray.o, e.n);
  if (media_ && scene_.has_boundaries()) init_volume_stack(scene_, ray, &y0.stack, stats_);
  // No strategy uses more than max_depth() + 2 light vertices (t = 1: s - 1 <= max_depth()).
  int count = random_walk(ray, beta, std::min(s_.max_light_length - 1, max_depth() + 1), Mode::Importance, y0.stack,
                          path);
  // An infinite light's vertex is a direction: its density is the direction's (pbrt 3, 16.3.2);
  // y1's is the disk's (pdf_light handles it).
  if (y0.infinite) y0.pdf_fwd = pmf * lights_.pdf(scene_, li, Vec3(0.0f), -e.ray.d, INFINITY);
  return count;
}

// light_sum, if given, receives the light side's share of the sum of ratios (see splat_t1).
float Bdpt::mis_weight(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, PathVertex* sampled, int s,
                       int t, double* light_sum) {
  if (s + t == 2) return 1;
  // The sampled endpoint (s = 1: a light sample, t = 1: the camera) stands in for light[0] or
  // camera[0]. The densities this strategy implies are assigned temporarily (pbrt's
  // ScopedAssignment), then restored.
  PathVertex* qs = s == 1 ? sampled : (s > 1 ? &light[s - 1] : nullptr);
  PathVertex* pt = t == 1 ? sampled : (t > 1 ? &camera[t - 1] : nullptr);
  PathVertex* qs_minus = s > 1 ? &light[s - 2] : nullptr;
  PathVertex* pt_minus = t > 1 ? &camera[t - 2] : nullptr;
  auto L = [&](int i) -> const PathVertex& { return i == s - 1 ? *qs : light[i]; };
  auto C = [&](int i) -> const PathVertex& { return i == t - 1 ? *pt : camera[i]; };
  struct Saved { float* where; float value; };
  Saved saved[4];
  int n_saved = 0;
  auto assign = [&](float* where, float value) {
    saved[n_saved++] = {where, *where};
    *where = value;
  };
  bool pt_delta = pt ? pt->delta : false, qs_delta = qs ? qs->delta : false;
  if (pt) pt->delta = false;
  if (qs) qs->delta = false;
  if (pt) assign(&pt->pdf_rev, s > 0 ? pdf(*qs, qs_minus, *pt) : pdf_light_origin(*pt, *pt_minus));
  if (pt_minus) assign(&pt_minus->pdf_rev, s > 0 ? pdf(*pt, qs, *pt_minus) : pdf_light(*pt, *pt_minus));
  if (qs) assign(&qs->pdf_rev, pdf(*pt, pt_minus, *qs));
  if (qs_minus) assign(&qs_minus->pdf_rev, pdf(*qs, pt, *qs_minus));

  // Strategy (s', t') exists only if the subpath limits let both walks produce it, and light
  // subpaths (s' >= 2) never start on a lamp that faces its receiver.
  const PathVertex& light_end = s > 1 ? light[0] : (s == 1 ? *qs : camera[t - 1]);
  const bool subpaths_from_light = light_end.light < 0 || !lights_.light(light_end.light).faces_receiver();
  auto exists = [&](int s2, int t2) {
    return s2 <= s_.max_light_length && t2 - 1 <= camera_depth() && (s2 <= 1 || subpaths_from_light);
  };
  auto remap0 = [](float f) { return f != 0 ? f : 1.0f; };
  double sum = 0, r = 1;
  for (int i = t - 1; i > 0; --i) {
    const PathVertex& c = C(i);
    r *= remap0(c.pdf_rev) / remap0(c.pdf_fwd);
    if (!c.delta && !C(i - 1).delta && exists(s + t - i, i)) sum += heuristic(float(r));
  }
  const double camera_sum = sum;
  r = 1;
  for (int i = s - 1; i >= 0; --i) {
    const PathVertex& l = L(i);
    r *= remap0(l.pdf_rev) / remap0(l.pdf_fwd);
    bool delta_light_vertex = i > 0 ? L(i - 1).delta : is_delta_light(l);
    if (!l.delta && !delta_light_vertex && exists(i, s + t - i)) sum += heuristic(float(r));
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
    float pmf, u_remapped;
    int li = lights_.pick(sampler_.next_1d(), &pmf, &u_remapped);
    Vec2 u = sampler_.next_2d();
    LightSample ls;
    if (!(pmf > 0) || !lights_.sample(scene_, li, pt.p, u, &ls) || !(ls.pdf > 0) || is_black(ls.radiance))
      return Spectrum(0.0f);
    const Light& l = lights_.light(li);
    PathVertex& sampled = endpoint(VertexType::Light);
    sampled.light = li;
    sampled.infinite = l.infinite();
    sampled.p = sampled.infinite ? pt.p + ls.wi : pt.p + ls.wi * ls.distance;
    sampled.n = l.faces_receiver() ? -ls.wi : ls.n;
    sampled.beta = ls.radiance / (pmf * ls.pdf);
    Spectrum c = pt.beta * f(pt, ls.wi, Mode::Radiance) * sampled.beta * cos_at(pt, ls.wi);
    if (is_black(c)) return c;
    c *= transmittance(pt, shadow_ray(pt.type == VertexType::Surface ? spawn_origin(pt.sp, ls.wi) : pt.p, ls));
    if (is_black(c)) return c;
    sampled.pdf_fwd = pdf_light_origin(sampled, pt);
    return c * (kinds * mis_weight(light, camera, &sampled, 1, t));
  }
  // s >= 2: join two surface vertices with a shadow ray.
  PathVertex& qs = light[s - 1];
  if (!scatters(qs)) return Spectrum(0.0f);
  Vec3 d = pt.p - qs.p;
  float d2 = length_squared(d);
  if (!(d2 > 0)) return Spectrum(0.0f);
  Vec3 w = d / std::sqrt(d2);  // from the light vertex towards the camera vertex
  Spectrum c = qs.beta * f(qs, w, Mode::Importance) * f(pt, -w, Mode::Radiance) * pt.beta;
  if (is_black(c)) return c;
  c *= cos_at(qs, w) * cos_at(pt, w) / d2;
  if (is_black(c)) return c;
  c *= transmittance(qs, pt);
  if (is_black(c)) return c;
  return c * (kinds * mis_weight(light, camera, nullptr, s, t));
}

void Bdpt::splat_t1(std::vector<PathVertex>& light, std::vector<PathVertex>& camera, int s, std::vector<Splat>& splats) {
  const PathVertex& qs = light[s - 1];
  if (!scatters(qs)) return;
  const float kinds = kind_limit_factor(light, camera, s, 1);
  if (!(kinds > 0)) return;
  const Camera& cam = ctx_.camera;
  Vec2 film;
  Vec3 dir;
  float dist;
  if (!cam.project(qs.p, ctx_.filter.radius(), &film, &dir, &dist)) return;
  Spectrum base = qs.beta * f(qs, -dir, Mode::Importance) * kinds;
  if (is_black(base)) return;
  PathVertex& z0 = endpoint(VertexType::Camera);
  z0.p = cam.position();
  base *= transmittance(qs, z0);
  if (is_black(base)) return;
  float c = dot(dir, cam.forward());
  // Pixel j's importance is W_j = h_j(x) / (a cos^4) (a: view-plane area of a pixel); with the
  // geometry term cos * cos_qs / d^2 the contribution is h_j cos_qs / (a cos^3 d^2). The film
  // divides the sum of splats by the number of light paths.
  base *= cos_at(qs, dir) / (cam.pixel_plane_area() * c * c * c * dist * dist);
  const float r = ctx_.filter.radius();
  const int px0 = std::max(ctx_.x0, int(std::ceil(film.x - r - 0.5f))),
            px1 = std::min(ctx_.x0 + ctx_.width - 1, int(std::floor(film.x + r - 0.5f)));
  const int py0 = std::max(ctx_.y0, int(std::ceil(film.y - r - 0.5f))),
            py1 = std::min(ctx_.y0 + ctx_.height - 1, int(std::floor(film.y + r - 0.5f)));
  const Vec2 own_center = pixel_center_;
  // The MIS weight depends on the pixel only through the camera's density at qs, which is the
  // pixel's filter value h times a common factor; that density is a factor of every ratio on the
  // light side (the camera side is empty for t = 1). So the first pixel's sum of ratios, scaled by
  // heuristic(h / h_first), gives the others' (the heuristics are multiplicative).
  float h_first = 0;
  double sum_first = 0;
  for (int py = py0; py <= py1; ++py)
    for (int px = px0; px <= px1; ++px) {
      float h = ctx_.filter.pdf(film.x - (px + 0.5f)) * ctx_.filter.pdf(film.y - (py + 0.5f));
      if (!(h > 0)) continue;
      float w;
      if (h_first > 0) {
        w = float(1 / (1 + heuristic(h / h_first) * sum_first));
      } else {
        pixel_center_ = {px + 0.5f, py + 0.5f};
        w = mis_weight(light, camera, &z0, s, 1, &sum_first);
        // The shortcut needs that density to be non-zero (not remapped to 1).
        if (pdf(z0, nullptr, qs) > 0) h_first = h;
      }
      Spectrum v = base * (h * w);
      if (is_finite(v) && !is_black(v))
        splats.push_back({uint32_t((py - ctx_.y0) * ctx_.width + (px - ctx_.x0)), v,
                          strategies_ ? strategy_cell(s, 1, s_.strategy_depth) : -1});
    }
  pixel_center_ = own_center;
}

SampleValue Bdpt::run(std::vector<Splat>& splats, Spectrum* strategies) {
  strategies_ = strategies;
  const size_t capacity = size_t(std::max(s_.max_camera_length, s_.max_light_length)) + size_t(s_.max_bounces) + 4;
  Scratch& sc = scratch(capacity);
  std::vector<PathVertex>& camera = sc.camera;
  std::vector<PathVertex>& light = sc.light;

  int nt = generate_camera_subpath(camera);
  int ns = generate_light_subpath(light);

  // s = 1 takes a fresh light sample and needs no light subpath (there is none when the picked
  // lamp faces its receiver, or emission sampling failed); a scene without lights has no s >= 1
  // (fuzz_abi: picking from the empty light set read through a null pointer).
  const int s_max = s_.max_light_length >= 1 && !lights_.empty() ? std::max(ns, 1) : 0;
  for (int t = 2; t <= nt; ++t)
    for (int s = 1; s <= s_max; ++s) {
      if (s + t - 2 > max_depth()) break;
      Spectrum c = connect(light, camera, s, t);
      if (!is_black(c)) add(c, s, t);
    }
  for (int s = 2; s <= ns; ++s)
    if (s - 1 <= max_depth()) splat_t1(light, camera, s, splats);
  out_.radiance = L_;
  return out_;
}

std::vector<float> Bdpt::weight_sums() {
  std::vector<float> sums;
  const size_t capacity = size_t(std::max(s_.max_camera_length, s_.max_light_length)) + size_t(s_.max_bounces) + 4;
  std::vector<PathVertex> camera(capacity), light(capacity);
  int nt = generate_camera_subpath(camera);
  int ns = generate_light_subpath(light);
  for (int t = 2; t <= nt; ++t)
    for (int s = 2; s <= ns; ++s) {
      if (s + t - 2 > max_depth()) break;
      PathVertex &qs = light[s - 1], &pt = camera[t - 1];
      if (!scatters(pt) || !scatters(qs) || is_black(transmittance(qs, pt))) continue;
      if (is_black(f(qs, normalize(pt.p - qs.p), Mode::Importance)) || is_black(f(pt, normalize(qs.p - pt.p), Mode::Radiance)))
        continue;
      // The full path x[0] = camera ... x[k] = light, with both densities of every vertex:
      // cam[i] (sampled from x[i-1]) and lig[i] (sampled from x[i+1]).
      const int k = s + t - 1;
      std::vector<PathVertex> x(k + 1);
      for (int i = 0; i < t; ++i) x[i] = camera[i];
      for (int i = 0; i < s; ++i) x[t + i] = light[s - 1 - i];
      std::vector<float> cam(k + 1), lig(k + 1);
      for (int i = 0; i < t; ++i) { cam[i] = camera[i].pdf_fwd; lig[i] = camera[i].pdf_rev; }
      for (int i = 0; i < s; ++i) { lig[t + i] = light[s - 1 - i].pdf_fwd; cam[t + i] = light[s - 1 - i].pdf_rev; }
      // Densities across the connection, which neither walk produced.
      lig[t - 1] = pdf(qs, s > 1 ? &light[s - 2] : nullptr, pt);
      lig[t - 2] = pdf(pt, &qs, camera[t - 2]);
      cam[t] = pdf(pt, &camera[t - 2], qs);
      cam[t + 1] = pdf(qs, &pt, light[s - 2]);
      lig[k] = light[0].pdf_fwd;
      // Cycles' bounce-kind limits scale every strategy's contribution by the same factor (see
      // kind_limit_factor): the weights times each strategy's factor, over the factor this
      // connection gets in the render, must sum to one too. Inside the joined path every vertex
      // has both neighbours; the ones the walks did not store are set here.
      const float factor = kind_limit_factor(light, camera, s, t);
      if (!(factor > 0)) continue;
      for (int i = 1; i < k; ++i)
        if (x[i].type == VertexType::Surface && x[i].kind == kMixed &&
            !mixed_kind(x[i], x[i - 1].p, x[i + 1].p, i != t - 1 && i != t && x[i].delta, x[i].kind_p))
          x[i].kind_p[0] = -1;
      float sum = 0;
      for (int t2 = 1; t2 <= k + 1; ++t2) {
        const int s2 = k + 1 - t2;
        if (s2 + t2 - 2 > max_depth() || (s2 == 1 && t2 == 1)) continue;
        if (s2 > s_.max_light_length || t2 - 1 > camera_depth()) continue;  // the subpath limits exclude it
        std::vector<PathVertex> c2(x.begin(), x.begin() + t2), l2(s2);
        for (int i = 0; i < t2; ++i) { c2[i].pdf_fwd = cam[i]; c2[i].pdf_rev = lig[i]; }
        for (int i = 0; i < s2; ++i) {
          l2[i] = x[k - i];
          l2[i].pdf_fwd = lig[k - i];
          l2[i].pdf_rev = cam[k - i];
        }
        // Only strategies whose connection can be made sample this path.
        if (t2 >= 1 && s2 >= 1) {
          const PathVertex& a = c2[t2 - 1];
          const PathVertex& b = l2[s2 - 1];
          bool a_ok = a.type == VertexType::Camera ? !ctx_.camera.orthographic() : (scatters(a) && !a.delta);
          bool b_ok = b.type == VertexType::Light ? !b.delta_direction : (scatters(b) && !b.delta);
          if (!a_ok || !b_ok) continue;
        }
        if (s2 == 0 && is_delta_light(x[k])) continue;
        if (t2 == 1 && x[1].delta) continue;
        const PathVertex* sampled = s2 == 1 ? &l2[0] : (t2 == 1 ? &c2[0] : nullptr);
        PathVertex sampled_copy;
        if (sampled) sampled_copy = *sampled;
        float w = mis_weight(l2, c2, sampled ? &sampled_copy : nullptr, s2, t2);
        if (!(w >= 0 && w <= 1 + 1e-5f)) sum = NAN;  // a weight outside [0, 1] fails the check
        sum += w * kind_limit_factor(l2, c2, s2, t2) / factor;
      }
      sums.push_back(sum);
    }
  return sums;
}

}  // namespace

std::vector<float> bdpt_mis_weight_sums(const RenderContext& ctx, const CameraSample& cs, Sampler& sampler) {
  SampleStats stats;
  Bdpt b(ctx, cs, sampler, stats);
  return b.weight_sums();
}

SampleValue trace_bdpt(const RenderContext& ctx, const CameraSample& cs, Sampler& sampler, SampleStats& stats,
                       std::vector<Splat>& splats, Spectrum* strategies) {
  Bdpt b(ctx, cs, sampler, stats);
  return b.run(splats, strategies);
}

}  // namespace lt
