// Density lookups into a GridData's storage, for the media sources only (the one header of
// media/ that includes NanoVDB).
#pragma once

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/SampleFromVoxels.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "media/density_grid.h"

namespace lt {

inline const nanovdb::FloatGrid* as_nano(const GridData& g) {
  return static_cast<const nanovdb::FloatGrid*>(g.nano_grid);
}

// Every node of a NanoVDB float grid's tree: leaf(const LeafNode*) for each leaf, and
// tile(origin, dim, value, active) for each tile of the internal nodes and the root (dim voxels
// per edge), in the tree's order.
template <class OnLeaf, class OnTile>
void walk_nano_tree(const GridData& g, OnLeaf&& leaf, OnTile&& tile) {
  using Root = nanovdb::FloatTree::RootType;
  using Upper = Root::ChildNodeType;
  using Lower = Upper::ChildNodeType;
  using Leaf = Lower::ChildNodeType;
  auto visit_lower = [&](const Lower* node) {
    for (uint32_t n = 0; n < Lower::SIZE; ++n) {
      if (node->data()->isChild(n))
        leaf(node->data()->getChild(n));
      else
        tile(node->offsetToGlobalCoord(n), int(Leaf::DIM), node->data()->getValue(n), node->data()->isActive(n));
    }
  };
  const Root& root = as_nano(g)->tree().root();
  for (uint32_t i = 0; i < root.tileCount(); ++i) {
    const auto* t = root.data()->tile(i);
    if (!t->isChild()) {
      tile(t->origin(), int(Upper::DIM), t->value, t->state != 0);
      continue;
    }
    const Upper* upper = root.data()->getChild(t);
    for (uint32_t n = 0; n < Upper::SIZE; ++n) {
      if (upper->data()->isChild(n))
        visit_lower(upper->data()->getChild(n));
      else
        tile(upper->offsetToGlobalCoord(n), int(Lower::DIM), upper->data()->getValue(n), upper->data()->isActive(n));
    }
  }
}

// Trilinear interpolation between the values at integer coordinates, at(i, j, k), clamped >= 0.
template <class At>
float trilinear(const At& at, const Vec3& p) {
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

// Trilinear interpolation of a dense array, zero outside it; voxel centres at integer coordinates.
struct DenseLookup {
  const float* v;
  int nx, ny, nz;
  float at(int i, int j, int k) const {
    if (unsigned(i) >= unsigned(nx) || unsigned(j) >= unsigned(ny) || unsigned(k) >= unsigned(nz)) return 0;
    return v[(size_t(k) * ny + j) * nx + i];
  }
  float operator()(const Vec3& p) const {
    return trilinear([this](int i, int j, int k) { return at(i, j, k); }, p);
  }
};

inline DenseLookup dense_lookup(const GridData& g) { return {g.dense.data(), g.dims[0], g.dims[1], g.dims[2]}; }

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
  return f(dense_lookup(g));
}

// A lookup into any grid's storage with one branch per lookup (for the grids a medium's emission
// reads beside its density; the density itself goes through with_density). Holds a NanoVDB read
// accessor (its node cache), so one per thread and estimator call.
class GridSampler {
 public:
  explicit GridSampler(const GridData& g) : dense_(dense_lookup(g)) {
    if (g.nano_grid) acc_.emplace(as_nano(g)->getAccessor());
  }
  float operator()(const Vec3& p) {  // trilinear at an index-space point, clamped >= 0
    if (!acc_) return dense_(p);
    return trilinear([this](int i, int j, int k) { return acc_->getValue(nanovdb::Coord(i, j, k)); }, p);
  }

 private:
  DenseLookup dense_;
  std::optional<nanovdb::FloatGrid::AccessorType> acc_;
};

}  // namespace lt
