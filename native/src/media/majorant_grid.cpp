#include "media/majorant_grid.h"

#include <cstdint>
#include <string>
#include <type_traits>

#include "media/grid_lookup.h"

namespace lt {

MajorantGrid::MajorantGrid(const int lo[3], const int hi[3], int cell) {
  // In 64 bits: a corrupt VDB's bounds may span the whole int32 index space (fuzz_vdb).
  int64_t extent[3], res[3], cells = 0;
  for (int a = 0; a < 3; ++a) {
    lo_[a] = lo[a];
    hi_[a] = int(std::min<int64_t>(std::max<int64_t>(hi[a], int64_t(lo[a]) + 1), INT32_MAX));
    extent[a] = int64_t(hi_[a]) - lo_[a];
  }
  // Cells double until the grid fits kMaxCells: memory stays bounded for sparse grids of wide
  // bounds (coarser bounds there cost only more null collisions).
  for (int64_t c = std::max(1, cell);; c *= 2) {
    cells = 1;
    for (int a = 0; a < 3; ++a) {
      res[a] = std::max<int64_t>(1, (extent[a] + c - 1) / c);
      cells *= res[a];
    }
    if (cells <= kMaxCells) {
      cell_ = int(c);
      break;
    }
  }
  for (int a = 0; a < 3; ++a) res_[a] = int(res[a]);
  values_.assign(size_t(cells), 0.0f);
  minima_.assign(size_t(cells), 0.0f);
}

template <class F>
void MajorantGrid::for_cells(const int a[3], const int b[3], F&& f) {
  long lo[3], hi[3];
  int c0[3], c1[3];
  for (int k = 0; k < 3; ++k) {
    // Voxel x lies in the footprint of cells c with c*C <= x - lo <= (c+1)*C.
    lo[k] = std::max<long>(a[k], lo_[k]) - lo_[k];
    hi[k] = std::min<long>(b[k], hi_[k]) - lo_[k];
    if (hi[k] < lo[k]) return;
    c0[k] = int(std::max<long>(0, (lo[k] + cell_ - 1) / cell_ - 1));
    c1[k] = int(std::min<long>(res_[k] - 1, hi[k] / cell_));
  }
  auto overlap = [&](int k, int c) {
    return std::max<long>(0, std::min<long>(hi[k], long(c + 1) * cell_) - std::max<long>(lo[k], long(c) * cell_) + 1);
  };
  for (int z = c0[2]; z <= c1[2]; ++z)
    for (int y = c0[1]; y <= c1[1]; ++y)
      for (int x = c0[0]; x <= c1[0]; ++x) f(index(x, y, z), int64_t(overlap(0, x)) * overlap(1, y) * overlap(2, z));
}

MajorantGrid MajorantGrid::build(const GridData& grid, int cell, const int* cover_lo, const int* cover_hi) {
  const bool cover = cover_lo && cover_hi;
  if (grid.empty() && !cover) return MajorantGrid();
  // The interpolated density can be non-zero only within one voxel of the non-background voxels.
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {  // clamped: a corrupt VDB may reach the int32 limits (fuzz_vdb)
    lo[a] = grid.empty() ? INT32_MAX : int(std::max<int64_t>(int64_t(grid.index_min[a]) - 1, INT32_MIN));
    hi[a] = grid.empty() ? INT32_MIN : int(std::min<int64_t>(int64_t(grid.index_max[a]) + 1, INT32_MAX));
    if (cover) {
      lo[a] = std::min(lo[a], cover_lo[a]);
      hi[a] = std::max(hi[a], cover_hi[a]);
    }
  }
  MajorantGrid maj(lo, hi, cell);
  if (grid.is_nanovdb()) {
    // Every stored value (active or not, voxel or tile) inside the domain raises the cells whose
    // footprint it lies in; regions with no node read the background.
    // The lower bounds start at +inf and fall to every stored value met; `covered` counts the
    // footprint voxels met per cell, so that a cell reaching voxels no node stores (they read the
    // background) falls to the background too.
    const float background = as_nano(grid)->tree().root().background();
    maj.raise_all(std::max(0.0f, background));
    maj.minima_.assign(maj.values_.size(), INFINITY);
    std::vector<int64_t> covered(maj.values_.size(), 0);
    auto add = [&](const int a[3], const int b[3], float v) {
      maj.add_voxels(a, b, v);
      maj.for_cells(a, b, [&](size_t i, int64_t n) {
        maj.minima_[i] = std::min(maj.minima_[i], v);
        covered[i] += n;
      });
    };
    walk_nano_tree(
        grid,
        [&](const auto* leaf) {
          for (uint32_t n = 0; n < std::remove_pointer_t<decltype(leaf)>::SIZE; ++n) {
            nanovdb::Coord c = leaf->offsetToGlobalCoord(n);
            int a[3] = {c[0], c[1], c[2]};
            add(a, a, leaf->getValue(n));
          }
        },
        [&](const nanovdb::Coord& origin, int dim, float v, bool) {
          int a[3] = {origin[0], origin[1], origin[2]}, b[3];
          for (int k = 0; k < 3; ++k) b[k] = int(std::min<int64_t>(int64_t(origin[k]) + dim - 1, INT32_MAX));
          add(a, b, v);
        });
    for (int z = 0; z < maj.res_[2]; ++z)
      for (int y = 0; y < maj.res_[1]; ++y)
        for (int x = 0; x < maj.res_[0]; ++x) {
          int64_t total = 1;
          const int c[3] = {x, y, z};
          for (int a = 0; a < 3; ++a) {
            int v0, v1;
            maj.footprint(a, c[a], &v0, &v1);
            total *= std::min(v1, maj.hi_[a]) - std::max(v0, maj.lo_[a]) + 1;
          }
          const size_t i = maj.index(x, y, z);
          float& m = maj.minima_[i];
          if (covered[i] < total) m = std::min(m, background);
          m = std::min(std::max(m, 0.0f), maj.values_[i]);
        }
    return maj;
  }
  // Dense: each cell's maximum and minimum over its footprint directly (voxels outside the array
  // read 0).
  const DenseLookup d = dense_lookup(grid);
  for (int z = 0; z < maj.res_[2]; ++z)
    for (int y = 0; y < maj.res_[1]; ++y)
      for (int x = 0; x < maj.res_[0]; ++x) {
        int v0[3], v1[3];
        const int c[3] = {x, y, z};
        bool outside = false;  // the footprint (within the domain) reaches voxels outside the array
        for (int a = 0; a < 3; ++a) {
          maj.footprint(a, c[a], &v0[a], &v1[a]);
          outside = outside || std::max(v0[a], maj.lo_[a]) < 0 || std::min(v1[a], maj.hi_[a]) > grid.dims[a] - 1;
          v0[a] = std::max(v0[a], 0);
          v1[a] = std::min(v1[a], grid.dims[a] - 1);
        }
        float mx = 0, mn = outside ? 0.0f : INFINITY;
        for (int k = v0[2]; k <= v1[2]; ++k)
          for (int j = v0[1]; j <= v1[1]; ++j)
            for (int i = v0[0]; i <= v1[0]; ++i) {
              const float v = d.at(i, j, k);
              mx = std::max(mx, v);
              mn = std::min(mn, v);
            }
        maj.raise_cell(x, y, z, mx);
        maj.minima_[maj.index(x, y, z)] = std::min(std::max(mn, 0.0f), maj.cell_value(x, y, z));
      }
  return maj;
}

void MajorantGrid::add_voxels(const int a[3], const int b[3], float v) {
  if (!(v > 0)) return;  // the density is clamped to >= 0, so 0 is every cell's floor
  for_cells(a, b, [&](size_t i, int64_t) { values_[i] = std::max(values_[i], v); });
}

void MajorantGrid::raise_cell(int x, int y, int z, float v) {
  float& m = values_[index(x, y, z)];
  m = std::max(m, v);
}

void MajorantGrid::raise_all(float v) {
  for (float& m : values_) m = std::max(m, v);
}

float MajorantGrid::value_at(const Vec3& p) const {
  int c[3];
  for (int a = 0; a < 3; ++a) c[a] = clamp(int(std::floor((p[a] - lo_[a]) / cell_)), 0, res_[a] - 1);
  return cell_value(c[0], c[1], c[2]);
}

float MajorantGrid::max_value() const {
  float m = 0;
  for (float v : values_) m = std::max(m, v);
  return m;
}

bool MajorantGrid::clip(const Vec3& o, const Vec3& d, float* t0, float* t1) const {
  float a = *t0, b = *t1;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (o[k] < lo_[k] || o[k] > hi_[k]) return false;
      continue;
    }
    float inv = 1.0f / d[k];
    float tn = (lo_[k] - o[k]) * inv, tf = (hi_[k] - o[k]) * inv;
    if (tn > tf) std::swap(tn, tf);
    a = std::max(a, tn);
    b = std::min(b, tf);
  }
  if (!(a < b)) return false;
  *t0 = a;
  *t1 = b;
  return true;
}

