#include "media/medium.h"

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/SampleFromVoxels.h>

#include <cstdio>
#include <limits>

#include "core/error.h"

namespace lt {

namespace {

const nanovdb::FloatGrid* as_nano(const GridData& g) { return static_cast<const nanovdb::FloatGrid*>(g.nano_grid); }

// Trilinear interpolation of a dense array, zero outside it; voxel centres at integer coordinates.
struct DenseLookup {
  const float* v;
  int nx, ny, nz;
  float at(int i, int j, int k) const {
    if (unsigned(i) >= unsigned(nx) || unsigned(j) >= unsigned(ny) || unsigned(k) >= unsigned(nz)) return 0;
    return v[(size_t(k) * ny + j) * nx + i];
  }
  float operator()(const Vec3& p) const {
    float fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
    int i = int(fx), j = int(fy), k = int(fz);
    float u = p.x - fx, w = p.y - fy, s = p.z - fz;
    float c00 = at(i, j, k) * (1 - u) + at(i + 1, j, k) * u;
    float c10 = at(i, j + 1, k) * (1 - u) + at(i + 1, j + 1, k) * u;
    float c01 = at(i, j, k + 1) * (1 - u) + at(i + 1, j, k + 1) * u;
    float c11 = at(i, j + 1, k + 1) * (1 - u) + at(i + 1, j + 1, k + 1) * u;
    float c0 = c00 * (1 - w) + c10 * w, c1 = c01 * (1 - w) + c11 * w;
    return std::max(0.0f, c0 * (1 - s) + c1 * s);
  }
};

// Calls f with a density lookup (index-space point -> interpolated density >= 0) for the grid's
// storage, so that the estimators are compiled once per storage type without a per-lookup branch.
// NanoVDB's cached trilinear sampler needs a read accessor that lives for the whole call.
template <class F>
auto with_density(const GridData& g, F&& f) {
  if (g.nano_grid) {
    auto acc = as_nano(g)->getAccessor();
    auto smp = nanovdb::createSampler<1>(acc);  // holds a reference to acc
    return f([&](const Vec3& p) { return std::max(0.0f, float(smp(nanovdb::Vec3f(p.x, p.y, p.z)))); });
  }
  DenseLookup d{g.dense.data(), g.dims[0], g.dims[1], g.dims[2]};
  return f(d);
}

Transform compose(const Transform& a, const Transform& b) {  // a after b
  Transform r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      float v = 0;
      for (int k = 0; k < 3; ++k) v += a.m[i * 4 + k] * b.m[k * 4 + j];
      r.m[i * 4 + j] = v + (j == 3 ? a.m[i * 4 + 3] : 0.0f);
    }
  }
  return r;
}

bool valid_coefficients(const Spectrum& s) { return is_finite(s) && s.x >= 0 && s.y >= 0 && s.z >= 0; }

inline float free_path(float u) { return -std::log1p(-u); }  // -ln(1 - u), u in [0, 1)

// exp(-sigma * d) per channel with 0 * inf = 0 (a channel that does not extinguish passes).
inline Spectrum beer(const Spectrum& sigma, float d) {
  Spectrum r;
  for (int c = 0; c < 3; ++c) r[c] = sigma[c] > 0 ? std::exp(-sigma[c] * d) : 1.0f;
  return r;
}

inline Spectrum safe_div(const Spectrum& a, float b) { return b > 0 && std::isfinite(b) ? a / b : Spectrum(0.0f); }

// A ray in the grid's index space with the coefficients per unit density and per unit of t.
struct HeteroRay {
  Vec3 o, d;
  float len;          // |ray.d| in world units
  Spectrum st, ss;    // sigma_t, sigma_s per unit density and per unit t
  float maj_scale;    // max channel of st: density majorant -> sigma_t majorant per unit t
  const MajorantGrid* maj;
};

