#include "media/leaf_region.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "media/grid_lookup.h"

namespace lt {

namespace {

constexpr int L = LeafRegion::kLeaf;

int64_t floor_div(int64_t i, int64_t n) { return i >= 0 ? i / n : -((-i + n - 1) / n); }

// Which of a leaf's voxels are kept: any at all, and any on each of its six faces (those dilate
// into the neighbouring leaf: -x, +x, -y, +y, -z, +z).
struct LeafFaces {
  bool any = false, face[6] = {false, false, false, false, false, false};
  void keep(int x, int y, int z) {  // offsets 0..7 within the leaf
    any = true;
    const int o[3] = {x, y, z};
    for (int a = 0; a < 3; ++a) {
      face[2 * a] = face[2 * a] || o[a] == 0;
      face[2 * a + 1] = face[2 * a + 1] || o[a] == L - 1;
    }
  }
};

}  // namespace

void LeafRegion::add_leaves(const int64_t a[3], const int64_t b[3]) {
  Box box;
  for (int k = 0; k < 3; ++k) {
    if (b[k] < a[k]) return;
    box.a[k] = a[k];
    box.b[k] = b[k];
  }
  boxes_.push_back(box);
}

void LeafRegion::cover_voxels(const int64_t a[3], const int64_t b[3]) {
  for (int k = 0; k < 3; ++k) {
    vlo_[k] = std::min(vlo_[k], a[k]);
    vhi_[k] = std::max(vhi_[k], b[k]);
  }
}

bool LeafRegion::voxel_span(int64_t n[3]) const {
  if (vhi_[0] < vlo_[0]) return false;
  for (int k = 0; k < 3; ++k) n[k] = vhi_[k] - vlo_[k] + 1;
  return true;
}

void LeafRegion::add_grid(const GridData& g, float clipping, const Transform& grid_to_here) {
  if (!grid_to_here.is_identity()) {
    // Each of the grid's own leaves adds the leaves here that its mapped box overlaps.
    LeafRegion own;
    own.add_grid(g, clipping);
    own.finish();
    auto add_mapped = [&](const int64_t a[3], const int64_t b[3]) {
      Vec3 lo, hi;
      grid_to_here.map_box(Vec3(float(L * a[0] - 0.5), float(L * a[1] - 0.5), float(L * a[2] - 0.5)),
                           Vec3(float(L * (b[0] + 1) - 0.5), float(L * (b[1] + 1) - 0.5), float(L * (b[2] + 1) - 0.5)),
                           &lo, &hi);
      int64_t la[3], lb[3];
      for (int k = 0; k < 3; ++k) {
        la[k] = int64_t(std::floor((double(lo[k]) + 0.5) / L));
        lb[k] = int64_t(std::floor((double(hi[k]) + 0.5) / L));
      }
      add_leaves(la, lb);
    };
    if (own.empty()) return;
    {
      Vec3 lo, hi;
      grid_to_here.map_box(Vec3(float(own.vlo_[0]), float(own.vlo_[1]), float(own.vlo_[2])),
                           Vec3(float(own.vhi_[0]), float(own.vhi_[1]), float(own.vhi_[2])), &lo, &hi);
      const int64_t a[3] = {int64_t(std::floor(lo.x)), int64_t(std::floor(lo.y)), int64_t(std::floor(lo.z))};
      const int64_t b[3] = {int64_t(std::ceil(hi.x)), int64_t(std::ceil(hi.y)), int64_t(std::ceil(hi.z))};
      cover_voxels(a, b);
    }
    if (own.bits_.empty()) {
      int64_t b[3];
      for (int k = 0; k < 3; ++k) b[k] = own.lo_[k] + own.res_[k] - 1;
      add_mapped(own.lo_, b);
      return;
    }
    for (int64_t z = 0; z < own.res_[2]; ++z)
      for (int64_t y = 0; y < own.res_[1]; ++y)
        for (int64_t x = 0; x < own.res_[0]; ++x) {
          const int64_t i = (z * own.res_[1] + y) * own.res_[0] + x;
          if (!(own.bits_[i >> 6] >> (i & 63) & 1)) continue;
          const int64_t c[3] = {own.lo_[0] + x, own.lo_[1] + y, own.lo_[2] + z};
          add_mapped(c, c);
        }
    return;
  }

  auto kept = [&](float v) { return std::abs(v) >= clipping; };
  auto keep_voxel = [&](LeafFaces& f, int64_t i, int64_t j, int64_t k, int x, int y, int z) {
    f.keep(x, y, z);
    const int64_t a[3] = {i - 1, j - 1, k - 1}, b[3] = {i + 1, j + 1, k + 1};  // with the dilation
    cover_voxels(a, b);
  };
  // A leaf's kept voxels: the leaf itself, and across each face that has one the neighbour.
  auto add_leaf = [&](const int64_t leaf[3], const LeafFaces& f) {
    if (!f.any) return;
    add_leaves(leaf, leaf);
    for (int a = 0; a < 3; ++a)
      for (int s = 0; s < 2; ++s) {
        if (!f.face[2 * a + s]) continue;
        int64_t n[3] = {leaf[0], leaf[1], leaf[2]};
        n[a] += s ? 1 : -1;
        add_leaves(n, n);
      }
  };
  // An active tile: the leaves it covers, not dilated (Cycles' IGNORE_TILES).
  auto add_tile = [&](const nanovdb::Coord& origin, int dim, float v) {
    if (!kept(v)) return;
    int64_t a[3], b[3];
    for (int k = 0; k < 3; ++k) {
      a[k] = floor_div(origin[k], L);
      b[k] = floor_div(int64_t(origin[k]) + dim - 1, L);
    }
    add_leaves(a, b);
    const int64_t va[3] = {origin[0], origin[1], origin[2]};
    const int64_t vb[3] = {int64_t(origin[0]) + dim - 1, int64_t(origin[1]) + dim - 1, int64_t(origin[2]) + dim - 1};
    cover_voxels(va, vb);
  };

  if (g.is_nanovdb()) {
    walk_nano_tree(
        g,
        [&](const auto* leaf) {
          static_assert(std::remove_pointer_t<decltype(leaf)>::DIM == L, "NanoVDB's leaves are OpenVDB's (Cycles')");
          LeafFaces f;
          const nanovdb::Coord o = leaf->origin();
          for (uint32_t n = 0; n < L * L * L; ++n)
            if (leaf->isActive(n) && kept(leaf->getValue(n))) {
              const int x = int(n >> 6), y = int(n >> 3 & 7), z = int(n & 7);
              keep_voxel(f, int64_t(o[0]) + x, int64_t(o[1]) + y, int64_t(o[2]) + z, x, y, z);
            }
          const int64_t c[3] = {floor_div(o[0], L), floor_div(o[1], L), floor_div(o[2], L)};
          add_leaf(c, f);
        },
        [&](const nanovdb::Coord& origin, int dim, float v, bool active) {
          if (active) add_tile(origin, dim, v);
        });
    return;
  }
  // Dense storage: every voxel of the array is active.
  const DenseLookup d = dense_lookup(g);
  for (int lz = 0; lz * L < g.dims[2]; ++lz)
    for (int ly = 0; ly * L < g.dims[1]; ++ly)
      for (int lx = 0; lx * L < g.dims[0]; ++lx) {
        LeafFaces f;
        for (int z = 0; z < L; ++z)
          for (int y = 0; y < L; ++y)
            for (int x = 0; x < L; ++x) {
              const int i = lx * L + x, j = ly * L + y, k = lz * L + z;
              if (i < g.dims[0] && j < g.dims[1] && k < g.dims[2] && kept(d.at(i, j, k)))
                keep_voxel(f, i, j, k, x, y, z);
            }
        const int64_t c[3] = {lx, ly, lz};
        add_leaf(c, f);
      }
}

void LeafRegion::finish() {
  bits_.clear();
  if (boxes_.empty()) return;
  int64_t lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = boxes_[0].a[k];
    hi[k] = boxes_[0].b[k];
  }
  for (const Box& b : boxes_)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], b.a[k]);
      hi[k] = std::max(hi[k], b.b[k]);
    }
  double count = 1;
  for (int k = 0; k < 3; ++k) {
    lo_[k] = lo[k];
    res_[k] = hi[k] - lo[k] + 1;
    count *= double(res_[k]);
  }
  if (count > double(kMaxLeaves)) return;  // the bounding box stands for the region
  bits_.assign(size_t((int64_t(count) + 63) / 64), 0);
  for (const Box& b : boxes_)
    for (int64_t z = b.a[2]; z <= b.b[2]; ++z)
      for (int64_t y = b.a[1]; y <= b.b[1]; ++y)
        for (int64_t x = b.a[0]; x <= b.b[0]; ++x) {
          const int64_t i = ((z - lo_[2]) * res_[1] + (y - lo_[1])) * res_[0] + (x - lo_[0]);
          bits_[size_t(i >> 6)] |= uint64_t(1) << (i & 63);
        }
}

