#include "media/density_grid.h"

#include "core/error.h"
#include "media/grid_lookup.h"

namespace lt {

GridData GridData::from_dense(std::vector<float> values, int nx, int ny, int nz, const Transform& index_to_object,
                              std::string name) {
  if (nx <= 0 || ny <= 0 || nz <= 0)
    throw InvalidArgument("dense density grid: dimensions must be positive (got " + std::to_string(nx) + " x " +
                          std::to_string(ny) + " x " + std::to_string(nz) + ")");
  if (values.size() != size_t(nx) * size_t(ny) * size_t(nz))
    throw InvalidArgument("dense density grid: " + std::to_string(values.size()) + " values for " + std::to_string(nx) +
                          " x " + std::to_string(ny) + " x " + std::to_string(nz) + " voxels");
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
  return dense_lookup(*this).at(i, j, k);
}

float GridData::interpolate(const Vec3& p) const {
  return with_density(*this, [&](const auto& density) { return density(p); });
}

size_t GridData::memory_bytes() const { return nano_grid ? nano_bytes : dense.capacity() * sizeof(float); }

}  // namespace lt