// Midpoint ray marching over [a, b] (already clipped to the domain) with steps of h (units of t)
// starting at a; the last step is shortened to end at b. visit(t_start, dt, density_at_midpoint)
// returns false to stop. Steps whose midpoints fall in a majorant cell bounded by 0 are skipped
// without changing the result (their density is exactly 0).
template <class D, class V>
void march(const HeteroRay& r, const D& density, float a, float b, float h, int* steps, V&& visit) {
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
    if (seg.value <= 0) {
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

// ---- GridData -------------------------------------------------------------------------------

GridData GridData::from_dense(std::vector<float> values, int nx, int ny, int nz, const Transform& index_to_object,
                              std::string name) {
  if (nx <= 0 || ny <= 0 || nz <= 0)
    throw InvalidArgument("dense density grid: dimensions must be positive (got " + std::to_string(nx) + " x " +
                          std::to_string(ny) + " x " + std::to_string(nz) + ")");
  if (values.size() != size_t(nx) * size_t(ny) * size_t(nz))
    throw InvalidArgument("dense density grid: " + std::to_string(values.size()) + " values for " +
                          std::to_string(nx) + " x " + std::to_string(ny) + " x " + std::to_string(nz) + " voxels");
  GridData g;
  g.name = std::move(name);
  g.index_to_object = index_to_object;
  g.dims[0] = nx;
  g.dims[1] = ny;
  g.dims[2] = nz;
  int lo[3] = {nx, ny, nz}, hi[3] = {-1, -1, -1};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        float v = values[(size_t(k) * ny + j) * nx + i];
        if (!std::isfinite(v))
          throw InvalidArgument("dense density grid: non-finite value at voxel (" + std::to_string(i) + ", " +
                                std::to_string(j) + ", " + std::to_string(k) + ")");
        if (v > 0) {
          ++g.active_voxels;
          const int ijk[3] = {i, j, k};
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], ijk[a]);
            hi[a] = std::max(hi[a], ijk[a]);
          }
        }
      }
  for (int a = 0; a < 3; ++a) {
    g.index_min[a] = lo[a];
    g.index_max[a] = hi[a];
  }
  g.dense = std::move(values);
  return g;
}

float GridData::voxel(int i, int j, int k) const {
  if (nano_grid) return as_nano(*this)->tree().getValue(nanovdb::Coord(i, j, k));
  return DenseLookup{dense.data(), dims[0], dims[1], dims[2]}.at(i, j, k);
}

float GridData::interpolate(const Vec3& p) const {
  return with_density(*this, [&](const auto& density) { return density(p); });
}

size_t GridData::memory_bytes() const { return nano_grid ? nano_bytes : dense.capacity() * sizeof(float); }

Transform affine_inverse(const Transform& t) {
  const float* m = t.m;
  float det = t.determinant();
  if (!(std::abs(det) > 0) || !std::isfinite(det)) throw InvalidArgument("transform is singular (determinant 0)");
  double inv_det = 1.0 / double(det);
  // Inverse of the 3x3 linear part by cofactors.
  double a[9] = {
      double(m[5]) * m[10] - double(m[6]) * m[9], double(m[2]) * m[9] - double(m[1]) * m[10],
      double(m[1]) * m[6] - double(m[2]) * m[5],  double(m[6]) * m[8] - double(m[4]) * m[10],
      double(m[0]) * m[10] - double(m[2]) * m[8], double(m[2]) * m[4] - double(m[0]) * m[6],
      double(m[4]) * m[9] - double(m[5]) * m[8],  double(m[1]) * m[8] - double(m[0]) * m[9],
      double(m[0]) * m[5] - double(m[1]) * m[4]};
  Transform r;
  for (int i = 0; i < 3; ++i) {
    double tr = 0;
    for (int j = 0; j < 3; ++j) {
      double v = a[i * 3 + j] * inv_det;
      r.m[i * 4 + j] = float(v);
      tr -= v * m[j * 4 + 3];
    }
    r.m[i * 4 + 3] = float(tr);
  }
  return r;
}

// ---- Medium: construction and queries -------------------------------------------------------