bool LeafRegion::contains(const Vec3& q) const {
  if (boxes_.empty()) return false;
  int64_t c[3];
  for (int k = 0; k < 3; ++k) {
    const double l = std::floor((double(q[k]) - double(shift_[k]) + 0.5) / L);
    if (!(l >= double(lo_[k]) && l < double(lo_[k] + res_[k]))) return false;
    c[k] = int64_t(l) - lo_[k];
  }
  if (bits_.empty()) return true;
  const int64_t i = (c[2] * res_[1] + c[1]) * res_[0] + c[0];
  return bits_[size_t(i >> 6)] >> (i & 63) & 1;
}

bool LeafRegion::bounds(int lo[3], int hi[3]) const {
  if (boxes_.empty()) return false;
  for (int k = 0; k < 3; ++k) {
    const double a = std::floor(double(L) * double(lo_[k]) - 0.5 + shift_[k]);
    const double b = std::ceil(double(L) * double(lo_[k] + res_[k]) - 0.5 + shift_[k]);
    lo[k] = int(std::clamp(a, double(INT32_MIN), double(INT32_MAX)));
    hi[k] = int(std::clamp(b, double(INT32_MIN), double(INT32_MAX)));
  }
  return true;
}

LeafRegion volume_mesh_region(const std::vector<const GridData*>& grids, float clipping, float face_offset) {
  LeafRegion region;
  if (grids.empty()) return region;
  const Transform object_to_density = affine_inverse(grids[0]->index_to_object);
  for (const GridData* g : grids) region.add_grid(*g, clipping, compose(object_to_density, g->index_to_object));
  region.finish();
  int64_t span[3];
  if (face_offset != 0 && region.voxel_span(span))
    region.set_shift(object_to_density.vector(
        Vec3(face_offset / float(span[0]), face_offset / float(span[1]), face_offset / float(span[2]))));
  return region;
}

}  // namespace lt