MajorantGrid::Iterator MajorantGrid::traverse(const Vec3& o, const Vec3& d, float t0, float t1) const {
  Iterator it;
  if (!valid() || !clip(o, d, &t0, &t1)) return it;
  it.grid_ = this;
  it.t_ = t0;
  it.t_end_ = t1;
  it.done_ = false;
  const Vec3 p = o + d * t0;
  for (int a = 0; a < 3; ++a) {
    // Position and direction in cell units relative to the domain's corner.
    float q = (p[a] - lo_[a]) / cell_, v = d[a] / cell_;
    it.cell_[a] = clamp(int(std::floor(q)), 0, res_[a] - 1);
    if (v > 0) {
      it.step_[a] = 1;
      it.t_delta_[a] = 1 / v;
      it.t_next_[a] = t0 + std::max(0.0f, (it.cell_[a] + 1 - q) / v);
    } else if (v < 0) {
      it.step_[a] = -1;
      it.t_delta_[a] = -1 / v;
      it.t_next_[a] = t0 + std::max(0.0f, (it.cell_[a] - q) / v);
    } else {
      it.step_[a] = 0;
      it.t_delta_[a] = INFINITY;
      it.t_next_[a] = INFINITY;
    }
  }
  return it;
}

bool MajorantGrid::Iterator::next(MajorantSegment* seg) {
  if (done_) return false;
  int axis = t_next_[0] < t_next_[1] ? (t_next_[0] < t_next_[2] ? 0 : 2) : (t_next_[1] < t_next_[2] ? 1 : 2);
  float tb = std::min(t_next_[axis], t_end_);
  seg->t0 = t_;
  seg->t1 = std::max(t_, tb);
  seg->value = grid_->cell_value(cell_[0], cell_[1], cell_[2]);
  seg->min = grid_->cell_min(cell_[0], cell_[1], cell_[2]);
  t_ = seg->t1;
  if (tb >= t_end_) {
    done_ = true;
  } else {
    cell_[axis] += step_[axis];
    if (cell_[axis] < 0 || cell_[axis] >= grid_->res_[axis]) done_ = true;
    t_next_[axis] += t_delta_[axis];
  }
  return true;
}

}  // namespace lt