Medium::Medium(const Medium& o)
    : sigma_a_(o.sigma_a_),
      sigma_s_(o.sigma_s_),
      phase_(o.phase_),
      emission_(o.emission_),
      empty_(o.empty_),
      emissive_(o.emissive_),
      grid_(o.grid_),
      world_to_index_(o.world_to_index_),
      majorant_(o.majorant_),
      voxel_size_(o.voxel_size_),
      march_step_(o.march_step_),
      capped_(o.capped_.load()) {}

Medium& Medium::operator=(const Medium& o) {
  if (this == &o) return *this;
  sigma_a_ = o.sigma_a_;
  sigma_s_ = o.sigma_s_;
  phase_ = o.phase_;
  emission_ = o.emission_;
  empty_ = o.empty_;
  emissive_ = o.emissive_;
  grid_ = o.grid_;
  world_to_index_ = o.world_to_index_;
  majorant_ = o.majorant_;
  voxel_size_ = o.voxel_size_;
  march_step_ = o.march_step_;
  capped_.store(o.capped_.load());
  return *this;
}

void Medium::set_emission(const Spectrum& e) {
  if (!valid_coefficients(e)) throw InvalidArgument("medium emission must be finite and >= 0");
  if (grid_ && !is_black(e)) throw InvalidArgument("emission is supported for homogeneous media only");
  emission_ = e;
  emissive_ = !is_black(e);
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
  m.voxel_size_ = std::min({length(index_to_world.column(0)), length(index_to_world.column(1)),
                            length(index_to_world.column(2))});
  m.march_step_ = m.voxel_size_;
  if (!grid->empty()) {
    // The interpolated density can be non-zero only within one voxel of the non-background voxels.
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {  // clamped: a corrupt VDB may reach the int32 limits (fuzz_vdb)
      lo[a] = int(std::max<int64_t>(int64_t(grid->index_min[a]) - 1, INT32_MIN));
      hi[a] = int(std::min<int64_t>(int64_t(grid->index_max[a]) + 1, INT32_MAX));
    }
    MajorantGrid& maj = m.majorant_ = MajorantGrid(lo, hi, majorant_cell);
    if (grid->is_nanovdb()) {
      // Every stored value (active or not, voxel or tile) inside the domain raises the cells whose
      // footprint it lies in; regions with no node read the background.
      using Tree = nanovdb::FloatTree;
      using Root = Tree::RootType;
      using Upper = Root::ChildNodeType;
      using Lower = Upper::ChildNodeType;
      using Leaf = Lower::ChildNodeType;
      const nanovdb::FloatGrid* ng = as_nano(*grid);
      const Root& root = ng->tree().root();
      maj.raise_all(std::max(0.0f, root.background()));
      auto add_tile = [&](const nanovdb::Coord& origin, int dim, float v) {
        int a[3] = {origin[0], origin[1], origin[2]}, b[3];
        for (int k = 0; k < 3; ++k) b[k] = int(std::min<int64_t>(int64_t(origin[k]) + dim - 1, INT32_MAX));
        maj.add_voxels(a, b, v);
      };
      auto visit_leaf = [&](const Leaf* leaf) {
        for (uint32_t n = 0; n < Leaf::SIZE; ++n) {
          float v = leaf->getValue(n);
          if (!(v > 0)) continue;
          nanovdb::Coord c = leaf->offsetToGlobalCoord(n);
          int a[3] = {c[0], c[1], c[2]};
          maj.add_voxels(a, a, v);
        }
      };
      auto visit_lower = [&](const Lower* node) {
        for (uint32_t n = 0; n < Lower::SIZE; ++n) {
          if (node->data()->isChild(n)) visit_leaf(node->data()->getChild(n));
          else add_tile(node->offsetToGlobalCoord(n), Leaf::DIM, node->data()->getValue(n));
        }
      };
      auto visit_upper = [&](const Upper* node) {
        for (uint32_t n = 0; n < Upper::SIZE; ++n) {
          if (node->data()->isChild(n)) visit_lower(node->data()->getChild(n));
          else add_tile(node->offsetToGlobalCoord(n), Lower::DIM, node->data()->getValue(n));
        }
      };
      for (uint32_t i = 0; i < root.tileCount(); ++i) {
        const auto* tile = root.data()->tile(i);
        if (tile->isChild()) visit_upper(root.data()->getChild(tile));
        else add_tile(tile->origin(), Upper::DIM, tile->value);
      }
    } else {
      // Dense: each cell's maximum over its footprint directly.
      DenseLookup d{grid->dense.data(), grid->dims[0], grid->dims[1], grid->dims[2]};
      for (int z = 0; z < maj.resolution(2); ++z)
        for (int y = 0; y < maj.resolution(1); ++y)
          for (int x = 0; x < maj.resolution(0); ++x) {
            int v0[3], v1[3];
            const int c[3] = {x, y, z};
            for (int a = 0; a < 3; ++a) {
              maj.footprint(a, c[a], &v0[a], &v1[a]);
              v0[a] = std::max(v0[a], 0);
              v1[a] = std::min(v1[a], grid->dims[a] - 1);
            }
            float mx = 0;
            for (int k = v0[2]; k <= v1[2]; ++k)
              for (int j = v0[1]; j <= v1[1]; ++j)
                for (int i = v0[0]; i <= v1[0]; ++i) mx = std::max(mx, d.at(i, j, k));
            maj.raise_cell(x, y, z, mx);
          }
    }
  }
  m.empty_ = grid->empty() || is_black(sigma_a + sigma_s) || !(m.majorant_.max_value() > 0);
  return m;
}

