#include "media/medium.h"

#include <cstdio>
#include <limits>

#include "core/error.h"
#include "media/grid_lookup.h"

namespace lt {

namespace {

bool valid_coefficients(const Spectrum& s) { return is_finite(s) && s.x >= 0 && s.y >= 0 && s.z >= 0; }

inline float free_path(float u) { return -std::log1p(-u); }  // -ln(1 - u), u in [0, 1)

// exp(-sigma * d) per channel with 0 * inf = 0 (a channel that does not extinguish passes).
inline Spectrum beer(const Spectrum& sigma, float d) {
  Spectrum r;
  for (int c = 0; c < 3; ++c) r[c] = sigma[c] > 0 ? std::exp(-sigma[c] * d) : 1.0f;
  return r;
}

// The smallest positive channel (INFINITY if none).
inline float min_positive(const Spectrum& s) {
  float m = INFINITY;
  for (int c = 0; c < 3; ++c)
    if (s[c] > 0) m = std::min(m, s[c]);
  return m;
}

inline Spectrum safe_div(const Spectrum& a, float b) { return b > 0 && std::isfinite(b) ? a / b : Spectrum(0.0f); }

// A ray in the grid's index space with the coefficients per unit density and per unit of t.
struct HeteroRay {
  Vec3 o, d;
  float len;        // |ray.d| in world units
  Spectrum st, ss;  // sigma_t, sigma_s per unit density and per unit t
  float maj_scale;  // max channel of st: density majorant -> sigma_t majorant per unit t
  const MajorantGrid* maj;
  const GridData* grid;
};

HeteroRay hetero_ray(const Medium& m, const Ray& ray, float len) {
  const Transform w2i = m.world_to_index(ray.time);
  HeteroRay r{w2i.point(ray.o),
              w2i.vector(ray.d),
              len,
              (m.sigma_a_unit() + m.sigma_s_unit()) * len,
              m.sigma_s_unit() * len,
              0,
              &m.majorant_grid(),
              m.grid().get()};
  r.maj_scale = max_component(r.st);
  return r;
}

// Where track() stopped.
struct Tracked {
  bool capped = false;  // after Medium::kMaxTrackingSteps tentative collisions, at t with density rho
  float t = 0, rho = 0;
  int steps = 0;  // tentative collisions taken
};

// The tentative collisions on [t0, t1] (inside the domain) against a piecewise-constant rate,
// pbrt-v4's SampleT_maj: the majorant segments are walked once; on_segment(seg, &sigma_bar) sets
// the rate of tentative collisions in the segment (0: none) or returns false to stop; free paths
// are sampled with that rate (exponential, so the collisions form a Poisson process of rate
// sigma_bar) and on_collision(t, rho) is called at each one with the density rho there; it
// returns false to stop. Residual ratio tracking and delta tracking are such pairs of callbacks.
template <class S, class F>
Tracked track(const HeteroRay& r, float t0, float t1, Sampler& rng, S&& on_segment, F&& on_collision) {
  return with_density(*r.grid, [&](const auto& density) {
    Tracked out;
    MajorantGrid::Iterator it = r.maj->traverse(r.o, r.d, t0, t1);
    MajorantSegment seg;
    while (it.next(&seg)) {
      float sigma_bar = 0;
      if (!on_segment(seg, &sigma_bar)) return out;
      if (!(sigma_bar > 0)) continue;
      float t = seg.t0;
      for (;;) {
        t += free_path(rng.next_1d()) / sigma_bar;
        if (t >= seg.t1) break;
        const float rho = density(r.o + r.d * t);
        if (++out.steps > Medium::kMaxTrackingSteps) {
          out.capped = true;
          out.t = t;
          out.rho = rho;
          return out;
        }
        if (!on_collision(t, rho)) return out;
      }
    }
    return out;
  });
}

// Midpoint ray marching over [a, b] (already clipped to the domain) with steps of h (units of t)
// starting at a; the last step is shortened to end at b. visit(t_start, dt, density_at_midpoint)
// returns false to stop. Steps whose midpoints fall in a majorant cell bounded by 0 are skipped
// without changing the result (their density is exactly 0), unless skip_empty is false (emission).
template <class D, class V>
void march(const HeteroRay& r, const D& density, float a, float b, float h, int* steps, V&& visit,
           bool skip_empty = true) {
  double nd = std::ceil(double(b - a) / double(h));
  long n;
  if (!(nd <= Medium::kMaxMarchingSteps)) {
    n = Medium::kMaxMarchingSteps;
    h = (b - a) / float(n);
  } else {
    n = std::max(1L, long(nd));
  }
  auto bounds = [&](long k, float* t0, float* t1) {
    *t0 = a + float(k) * h;
    *t1 = k + 1 >= n ? b : std::min(b, a + float(k + 1) * h);
  };
  long k = 0;
  auto step = [&]() {
    float t0, t1;
    bounds(k, &t0, &t1);
    ++*steps;
    float rho = density(r.o + r.d * (0.5f * (t0 + t1)));
    ++k;
    return visit(t0, t1 - t0, rho);
  };
  MajorantGrid::Iterator it = r.maj->traverse(r.o, r.d, a, b);
  MajorantSegment seg;
  while (k < n && it.next(&seg)) {
    if (seg.value <= 0 && skip_empty) {
      double first = std::ceil(double(seg.t1 - a) / double(h) - 0.5);
      if (first > double(k)) k = long(std::min(double(n), first));
      continue;
    }
    for (;;) {
      if (k >= n) return;
      float t0, t1;
      bounds(k, &t0, &t1);
      if (0.5f * (t0 + t1) >= seg.t1) break;
      if (!step()) return;
    }
  }
  while (k < n)  // float rounding may end the traversal a hair before b
    if (!step()) return;
}

constexpr float kRouletteThreshold = 0.05f, kRouletteKill = 0.75f;  // pbrt-v4's values

}  // namespace

// ---- Medium: construction and queries -------------------------------------------------------

Medium::Medium(const Medium& o)
    : sigma_a_(o.sigma_a_),
      sigma_s_(o.sigma_s_),
      phase_(o.phase_),
      emission_(o.emission_),
      grid_emission_(o.grid_emission_),
      empty_(o.empty_),
      emissive_(o.emissive_),
      grid_(o.grid_),
      world_to_index_(o.world_to_index_),
      object_to_index_(o.object_to_index_),
      motion_(o.motion_),
      majorant_(o.majorant_),
      voxel_size_(o.voxel_size_),
      march_step_(o.march_step_),
      majorant_cell_(o.majorant_cell_),
      capped_(o.capped_.load()) {}

Medium& Medium::operator=(const Medium& o) {
  if (this == &o) return *this;
  sigma_a_ = o.sigma_a_;
  sigma_s_ = o.sigma_s_;
  phase_ = o.phase_;
  emission_ = o.emission_;
  grid_emission_ = o.grid_emission_;
  empty_ = o.empty_;
  emissive_ = o.emissive_;
  grid_ = o.grid_;
  world_to_index_ = o.world_to_index_;
  object_to_index_ = o.object_to_index_;
  motion_ = o.motion_;
  majorant_ = o.majorant_;
  voxel_size_ = o.voxel_size_;
  march_step_ = o.march_step_;
  majorant_cell_ = o.majorant_cell_;
  capped_.store(o.capped_.load());
  return *this;
}

void Medium::set_emission(const Spectrum& e) {
  // Negative channels are allowed: Cycles' blackbody below ~1900 K (volume_material.h).
  if (!is_finite(e)) throw InvalidArgument("medium emission must be finite");
  if (grid_ && !is_black(e)) throw InvalidArgument("emission is supported for homogeneous media only");
  emission_ = e;
  emissive_ = !is_black(e);
}

void Medium::set_grid_emission(std::shared_ptr<const GridEmission> e) {
  if (!grid_) throw InvalidArgument("grid emission is supported for heterogeneous media only");
  grid_emission_ = std::move(e);
  emissive_ = grid_emission_ != nullptr;
  // An emission region reaching past the density's domain widens the domain (Cycles shades the
  // whole volume mesh: media/leaf_region.h); the density is the grid's there.
  int lo[3], hi[3];
  if (!grid_emission_ || !grid_emission_->region() || !grid_emission_->region()->bounds(lo, hi)) return;
  bool inside = majorant_.valid();
  for (int a = 0; a < 3 && inside; ++a) inside = lo[a] >= majorant_.lo()[a] && hi[a] <= majorant_.hi()[a];
  if (!inside) majorant_ = MajorantGrid::build(*grid_, majorant_cell_, lo, hi);
}

Spectrum Medium::emission_at(const Vec3& p, float time) const {
  if (!grid_) return emission_;
  if (!grid_emission_ || !majorant_.valid()) return Spectrum(0.0f);
  Vec3 q = world_to_index(time).point(p);
  for (int a = 0; a < 3; ++a)
    if (!(q[a] >= majorant_.lo()[a] && q[a] <= majorant_.hi()[a])) return Spectrum(0.0f);
  GridEmission::Lookup lookup(*grid_emission_);
  return lookup(q);
}

Medium Medium::homogeneous(const Spectrum& sigma_a, const Spectrum& sigma_s, float g) {
  if (!valid_coefficients(sigma_a) || !valid_coefficients(sigma_s))
    throw InvalidArgument("homogeneous medium: sigma_a and sigma_s must be finite and >= 0");
  if (!std::isfinite(g)) throw InvalidArgument("homogeneous medium: anisotropy g must be finite");
  Medium m;
  m.sigma_a_ = sigma_a;
  m.sigma_s_ = sigma_s;
  m.phase_ = Phase::hg(g);
  m.empty_ = is_black(sigma_a + sigma_s);
  return m;
}

Medium Medium::heterogeneous(std::shared_ptr<const GridData> grid, const Spectrum& sigma_a, const Spectrum& sigma_s,
                             float g, const Transform& object_to_world, int majorant_cell) {
  if (!grid) throw InvalidArgument("heterogeneous medium: no density grid");
  if (!valid_coefficients(sigma_a) || !valid_coefficients(sigma_s))
    throw InvalidArgument("heterogeneous medium: sigma_a and sigma_s must be finite and >= 0");
  if (!std::isfinite(g)) throw InvalidArgument("heterogeneous medium: anisotropy g must be finite");
  if (!grid->is_nanovdb() && grid->dense.empty() && !grid->empty())
    throw InvalidArgument("heterogeneous medium: grid '" + grid->name + "' has no storage");
  Medium m;
  m.sigma_a_ = sigma_a;
  m.sigma_s_ = sigma_s;
  m.phase_ = Phase::hg(g);
  m.grid_ = grid;
  Transform index_to_world = compose(object_to_world, grid->index_to_object);
  m.world_to_index_ = affine_inverse(index_to_world);
  m.object_to_index_ = affine_inverse(grid->index_to_object);
  m.voxel_size_ =
      std::min({length(index_to_world.column(0)), length(index_to_world.column(1)), length(index_to_world.column(2))});
  m.march_step_ = m.voxel_size_;
  m.majorant_cell_ = majorant_cell;
  m.majorant_ = MajorantGrid::build(*grid, majorant_cell);
  m.empty_ = grid->empty() || is_black(sigma_a + sigma_s) || !(m.majorant_.max_value() > 0);
  return m;
}

float Medium::density(const Vec3& p, float time) const {
  if (!grid_) return 1;
  if (!majorant_.valid()) return 0;
  Vec3 q = world_to_index(time).point(p);
  for (int a = 0; a < 3; ++a)
    if (!(q[a] >= majorant_.lo()[a] && q[a] <= majorant_.hi()[a])) return 0;
  return grid_->interpolate(q);
}

// A moving medium's: over its steps and 8 times between each two (a turn's arc leaves its chord).
bool Medium::bounds(Vec3* lo, Vec3* hi) const {
  if (!grid_) return false;
  if (!majorant_.valid()) {
    *lo = *hi = Vec3(0.0f);
    return true;
  }
  const int* a = majorant_.lo();
  const int* b = majorant_.hi();
  const Vec3 ia{float(a[0]), float(a[1]), float(a[2])}, ib{float(b[0]), float(b[1]), float(b[2])};
  affine_inverse(world_to_index_).map_box(ia, ib, lo, hi);
  const int n = motion_.empty() ? 0 : 8 * int(motion_.size() - 1);
  for (int k = 0; k <= n && n > 0; ++k) {
    Vec3 l, h;
    affine_inverse(world_to_index(float(k) / float(n))).map_box(ia, ib, &l, &h);
    *lo = vmin(*lo, l);
    *hi = vmax(*hi, h);
  }
  return true;
}

bool Medium::clip(const Ray& ray, float* t0, float* t1) const {
  if (empty_ || !(*t0 < *t1)) return false;
  if (!grid_) return true;
  const Transform w2i = world_to_index(ray.time);
  return majorant_.clip(w2i.point(ray.o), w2i.vector(ray.d), t0, t1);
}

Transform Medium::world_to_index(float time) const {
  if (motion_.empty()) return world_to_index_;
  return compose(object_to_index_, affine_inverse(interpolate_motion(motion_, time)));
}

void Medium::set_motion(const std::vector<Transform>& object_to_world) {
  if (!grid_) throw InvalidArgument("medium motion: only a Volume object's grid moves");
  if (object_to_world.empty()) {  // still again
    motion_.clear();
    return;
  }
  if (object_to_world.size() < 2) throw InvalidArgument("medium motion: at least 2 steps");
  for (const Transform& m : object_to_world) {
    bool finite = true;
    for (float x : m.m) finite = finite && std::isfinite(x);
    if (!finite || !(std::abs(m.determinant()) > 1e-30f))
      throw InvalidArgument("medium motion: a step is not finite or not invertible");
  }
  motion_ = decompose_motion(object_to_world);
}

size_t Medium::memory_bytes() const {
  if (!grid_) return 0;
  return grid_->memory_bytes() + majorant_.memory_bytes() + (grid_emission_ ? grid_emission_->memory_bytes() : 0);
}

// ---- Medium: estimators ---------------------------------------------------------------------

Spectrum Medium::transmittance(const Ray& ray, float t0, float t1, Sampler& s, VolumeEstimator e, float step) const {
  if (empty_ || !(t1 > t0)) return Spectrum(1.0f);
  const float len = length(ray.d);
  if (!(len > 0) || !std::isfinite(len)) return Spectrum(1.0f);
  if (!grid_) return beer(sigma_a_ + sigma_s_, (t1 - t0) * len);  // closed form, no random numbers

  const HeteroRay r = hetero_ray(*this, ray, len);
  if (!majorant_.clip(r.o, r.d, &t0, &t1)) return Spectrum(1.0f);

  if (e == VolumeEstimator::RayMarching) {
    // tau = sigma_t_unit * integral of the density; one scalar integral serves all channels.
    float h = (step > 0 ? step : march_step_) / len;
    double integral = 0;
    int steps = 0;
    // Stop once every extinguishing channel is below float's smallest normal number.
    const double stop = 104.0 / min_positive(r.st);
    with_density(*grid_, [&](const auto& density) {
      march(r, density, t0, t1, h, &steps, [&](float, float dt, float rho) {
        integral += double(rho) * dt;
        return integral < stop;
      });
      return 0;
    });
    return beer(r.st, float(integral));
  }

  // Residual ratio tracking (Novak et al. 2014, sec. 5.2) with a control per majorant cell: the
  // cell's lower bound of the density, sigma_c = min * sigma_t. T = exp(-sigma_t * integral of min),
  // exact from the segments the DDA walks anyway, times ratio tracking of the residual
  // sigma_t (rho - min) against sigma_bar = (max - min) * max_c sigma_t: T *= 1 - sigma_t (rho -
  // min) / sigma_bar per channel at each tentative collision. The weights lie in [0, 1] because
  // min <= rho <= max, and the residual is small where the cell's density varies little, so
  // fewer collisions and less noise than plain ratio tracking (its special case min = 0).
  // Russian roulette once the residual's estimate is small (pbrt-v4) keeps dense residuals cheap
  // without bias; the control's exact factor is left out of it (it is not noise), and the walk
  // stops once that factor underflows to 0 in every extinguishing channel (the result is then 0
  // in float anyway).
  Spectrum T(1.0f);
  double control = 0;       // integral of the lower bound over the segments walked, units of t
  float min = 0, rate = 0;  // the current segment's lower bound and residual majorant
  const double stop = 104.0 / min_positive(r.st);
  const Tracked end = track(
      r, t0, t1, s,
      [&](const MajorantSegment& seg, float* sigma_bar) {
        min = seg.min;
        control += double(min) * (seg.t1 - seg.t0);
        *sigma_bar = rate = (seg.value - min) * r.maj_scale;
        return control < stop;
      },
      [&](float, float rho) {
        T *= Spectrum(1.0f) - r.st * ((rho - min) / rate);
        const float m = max_component(T);
        if (m < kRouletteThreshold) {
          if (!(m > 0) || s.next_1d() < kRouletteKill) {
            T = Spectrum(0.0f);
            return false;
          }
          T /= 1 - kRouletteKill;
        }
        return true;
      });
  if (end.capped) {
    count_capped();
    return Spectrum(0.0f);
  }
  return T * beer(r.st, float(control));
}

bool Medium::sample_distance(const Ray& ray, float t0, float t1, Sampler& s, VolumeEstimator e, float step,
                             MediumInteraction* out) const {
  out->weight = Spectrum(1.0f);
  out->sigma_s = Spectrum(0.0f);
  out->steps = 0;
  out->t = t1;
  if (empty_ || !(t1 > t0)) return false;
  const float len = length(ray.d);
  if (!(len > 0) || !std::isfinite(len)) return false;

  if (!grid_) {
    // Closed form with the channel chosen uniformly and the channel-averaged pdf (one-sample MIS
    // with the balance heuristic; pbrt-v3's HomogeneousMedium): unbiased per channel.
    const Spectrum st = sigma_a_ + sigma_s_;
    const int c = std::min(2, int(s.next_1d() * 3));
    const float u = s.next_1d();
    const float d = (t1 - t0) * len;  // world distance (may be infinite)
    const float dist = st[c] > 0 ? free_path(u) / st[c] : INFINITY;
    if (dist < d) {
      Spectrum T = beer(st, dist);
      float pdf = average(st * T);
      out->t = t0 + dist / len;
      out->p = ray.o + ray.d * out->t;
      out->sigma_s = sigma_s_;
      out->weight = safe_div(sigma_s_ * T, pdf);
      return true;
    }
    Spectrum T = beer(st, d);
    out->weight = safe_div(T, average(T));
    return false;
  }

  const HeteroRay r = hetero_ray(*this, ray, len);
  if (!majorant_.clip(r.o, r.d, &t0, &t1)) return false;

  if (e == VolumeEstimator::RayMarching) {
    // Hero channel c (uniform) marches to its target optical depth; inside the step where the
    // target is met the (constant) sigma_t of the step makes the revert exact and linear:
    // t = t_k + (tau_target - tau(t_k)) / sigma_t,c. The pdf is averaged over the channels
    // (balance heuristic), so each channel is unbiased with respect to the marched field.
    const int c = std::min(2, int(s.next_1d() * 3));
    const double target = free_path(s.next_1d());
    const float sc = r.st[c];
    const float h = (step > 0 ? step : march_step_) / len;
    double integral = 0, hit_integral = 0;
    float hit_t = 0, hit_rho = 0;
    bool hit = false;
    with_density(*grid_, [&](const auto& density) {
      march(r, density, t0, t1, h, &out->steps, [&](float tk, float dt, float rho) {
        if (sc > 0 && rho > 0) {
          double need = (target - double(sc) * integral) / (double(sc) * rho);  // in units of t
          if (need <= dt) {
            need = std::max(0.0, need);
            hit = true;
            hit_t = tk + float(need);
            hit_rho = rho;
            hit_integral = integral + rho * need;
            return false;
          }
        }
        integral += double(rho) * dt;
        return true;
      });
      return 0;
    });
    if (hit) {
      Spectrum T = beer(r.st, float(hit_integral));
      float pdf = average(r.st * hit_rho * T);
      out->t = hit_t;
      out->p = ray.o + ray.d * hit_t;
      out->sigma_s = sigma_s_ * hit_rho;
      out->weight = safe_div(r.ss * hit_rho * T, pdf);
      return true;
    }
    Spectrum T = beer(r.st, float(integral));
    out->weight = safe_div(T, average(T));
    return false;
  }

  // Delta tracking (Woodcock et al. 1965) against the per-cell majorant sigma_bar = maj * max_c
  // sigma_t, generalised to chromatic media as spectral tracking (Kutz et al. 2017, sec. 5.1, with
  // absorption and scattering merged into one "real" event because there is no emission): at a
  // tentative collision with weights w, the probabilities are
  //   P_real = avg(w sigma_t) / C,  P_null = avg(w |sigma_n|) / C,  C = avg(w sigma_t) + avg(w |sigma_n|),
  // sigma_n = sigma_bar - sigma_t, and the weights become w sigma_s / (sigma_bar P_real) on a real
  // collision (returned) or w sigma_n / (sigma_bar P_null) on a null one (continue). For grey media
  // these are the classic probabilities sigma_t / sigma_bar and weights albedo resp. 1.
  Spectrum w(1.0f);
  bool collided = false;
  // The control (the cells' minima) is not used here: for grey media delta tracking already samples
  // the exact free-flight distribution (only the albedo weights the collision), and decomposition
  // tracking (Kutz et al. 2017, sec. 6) would sample the same distribution, saving at most the
  // density lookup of a collision in the control (measured on cloud.vdb: the same time).
  float sigma_bar = 0;
  const Tracked end = track(
      r, t0, t1, s,
      [&](const MajorantSegment& seg, float* rate) {
        *rate = sigma_bar = seg.value * r.maj_scale;
        return true;
      },
      [&](float t, float rho) {
        const Spectrum st = r.st * rho, ss = r.ss * rho;
        const Spectrum sn = Spectrum(sigma_bar) - st;
        const float p_real = average(w * st);
        const float p_null = average(w * Spectrum(std::abs(sn.x), std::abs(sn.y), std::abs(sn.z)));
        const float total = p_real + p_null;
        if (!(total > 0)) {  // every channel's weight is zero: nothing left to estimate
          w = Spectrum(0.0f);
          return false;
        }
        if (s.next_1d() * total < p_real) {
          collided = true;
          out->t = t;
          out->p = ray.o + ray.d * t;
          out->sigma_s = sigma_s_ * rho;
          out->weight = w * ss * (total / (sigma_bar * p_real));
          return false;
        }
        w *= sn * (total / (sigma_bar * p_null));
        return true;
      });
  out->steps = end.steps;
  if (end.capped) {
    // Cap: force a collision here with the albedo as the collision weight (biased).
    count_capped();
    const Spectrum st = r.st * end.rho, ss = r.ss * end.rho;
    out->t = end.t;
    out->p = ray.o + ray.d * end.t;
    out->sigma_s = sigma_s_ * end.rho;
    for (int c = 0; c < 3; ++c) w[c] *= st[c] > 0 ? ss[c] / st[c] : 0.0f;
    out->weight = w;
    return true;
  }
  if (collided) return true;
  out->weight = w;
  return false;
}

Spectrum Medium::emission_integral(const Ray& ray, float t0, float t1, Sampler& s, VolumeEstimator e, float step,
                                   const Spectrum& sigma_other, const std::function<Spectrum(float)>* other) const {
  if (!grid_emission_ || !(t1 > t0)) return Spectrum(0.0f);
  const float len = length(ray.d);
  if (!(len > 0) || !std::isfinite(len)) return Spectrum(0.0f);
  const HeteroRay r = hetero_ray(*this, ray, len);
  const float start = t0;
  if (!majorant_.clip(r.o, r.d, &t0, &t1)) return Spectrum(0.0f);
  GridEmission::Lookup emission(*grid_emission_);
  const Spectrum so = sigma_other * len;  // the other media's homogeneous extinction per unit t
  auto others = [&](float t) { return other ? (*other)(t) : Spectrum(1.0f); };
  Spectrum L(0.0f);

  if (e == VolumeEstimator::RayMarching) {
    // Cycles' volume_integrate_heterogeneous: per step, E and sigma_t at the step's point, the
    // step's emission in closed form E (1 - e^{-sigma dt}) / sigma (volume_emission_integrate)
    // times the transmittance before it. Empty cells are marched too (emission without density).
    Spectrum T = beer(so, t0 - start);
    const float h = (step > 0 ? step : march_step_) / len;
    int steps = 0;
    with_density(*grid_, [&](const auto& density) {
      march(
          r, density, t0, t1, h, &steps,
          [&](float tk, float dt, float rho) {
            const float tm = tk + 0.5f * dt;
            const Spectrum E = emission(r.o + r.d * tm);
            const Spectrum sigma = r.st * rho + so;
            if (!is_black(E)) {
              Spectrum f;
              for (int c = 0; c < 3; ++c) {
                const double x = double(sigma[c]) * dt;
                f[c] = float(sigma[c] > 0 ? -std::expm1(-x) / sigma[c] : dt);
              }
              L += T * E * f * others(tm) * len;
            }
            T *= beer(sigma, dt);
            return max_component(T) > 1e-12f;  // the rest adds nothing a float image holds
          },
          /*skip_empty=*/false);
      return 0;
    });
    return L;
  }

  // Tentative collisions at rate sigma_bar = (max - min) x max_c sigma_t per cell (at least one per
  // voxel of the ray's index-space path, for emission where the density's majorant is 0). At a
  // collision at t the estimate of the transmittance from `start` is T_res (residual ratio tracking,
  // as transmittance()) x exp(-sigma_t x integral of min) x exp(-sigma_other (t - start)); its
  // product with E(t) / sigma_bar, summed over the collisions, is unbiased for the integral (the
  // collisions are a Poisson process of rate sigma_bar, and ratio tracking's estimate at t, given a
  // collision at t, is unbiased for T(start, t)). Russian roulette on the whole estimate.
  const float floor_rate = length(r.d);  // one collision per index unit (voxel) of travel
  Spectrum T_res(1.0f);
  double control = 0;  // integral of the minimum before the current segment, units of t
  float min = 0, rate = 0, seg_t0 = 0;
  const float pre = t0 - start;  // the other media's extinction before the domain
  const Tracked end = track(
      r, t0, t1, s,
      [&](const MajorantSegment& seg, float* sigma_bar) {
        if (seg_t0 < seg.t0 && rate > 0) control += double(min) * (seg.t0 - seg_t0);
        min = seg.min;
        seg_t0 = seg.t0;
        *sigma_bar = rate = std::max((seg.value - min) * r.maj_scale, floor_rate);
        return true;
      },
      [&](float t, float rho) {
        const Spectrum Tc = beer(r.st, float(control + double(min) * (t - seg_t0))) * beer(so, pre + (t - t0));
        const Spectrum T = T_res * Tc;
        const Spectrum E = emission(r.o + r.d * t);
        if (!is_black(E)) L += T * E * others(t) * (len / rate);
        T_res *= Spectrum(1.0f) - r.st * ((rho - min) / rate);
        const float m = max_component(T_res * Tc);
        if (m < kRouletteThreshold) {
          if (!(m > 0) || s.next_1d() < kRouletteKill) return false;
          T_res /= 1 - kRouletteKill;
        }
        return true;
      });
  if (end.capped) count_capped();
  return L;
}

}  // namespace lt
