// A scalar voxel grid (a heterogeneous medium's density): NanoVDB or dense storage, voxel
// centres at integer index coordinates, trilinear interpolation between them (Cycles' convention).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/math.h"

namespace lt {

// Values are interpolated trilinearly and clamped to >= 0. Either a NanoVDB float grid (from
// io/vdb.h) or a dense array.
struct GridData {
  std::string name;
  Transform index_to_object;  // index space -> object space (the VDB's linear transform)
  int index_min[3] = {0, 0, 0}, index_max[3] = {-1, -1, -1};  // inclusive bounds of non-background voxels
  uint64_t active_voxels = 0;                                 // VDB: active voxels; dense: non-zero voxels
  float background = 0;

  // NanoVDB storage: nano_owner keeps the buffer alive (a nanovdb::GridHandle<HostBuffer>, type
  // erased so that this header needs no NanoVDB), nano_grid points at the nanovdb::FloatGrid in it.
  std::shared_ptr<void> nano_owner;
  const void* nano_grid = nullptr;
  size_t nano_bytes = 0;

  // Dense storage: value (i, j, k) at dense[(k * dims[1] + j) * dims[0] + i], index coordinates
  // (i, j, k); zero outside.
  std::vector<float> dense;
  int dims[3] = {0, 0, 0};

  // Throws InvalidArgument for non-positive dimensions, a size mismatch or non-finite values.
  static GridData from_dense(std::vector<float> values, int nx, int ny, int nz,
                             const Transform& index_to_object = Transform(), std::string name = "density");

  bool empty() const { return index_max[0] < index_min[0]; }
  bool is_nanovdb() const { return nano_grid != nullptr; }
  float voxel(int i, int j, int k) const;  // the stored value (background / 0 outside)
  float interpolate(const Vec3& p) const;  // trilinear at an index-space point, clamped >= 0
  size_t memory_bytes() const;             // NanoVDB buffer or dense array
};

}  // namespace lt
