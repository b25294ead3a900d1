// The part of a Volume object that Cycles 3.4 shades (scene/volume.cpp, VolumeMeshBuilder): the
// active voxels of every grid its shader reads whose |value| >= the Volume's Clipping (Render >
// Clipping, 0.001 by default), dilated by one voxel across faces (linear interpolation's padding;
// active tiles are not dilated), rounded out to whole 8^3 leaves. Cycles' volume mesh encloses
// these leaves and shades nothing outside them, so a constant emission fills exactly this blocky
// region, not the grids' bounding box.
//
// In a grid's index space (voxel centres at integer coordinates), leaf b covers the cells of
// voxels 8b ... 8b + 7, i.e. [8b - 0.5, 8b + 7.5) along each axis, moved by the region's shift
// (Cycles moves each volume mesh a little to keep faces of overlapping volumes apart).
#pragma once

#include <climits>
#include <cstdint>
#include <vector>

#include "core/math.h"

namespace lt {

struct GridData;

class LeafRegion {
 public:
  static constexpr int kLeaf = 8;
  // Beyond this many leaves in the bounding box the box stands for the region (16 MB of bits).
  static constexpr int64_t kMaxLeaves = int64_t(1) << 27;

  // Adds the leaves of `grid` for the given clipping; grid_to_here maps its index space to this
  // region's (each of its leaves then adds the leaves here that its mapped box overlaps).
  void add_grid(const GridData& grid, float clipping, const Transform& grid_to_here = Transform());
  // Adds the inclusive box [a, b] of leaf coordinates.
  void add_leaves(const int64_t a[3], const int64_t b[3]);
  // Builds the lookup; call after the last add (adding again needs another finish).
  void finish();

  // Moves the region by `s` (index units; Cycles' face_overlap_avoidance).
  void set_shift(const Vec3& s) { shift_ = s; }
  // The voxels across the bounding box of the active voxels after the dilation (tiles whole), per
  // axis (Cycles' topology grid's active bounding box); false if there are none.
  bool voxel_span(int64_t n[3]) const;

  bool empty() const { return boxes_.empty(); }
  // Whether the index-space point q lies in the region (finished regions only).
  bool contains(const Vec3& q) const;
  // The integer index-space box [lo, hi] that holds the region; false if it is empty.
  bool bounds(int lo[3], int hi[3]) const;
  size_t memory_bytes() const { return bits_.capacity() * sizeof(uint64_t) + boxes_.capacity() * sizeof(Box); }

 private:
  struct Box {
    int64_t a[3], b[3];
  };
  void cover_voxels(const int64_t a[3], const int64_t b[3]);

  std::vector<Box> boxes_;  // what was added, in leaf coordinates
  int64_t vlo_[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, vhi_[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
  Vec3 shift_{0.0f};
  int64_t lo_[3] = {0, 0, 0}, res_[3] = {0, 0, 0};
  std::vector<uint64_t> bits_;  // a bit per leaf of the bounding box; empty: the whole box
};

// Cycles' volume mesh of a Volume object whose shader reads `grids` (the density's first), in the
// density's index space: every grid's leaves at `clipping`, moved by face_offset / (voxels across
// the active box) per axis in object space (face_overlap_avoidance: 0.1 x hash_uint_to_float(
// hash_string(the Volume datablock's name))). Finished.
LeafRegion volume_mesh_region(const std::vector<const GridData*>& grids, float clipping, float face_offset);

}  // namespace lt