float Medium::density(const Vec3& p) const {
  if (!grid_) return 1;
  if (!majorant_.valid()) return 0;
  Vec3 q = world_to_index_.point(p);
  for (int a = 0; a < 3; ++a)
    if (!(q[a] >= majorant_.lo()[a] && q[a] <= majorant_.hi()[a])) return 0;
  return grid_->interpolate(q);
}

bool Medium::bounds(Vec3* lo, Vec3* hi) const {
  if (!grid_) return false;
  if (!majorant_.valid()) {
    *lo = *hi = Vec3(0.0f);
    return true;
  }
  Transform index_to_world = affine_inverse(world_to_index_);
  *lo = Vec3(INFINITY);
  *hi = Vec3(-INFINITY);
  for (int c = 0; c < 8; ++c) {
    Vec3 q(float((c & 1) ? majorant_.hi()[0] : majorant_.lo()[0]), float((c & 2) ? majorant_.hi()[1] : majorant_.lo()[1]),
           float((c & 4) ? majorant_.hi()[2] : majorant_.lo()[2]));
    Vec3 p = index_to_world.point(q);
    *lo = vmin(*lo, p);
    *hi = vmax(*hi, p);
  }
  return true;
}

bool Medium::clip(const Ray& ray, float* t0, float* t1) const {
  if (empty_ || !(*t0 < *t1)) return false;
  if (!grid_) return true;
  return majorant_.clip(world_to_index_.point(ray.o), world_to_index_.vector(ray.d), t0, t1);
}

size_t Medium::memory_bytes() const { return grid_ ? grid_->memory_bytes() + majorant_.memory_bytes() : 0; }

// ---- Medium: estimators ---------------------------------------------------------------------

