// The region a Volume object's emission fills (media/leaf_region.h, Cycles 3.4's volume mesh):
// clipped active voxels dilated across faces, rounded out to 8^3 leaves; tiles not dilated; and a
// constant emission that fills that region where the density is zero.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "../scenes/make_test_vdb.h"
#include "io/vdb.h"
#include "media/grid_emission.h"
#include "media/leaf_region.h"
#include "media/medium.h"
#include "media/volume_material.h"
#include "test_media_util.h"

namespace lt {
namespace {

using media_test::Mean;
using media_test::within_se;

std::string vdb(const std::string& name) { return std::string(LANTERN_TEST_VDB_DIR) + "/" + name; }

// A leaf's centre in index space (leaf b covers [8b - 0.5, 8b + 7.5)).
Vec3 leaf_centre(int x, int y, int z) { return Vec3(8.0f * x + 3.5f, 8.0f * y + 3.5f, 8.0f * z + 3.5f); }

GridData dense(int nx, int ny, int nz, std::initializer_list<std::pair<std::array<int, 3>, float>> voxels) {
  std::vector<float> v(size_t(nx) * ny * nz, 0.0f);
  for (const auto& [c, value] : voxels) v[(size_t(c[2]) * ny + c[1]) * nx + c[0]] = value;
  return GridData::from_dense(v, nx, ny, nz);
}

TEST(LeafRegion, DilatesAcrossFacesOnlyAndClips) {
  // (7, 3, 3) is on leaf 0's +x face: leaf 1 along x joins. (7, 7, 11) is on +x, +y faces of leaf
  // (0, 0, 1): (1, 0, 1) and (0, 1, 1) join, not the diagonal (1, 1, 1). (20, 3, 3) is under the
  // clipping.
  const GridData g = dense(32, 16, 16, {{{7, 3, 3}, 1.0f}, {{7, 7, 11}, 0.5f}, {{20, 3, 3}, 0.0005f}});
  LeafRegion r;
  r.add_grid(g, 0.001f);
  r.finish();
  auto in = [&](int x, int y, int z) { return r.contains(leaf_centre(x, y, z)); };
  EXPECT_TRUE(in(0, 0, 0));
  EXPECT_TRUE(in(1, 0, 0));
  EXPECT_FALSE(in(2, 0, 0));  // clipped
  EXPECT_FALSE(in(0, 1, 0));
  EXPECT_TRUE(in(0, 0, 1));
  EXPECT_TRUE(in(1, 0, 1));
  EXPECT_TRUE(in(0, 1, 1));
  EXPECT_FALSE(in(1, 1, 1));  // faces only (Cycles' NN_FACE dilation)
  EXPECT_FALSE(in(-1, 0, 0));
  // Leaf boundaries at 8b - 0.5.
  EXPECT_TRUE(r.contains(Vec3(-0.49f, 3, 3)));
  EXPECT_FALSE(r.contains(Vec3(-0.51f, 3, 3)));
  EXPECT_TRUE(r.contains(Vec3(15.49f, 3, 3)));
  EXPECT_FALSE(r.contains(Vec3(15.51f, 3, 3)));
  int lo[3], hi[3];
  ASSERT_TRUE(r.bounds(lo, hi));
  EXPECT_EQ(lo[0], -1);
  EXPECT_EQ(hi[0], 16);
  EXPECT_EQ(lo[1], -1);
  EXPECT_EQ(hi[1], 16);
  EXPECT_EQ(hi[2], 16);

  LeafRegion lower;  // a lower clipping keeps (20, 3, 3): leaf 2, not dilated (not on a face)
  lower.add_grid(g, 0.0001f);
  lower.finish();
  EXPECT_TRUE(lower.contains(leaf_centre(2, 0, 0)));
  EXPECT_FALSE(lower.contains(leaf_centre(3, 0, 0)));

  LeafRegion none;
  none.add_grid(dense(8, 8, 8, {{{3, 3, 3}, 0.0005f}}), 0.001f);
  none.finish();
  EXPECT_TRUE(none.empty());
  EXPECT_FALSE(none.contains(leaf_centre(0, 0, 0)));
  EXPECT_FALSE(none.bounds(lo, hi));
}

TEST(LeafRegion, NanoVdbLeavesMatchTheirVoxels) {
  // fire.vdb's flame (NanoVDB): every leaf's membership against a brute-force pass over its
  // voxels (active voxels are the non-zero ones there), at two clippings.
  const GridData g = load_density_grid(vdb("fire.vdb"), "flame");
  ASSERT_TRUE(g.is_nanovdb());
  for (float clip : {0.001f, 0.3f}) {
    LeafRegion r;
    r.add_grid(g, clip);
    r.finish();
    auto kept = [&](int i, int j, int k) { return std::abs(g.voxel(i, j, k)) >= clip && g.voxel(i, j, k) != 0; };
    int inside = 0, outside = 0;
    for (int z = -2; z <= 6; ++z)
      for (int y = -2; y <= 5; ++y)
        for (int x = -2; x <= 5; ++x) {
          bool expect = false;
          for (int k = 8 * z - 1; k <= 8 * z + 8 && !expect; ++k)
            for (int j = 8 * y - 1; j <= 8 * y + 8 && !expect; ++j)
              for (int i = 8 * x - 1; i <= 8 * x + 8 && !expect; ++i) {
                const int out =
                    (i < 8 * x || i > 8 * x + 7) + (j < 8 * y || j > 8 * y + 7) + (k < 8 * z || k > 8 * z + 7);
                expect = out <= 1 && kept(i, j, k);  // in the leaf, or a face neighbour of it
              }
          EXPECT_EQ(r.contains(leaf_centre(x, y, z)), expect)
              << "leaf " << x << " " << y << " " << z << " clip " << clip;
          (expect ? inside : outside)++;
        }
    EXPECT_GT(inside, 0);
    EXPECT_GT(outside, 0);
  }
}

TEST(LeafRegion, TilesAreLeavesWithoutDilation) {
  // tiles.vdb: box A [0, 31]^3 in leaf-sized tiles, box B [128, 255]^3 one upper-node tile.
  const GridData g = load_density_grid(vdb("tiles.vdb"));
  LeafRegion r;
  r.add_grid(g, 0.001f);
  r.finish();
  EXPECT_TRUE(r.contains(leaf_centre(0, 0, 0)));
  EXPECT_TRUE(r.contains(leaf_centre(3, 3, 3)));
  EXPECT_FALSE(r.contains(leaf_centre(4, 0, 0)));
  EXPECT_FALSE(r.contains(leaf_centre(-1, 0, 0)));
  EXPECT_FALSE(r.contains(leaf_centre(10, 10, 10)));
  EXPECT_TRUE(r.contains(leaf_centre(16, 16, 16)));
  EXPECT_TRUE(r.contains(leaf_centre(31, 20, 16)));
  EXPECT_FALSE(r.contains(leaf_centre(32, 20, 16)));
  EXPECT_FALSE(r.contains(leaf_centre(15, 20, 16)));
}

TEST(LeafRegion, AnotherIndexSpaceAddsTheLeavesItsBoxesOverlap) {
  // A grid of half-size voxels shifted by 16 (its index 2q + 32 is this space's q): its leaf 0
  // covers this space's [-16.25, -12.25): this space's leaves -2 (from -16.5) only.
  const GridData fine = dense(8, 8, 8, {{{3, 3, 3}, 1.0f}});
  Transform fine_to_here;
  fine_to_here.m[0] = fine_to_here.m[5] = fine_to_here.m[10] = 0.5f;
  fine_to_here.m[3] = fine_to_here.m[7] = fine_to_here.m[11] = -16.0f;
  LeafRegion r;
  r.add_grid(fine, 0.001f, fine_to_here);
  r.finish();
  EXPECT_TRUE(r.contains(Vec3(-14.0f, -14.0f, -14.0f)));
  EXPECT_TRUE(r.contains(leaf_centre(-2, -2, -2)));
  EXPECT_FALSE(r.contains(leaf_centre(-1, -2, -2)));
  EXPECT_FALSE(r.contains(leaf_centre(-3, -2, -2)));
}

TEST(LeafRegion, ConstantEmissionFillsTheRegionBeyondTheDensity) {
  // Density on voxels 6..9 of a 16^3 array (domain [5, 10] before); leaves 0 and 1 per axis hold
  // it, so the region is [-0.5, 15.5)^3. A constant emission E along x at y = z = 2 (no density
  // there) integrates to E x 16 voxels; without the region it was 0 (outside the density's domain).
  std::vector<float> v(16 * 16 * 16, 0.0f);
  for (int k = 6; k <= 9; ++k)
    for (int j = 6; j <= 9; ++j)
      for (int i = 6; i <= 9; ++i) v[(k * 16 + j) * 16 + i] = 1.0f;
  auto d = std::make_shared<const GridData>(GridData::from_dense(v, 16, 16, 16));
  EmissionComponent c;
  c.strength = {0.5f, -1};
  c.color = Spectrum(1.0f, 0.5f, 0.25f);
  auto make = [&](bool with_region) {
    Medium m = Medium::heterogeneous(d, Spectrum(1.0f), Spectrum(1.0f), 0.0f);
    auto e = std::make_shared<GridEmission>(std::vector<std::shared_ptr<const GridData>>{},
                                            std::vector<EmissionComponent>{c}, d->index_to_object);
    if (with_region) {
      LeafRegion r;
      r.add_grid(*d, 0.001f);
      r.finish();
      e->set_region(std::move(r));
    }
    m.set_grid_emission(e);
    return m;
  };
  const Medium with = make(true), without = make(false);
  const Spectrum E = principled_volume_emission(c.strength.value, c.color, 0, Spectrum(0.0f), 0);
  ASSERT_FALSE(is_black(E));
  EXPECT_TRUE(is_black(without.emission_at(Vec3(3.0f, 2.0f, 2.0f))));
  EXPECT_EQ(with.emission_at(Vec3(3.0f, 2.0f, 2.0f))[2], E[2]);
  EXPECT_EQ(with.emission_at(Vec3(15.4f, 2.0f, 2.0f))[0], E[0]);
  EXPECT_TRUE(is_black(with.emission_at(Vec3(15.6f, 2.0f, 2.0f))));
  EXPECT_TRUE(is_black(with.emission_at(Vec3(3.0f, 2.0f, 15.6f))));
  Vec3 lo, hi;
  ASSERT_TRUE(with.bounds(&lo, &hi));
  EXPECT_LE(lo.x, -0.5f);
  EXPECT_GE(hi.x, 15.5f);

  Ray r;
  r.o = Vec3(-10.0f, 2.0f, 2.0f);
  r.d = Vec3(2.0f, 0.0f, 0.0f);  // not unit: the integral is per world unit
  const Spectrum expected = E * 16.0f;
  Sampler s(media_test::seed(91), 0, 0);
  EXPECT_TRUE(is_black(without.emission_integral(r, 0, 20, s, VolumeEstimator::Tracking, 0, Spectrum(0.0f), nullptr)));
  Mean m;
  for (int i = 0; i < 20000; ++i) {
    Sampler si(media_test::seed(92), uint32_t(i), 0);
    m.add(with.emission_integral(r, 0, 20, si, VolumeEstimator::Tracking, 0, Spectrum(0.0f), nullptr)[0]);
  }
  EXPECT_TRUE(within_se(m, expected[0]));
  // Ray marching at a twentieth of a voxel: exact up to the step that straddles each end.
  const Spectrum marched =
      with.emission_integral(r, 0, 20, s, VolumeEstimator::RayMarching, 0.05f, Spectrum(0.0f), nullptr);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(marched[k], expected[k], 2 * 0.05f * E[k]);
}

}  // namespace
}  // namespace lt
