// A coarse grid of per-cell upper bounds ("majorants") of a trilinearly interpolated voxel density,
// and its traversal along a ray by 3D DDA (Amanatides & Woo 1987, "A Fast Voxel Traversal
// Algorithm for Ray Tracing"), in the manner of pbrt-v4's DDAMajorantIterator.
//
// Everything is in the grid's index space, where voxel centres sit at integer coordinates and the
// density between them is interpolated trilinearly. The domain is the continuous box [lo, hi]
// (integer corners) outside which the density is zero. Cell c along an axis covers the continuous
// interval [lo + c*C, lo + (c+1)*C]; the interpolated density there depends on the voxels
// lo + c*C ... lo + (c+1)*C inclusive (C + 1 of them: the interpolation footprint reaches one voxel
// past the cell's own C), and trilinear interpolation never exceeds the largest of the 8 corners it
// blends, so the maximum over those (C+1)^3 voxels bounds the interpolated density everywhere in
// the cell (and is attained at the voxel centres on the cell, so it is also tight). Likewise each
// cell keeps a lower bound ("minorant"): the minimum over the same footprint (and the background
// where the footprint reaches voxels no node stores), clamped to >= 0; trilinear interpolation
// never falls below the smallest corner, so it bounds the density from below. It is the control
// extinction of residual ratio tracking (media/medium.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/math.h"

namespace lt {

struct GridData;

struct MajorantSegment {
  float t0 = 0, t1 = 0;  // ray parameters
  float value = 0;       // upper bound of the density on the segment
  float min = 0;         // lower bound of the density on the segment (<= value)
};

class MajorantGrid {
 public:
  MajorantGrid() = default;
  // Domain [lo, hi] in index space (hi > lo per axis), `cell` voxels per cell edge (>= 1), doubled
  // as often as needed to keep at most kMaxCells cells (2 x 64 MB of floats; cell_size() says what
  // was chosen). All cells start at 0 (upper and lower bounds).
  MajorantGrid(const int lo[3], const int hi[3], int cell);
  static constexpr int64_t kMaxCells = int64_t(1) << 24;
  // The majorants of a density grid: the domain is the non-background voxels' bounds widened by one
  // voxel (the interpolation's reach), each cell the maximum of the stored values (NanoVDB: every
  // voxel and tile, active or not, and the background) over its footprint, and their minimum
  // (clamped >= 0) as the lower bound, in the same pass. An empty grid gives an invalid grid (no
  // cells). cover_lo, cover_hi (optional): an index box the domain covers as well (a Volume
  // object's emission reaching past its density: media/leaf_region.h); the density there is the
  // grid's, usually 0.
  static MajorantGrid build(const GridData& grid, int cell, const int* cover_lo = nullptr,
                            const int* cover_hi = nullptr);

  // Raises to v the bound of every cell whose footprint contains a voxel of the inclusive index
  // box [a, b] (a voxel value, or a tile of equal values); voxels outside [lo, hi] are ignored.
  void add_voxels(const int a[3], const int b[3], float v);
  // Raises the bound of one cell, or of every cell, to v.
  void raise_cell(int x, int y, int z, float v);
  void raise_all(float v);
  // Sets every cell's lower bound to 0: residual ratio tracking then reduces to plain ratio
  // tracking (for comparisons and tests).
  void clear_minima() { minima_.assign(minima_.size(), 0.0f); }
  // The voxels in a cell's interpolation footprint along an axis: lo + c*C ... lo + (c+1)*C.
  void footprint(int axis, int c, int* v0, int* v1) const {
    *v0 = lo_[axis] + c * cell_;
    *v1 = *v0 + cell_;
  }

  int resolution(int axis) const { return res_[axis]; }
  int cell_size() const { return cell_; }
  const int* lo() const { return lo_; }
  const int* hi() const { return hi_; }
  float cell_value(int x, int y, int z) const { return values_[index(x, y, z)]; }
  float cell_min(int x, int y, int z) const { return minima_[index(x, y, z)]; }
  // The cell containing an index-space point (clamped to the grid).
  float value_at(const Vec3& p) const;
  float max_value() const;
  size_t memory_bytes() const { return (values_.capacity() + minima_.capacity()) * sizeof(float) + sizeof(*this); }
  bool valid() const { return !values_.empty(); }

  // Clips the ray o + t d (index space) to the domain; false if [t0, t1] misses it.
  bool clip(const Vec3& o, const Vec3& d, float* t0, float* t1) const;

  // Consecutive segments covering the part of [t0, t1] inside the domain, one per cell crossed, in
  // order of t. next() returns false when the ray has left the domain or reached t1.
  class Iterator {
   public:
    Iterator() = default;
    bool next(MajorantSegment* seg);

   private:
    friend class MajorantGrid;
    const MajorantGrid* grid_ = nullptr;
    int cell_[3] = {0, 0, 0}, step_[3] = {0, 0, 0};
    float t_next_[3] = {0, 0, 0}, t_delta_[3] = {0, 0, 0};
    float t_ = 0, t_end_ = 0;
    bool done_ = true;
  };
  Iterator traverse(const Vec3& o, const Vec3& d, float t0, float t1) const;

 private:
  size_t index(int x, int y, int z) const { return (size_t(z) * res_[1] + y) * res_[0] + x; }
  // Calls f(cell index, number of voxels of the box [a, b] (clipped to the domain) in the cell's
  // footprint) for every cell whose footprint meets the inclusive voxel box [a, b].
  template <class F>
  void for_cells(const int a[3], const int b[3], F&& f);

  int lo_[3] = {0, 0, 0}, hi_[3] = {0, 0, 0}, res_[3] = {0, 0, 0};
  int cell_ = 1;
  std::vector<float> values_, minima_;
};

}  // namespace lt