Spectrum Medium::transmittance(const Ray& ray, float t0, float t1, Sampler& s, VolumeEstimator e, float step) const {
  if (empty_ || !(t1 > t0)) return Spectrum(1.0f);
  const float len = length(ray.d);
  if (!(len > 0) || !std::isfinite(len)) return Spectrum(1.0f);
  if (!grid_) return beer(sigma_a_ + sigma_s_, (t1 - t0) * len);  // closed form, no random numbers

  HeteroRay r{world_to_index_.point(ray.o), world_to_index_.vector(ray.d), len,
              (sigma_a_ + sigma_s_) * len, sigma_s_ * len, 0, &majorant_};
  r.maj_scale = max_component(r.st);
  if (!majorant_.clip(r.o, r.d, &t0, &t1)) return Spectrum(1.0f);

  if (e == VolumeEstimator::RayMarching) {
    // tau = sigma_t_unit * integral of the density; one scalar integral serves all channels.
    float h = (step > 0 ? step : march_step_) / len;
    double integral = 0;
    int steps = 0;
    // Stop once every extinguishing channel is below float's smallest normal number.
    float st_min = INFINITY;
    for (int c = 0; c < 3; ++c)
      if (r.st[c] > 0) st_min = std::min(st_min, r.st[c]);
    const double stop = 104.0 / st_min;
    with_density(*grid_, [&](const auto& density) {
      march(r, density, t0, t1, h, &steps, [&](float, float dt, float rho) {
        integral += double(rho) * dt;
        return integral < stop;
      });
      return 0;
    });
    return beer(r.st, float(integral));
  }

  // Ratio tracking (Novak et al. 2014) against the per-cell majorant sigma_bar = maj * max_c
  // sigma_t: T *= 1 - sigma_t(x) / sigma_bar per channel at each tentative collision; unbiased for
  // every channel because sigma_bar bounds all of them. Russian roulette once T is small
  // (pbrt-v4) keeps dense media cheap without bias.
  return with_density(*grid_, [&](const auto& density) {
    Spectrum T(1.0f);
    int steps = 0;
    MajorantGrid::Iterator it = majorant_.traverse(r.o, r.d, t0, t1);
    MajorantSegment seg;
    while (it.next(&seg)) {
      const float sigma_bar = seg.value * r.maj_scale;
      if (!(sigma_bar > 0)) continue;
      float t = seg.t0;
      for (;;) {
        t += free_path(s.next_1d()) / sigma_bar;
        if (t >= seg.t1) break;
        if (++steps > kMaxTrackingSteps) {
          count_capped();
          return Spectrum(0.0f);
        }
        const float rho = density(r.o + r.d * t);
        T *= Spectrum(1.0f) - r.st * (rho / sigma_bar);
        const float m = max_component(T);
        if (m < kRouletteThreshold) {
          if (!(m > 0) || s.next_1d() < kRouletteKill) return Spectrum(0.0f);
          T /= 1 - kRouletteKill;
        }
      }
    }
    return T;
  });
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

  HeteroRay r{world_to_index_.point(ray.o), world_to_index_.vector(ray.d), len,
              (sigma_a_ + sigma_s_) * len, sigma_s_ * len, 0, &majorant_};
  r.maj_scale = max_component(r.st);
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
  return with_density(*grid_, [&](const auto& density) {
    Spectrum w(1.0f);
    int& steps = out->steps;
    MajorantGrid::Iterator it = majorant_.traverse(r.o, r.d, t0, t1);
    MajorantSegment seg;
    while (it.next(&seg)) {
      const float sigma_bar = seg.value * r.maj_scale;
      if (!(sigma_bar > 0)) continue;
      float t = seg.t0;
      for (;;) {
        t += free_path(s.next_1d()) / sigma_bar;
        if (t >= seg.t1) break;
        const float rho = density(r.o + r.d * t);
        const Spectrum st = r.st * rho, ss = r.ss * rho;
        if (++steps > kMaxTrackingSteps) {
          // Cap: force a collision here with the albedo as the collision weight (biased).
          count_capped();
          out->t = t;
          out->p = ray.o + ray.d * t;
          out->sigma_s = sigma_s_ * rho;
          for (int c = 0; c < 3; ++c) w[c] *= st[c] > 0 ? ss[c] / st[c] : 0.0f;
          out->weight = w;
          return true;
        }
        const Spectrum sn = Spectrum(sigma_bar) - st;
        const float p_real = average(w * st);
        const float p_null = average(w * Spectrum(std::abs(sn.x), std::abs(sn.y), std::abs(sn.z)));
        const float total = p_real + p_null;
        if (!(total > 0)) {  // every channel's weight is zero: nothing left to estimate
          out->weight = Spectrum(0.0f);
          return false;
        }
        if (s.next_1d() * total < p_real) {
          out->t = t;
          out->p = ray.o + ray.d * t;
          out->sigma_s = sigma_s_ * rho;
          out->weight = w * ss * (total / (sigma_bar * p_real));
          return true;
        }
        w *= sn * (total / (sigma_bar * p_null));
      }
    }
    out->weight = w;
    return false;
  });
}

}  // namespace lt
