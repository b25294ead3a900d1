// Loading OpenVDB density grids (io/vdb.h) from the small files tests/scenes/make_test_vdb writes
// at build time: values, transform and bounds as written, agreement of the NanoVDB path with the
// dense path, the majorant over tiles, and clear errors (never a crash) for every bad input.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>

#include "../scenes/make_test_vdb.h"
#include "core/error.h"
#include "io/vdb.h"
#include "media/medium.h"
#include "test_media_util.h"

namespace lt {
namespace {

namespace tv = test_vdb;
using media_test::Mean;
using media_test::within_se;

std::string vdb(const std::string& name) { return std::string(LANTERN_TEST_VDB_DIR) + "/" + name; }

std::string error_of(const std::function<void()>& f, std::string* kind) {
  try {
    f();
  } catch (const IoError& e) {
    *kind = "IoError";
    return e.what();
  } catch (const InvalidArgument& e) {
    *kind = "InvalidArgument";
    return e.what();
  } catch (const std::exception& e) {
    *kind = "other";
    return e.what();
  }
  *kind = "none";
  return "";
}

Ray make_ray(const Vec3& o, const Vec3& d) {
  Ray r;
  r.o = o;
  r.d = d;
  return r;
}

TEST(VdbLoad, DensityGridValuesTransformAndBounds) {
  GridData g = load_density_grid(vdb("density.vdb"));
  EXPECT_EQ(g.name, "density");
  EXPECT_TRUE(g.is_nanovdb());
  EXPECT_EQ(g.active_voxels, 16u * 16u * 16u);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(g.index_min[a], tv::kMin[a]);
    EXPECT_EQ(g.index_max[a], tv::kMax[a]);
    EXPECT_NEAR(length(g.index_to_object.column(a)), tv::kVoxelSize, 1e-7);
    EXPECT_NEAR(g.index_to_object.m[a * 4 + 3], tv::kTranslation[a], 1e-6);
  }
  const int probes[][3] = {{-3, 0, 2}, {12, 15, 17}, {0, 0, 2}, {5, 7, 9}, {-1, 13, 4}};
  for (auto& p : probes) EXPECT_FLOAT_EQ(g.voxel(p[0], p[1], p[2]), float(tv::ramp(p[0], p[1], p[2])));
  EXPECT_EQ(g.voxel(-4, 0, 2), 0.0f);  // outside: background
  // Voxel centres at integer index coordinates, trilinear in between: the ramp is reproduced.
  Sampler s(media_test::seed(101), 0, 0);
  for (int i = 0; i < 1000; ++i) {
    Vec3 p(tv::kMin[0] + s.next_1d() * (tv::kMax[0] - tv::kMin[0]),
           tv::kMin[1] + s.next_1d() * (tv::kMax[1] - tv::kMin[1]),
           tv::kMin[2] + s.next_1d() * (tv::kMax[2] - tv::kMin[2]));
    ASSERT_NEAR(g.interpolate(p), tv::ramp(p.x, p.y, p.z), 2e-6) << p.x << " " << p.y << " " << p.z;
  }
  // A world point through the medium (object = world): index (5, 7, 9) sits at translation + 0.1 * ijk.
  Medium m = Medium::heterogeneous(std::make_shared<const GridData>(std::move(g)), Spectrum(1.0f), Spectrum(0.0f), 0);
  Vec3 w(float(tv::kTranslation[0] + 0.5), float(tv::kTranslation[1] + 0.7), float(tv::kTranslation[2] + 0.9));
  EXPECT_NEAR(m.density(w), tv::ramp(5, 7, 9), 1e-5);
  EXPECT_NEAR(m.voxel_size(), tv::kVoxelSize, 1e-7);
  EXPECT_EQ(m.density(w + Vec3(10, 0, 0)), 0.0f);

  GridData t = load_density_grid(vdb("density.vdb"), "temperature");
  EXPECT_EQ(t.active_voxels, 1u);
  EXPECT_EQ(t.voxel(1, 2, 3), 300.0f);
  auto grids = list_vdb_grids(vdb("density.vdb"));
  ASSERT_EQ(grids.size(), 3u);
  EXPECT_EQ(grids[0].first, "density");
  EXPECT_EQ(grids[0].second, "float");
}

TEST(VdbLoad, NanoVdbPathMatchesDensePath) {
  auto nano = std::make_shared<const GridData>(load_density_grid(vdb("density.vdb")));
  // The same values as a dense array whose index (0, 0, 0) is the VDB's kMin.
  const int n[3] = {tv::kMax[0] - tv::kMin[0] + 1, tv::kMax[1] - tv::kMin[1] + 1, tv::kMax[2] - tv::kMin[2] + 1};
  std::vector<float> v(size_t(n[0]) * n[1] * n[2]);
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        v[(size_t(k) * n[1] + j) * n[0] + i] = float(tv::ramp(i + tv::kMin[0], j + tv::kMin[1], k + tv::kMin[2]));
  Transform shift = nano->index_to_object;  // index_dense = index_vdb - kMin
  for (int a = 0; a < 3; ++a) shift.m[a * 4 + 3] += float(tv::kVoxelSize * tv::kMin[a]);
  auto dense = std::make_shared<const GridData>(GridData::from_dense(v, n[0], n[1], n[2], shift));
  const Spectrum sa(2, 5, 9), ss(3, 1, 4);
  Medium a = Medium::heterogeneous(nano, sa, ss, 0.2f), b = Medium::heterogeneous(dense, sa, ss, 0.2f);
  // Identical majorants and lower bounds (the domains coincide: both are the bounding box widened
  // by one voxel).
  int positive_minima = 0;
  ASSERT_EQ(a.majorant_grid().resolution(0), b.majorant_grid().resolution(0));
  for (int z = 0; z < a.majorant_grid().resolution(2); ++z)
    for (int y = 0; y < a.majorant_grid().resolution(1); ++y)
      for (int x = 0; x < a.majorant_grid().resolution(0); ++x) {
        ASSERT_FLOAT_EQ(a.majorant_grid().cell_value(x, y, z), b.majorant_grid().cell_value(x, y, z));
        ASSERT_FLOAT_EQ(a.majorant_grid().cell_min(x, y, z), b.majorant_grid().cell_min(x, y, z));
        positive_minima += a.majorant_grid().cell_min(x, y, z) > 0;
      }
  EXPECT_GT(positive_minima, 0);
  Sampler s(media_test::seed(102), 0, 0);
  for (int i = 0; i < 200; ++i) {
    Vec3 o = Vec3(1.75f, -1.25f, 1.45f) + sample_uniform_sphere(s.next_2d()) * 2.0f;
    Vec3 target = Vec3(1.75f, -1.25f, 1.45f) + sample_uniform_sphere(s.next_2d()) * (0.7f * s.next_1d());
    Ray r = make_ray(o, normalize(target - o));
    Spectrum ta = a.transmittance(r, 0, 5, s, VolumeEstimator::RayMarching, 0.03f);
    Spectrum tb = b.transmittance(r, 0, 5, s, VolumeEstimator::RayMarching, 0.03f);
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(ta[c], tb[c], 1e-5f + 1e-4f * tb[c]) << "ray " << i;
    // Same random numbers, same lookups: delta tracking takes identical decisions.
    Sampler s1(media_test::seed(103), i, 0), s2(media_test::seed(103), i, 0);
    MediumInteraction ma, mb;
    bool ha = a.sample_distance(r, 0, 5, s1, VolumeEstimator::Tracking, 0, &ma);
    bool hb = b.sample_distance(r, 0, 5, s2, VolumeEstimator::Tracking, 0, &mb);
    ASSERT_EQ(ha, hb) << "ray " << i;
    if (ha) ASSERT_NEAR(ma.t, mb.t, 1e-4f);
  }
}

TEST(VdbLoad, TileGridMajorantAndTransmittance) {
  auto g = std::make_shared<const GridData>(load_density_grid(vdb("tiles.vdb")));
  EXPECT_EQ(g->active_voxels, 32ull * 32 * 32 + 128ull * 128 * 128);
  EXPECT_LT(g->memory_bytes(), 1000000u);  // tiles, not voxels (dense: 67 MB)
  const float sigma = 0.05f;
  Medium m = Medium::heterogeneous(g, Spectrum(0.0f), Spectrum(sigma), 0);  // index space = world
  const MajorantGrid& maj = m.majorant_grid();
  EXPECT_EQ(maj.value_at(Vec3(10, 10, 10)), tv::kBoxAValue);
  EXPECT_EQ(maj.value_at(Vec3(200, 200, 200)), tv::kBoxBValue);
  EXPECT_EQ(maj.value_at(Vec3(80, 80, 80)), 0.0f);  // between the boxes: no over-raising by tiles
  EXPECT_EQ(maj.value_at(Vec3(200, 10, 10)), 0.0f);
  // Lower bounds: the box values inside, 0 in cells reaching past a box (tiles of 0 or no node).
  auto min_at = [&](const Vec3& p) {
    MajorantSegment seg;
    MajorantGrid::Iterator it = maj.traverse(p, Vec3(1, 0, 0), 0, 1e-3f);
    EXPECT_TRUE(it.next(&seg));
    return seg.min;
  };
  EXPECT_EQ(min_at(Vec3(10, 10, 10)), tv::kBoxAValue);
  EXPECT_EQ(min_at(Vec3(200, 200, 200)), tv::kBoxBValue);
  EXPECT_EQ(min_at(Vec3(127.5f, 200, 200)), 0.0f);
  EXPECT_EQ(min_at(Vec3(31.5f, 10, 10)), 0.0f);
  EXPECT_EQ(min_at(Vec3(0.5f, 10, 10)), 0.0f);  // voxel -1: no node stores it (the background)
  EXPECT_EQ(min_at(Vec3(80, 80, 80)), 0.0f);
  // Box B along x at y = z = 190: density 0.5 from x = 128 to 255, falling linearly to 0 over one
  // voxel on either side: integral = 0.5 * 128 exactly.
  const Ray r = make_ray(Vec3(-50, 190, 190), Vec3(1, 0, 0));
  const double expect = std::exp(-sigma * 0.5 * 128);
  Sampler s(media_test::seed(104), 0, 0);
  EXPECT_NEAR(m.transmittance(r, 0, 400, s, VolumeEstimator::RayMarching, 0.5f).x, expect, 1e-5);
  Mean mt;
  for (int i = 0; i < 50000; ++i) mt.add(m.transmittance(r, 0, 400, s, VolumeEstimator::Tracking, 0).x);
  EXPECT_TRUE(within_se(mt, expect));
  // Memory report: NanoVDB buffer + majorant grid.
  EXPECT_EQ(m.memory_bytes(), g->nano_bytes + maj.memory_bytes());
  std::printf("[ media    ] tiles.vdb: %llu active voxels, NanoVDB %zu bytes, majorant %zu bytes\n",
              (unsigned long long)g->active_voxels, g->nano_bytes, maj.memory_bytes());
}

// The example and benchmark clouds (bench/volumes.py parses the "[ media    ] vdb memory" lines).
TEST(VdbLoad, CloudAndSmokeMemory) {
  for (const char* name : {"cloud.vdb", "smoke.vdb"}) {
    auto g = std::make_shared<const GridData>(load_density_grid(vdb(name)));
    EXPECT_GT(g->active_voxels, 1000u) << name;
    EXPECT_LE(g->active_voxels, 64ull * 64 * 64) << name;
    Medium m = Medium::heterogeneous(g, Spectrum(0.0f), Spectrum(1.0f), 0);
    const size_t maj = m.majorant_grid().memory_bytes();
    EXPECT_EQ(m.memory_bytes(), g->nano_bytes + maj);
    EXPECT_LT(m.memory_bytes(), 16u * g->active_voxels + 2000000u) << name;
    std::printf(
        "[ media    ] vdb memory %s: %llu active voxels, NanoVDB %zu bytes, majorant %zu bytes, "
        "file %llu bytes\n",
        name, (unsigned long long)g->active_voxels, g->nano_bytes, maj,
        (unsigned long long)std::filesystem::file_size(vdb(name)));
  }
}

TEST(VdbErrors, MissingFile) {
  std::string kind, msg = error_of([] { load_density_grid(vdb("does_not_exist.vdb")); }, &kind);
  EXPECT_EQ(kind, "IoError") << msg;
  EXPECT_NE(msg.find("not found"), std::string::npos) << msg;
  EXPECT_NE(msg.find("does_not_exist.vdb"), std::string::npos) << msg;
  msg = error_of([] { load_density_grid(LANTERN_TEST_VDB_DIR); }, &kind);
  EXPECT_EQ(kind, "IoError") << msg;
}

TEST(VdbErrors, CorruptAndTruncatedFiles) {
  // Every truncation of a valid file fails with IoError naming the file, never a crash. Cut after
  // its header, the header's grid descriptors show the cut and the file is refused before OpenVDB
  // reads it (OpenVDB reads past the end and allocates what unset length fields say: gigabytes for
  // some cuts, run to run).
  std::ifstream in(vdb("density.vdb"), std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1000u);
  const std::string path = std::string(LANTERN_TEST_VDB_DIR) + "/truncated_test.vdb";
  std::vector<size_t> lengths = {0, 1, 4, 8, 16, 100, 300};
  for (size_t len = 500; len < bytes.size(); len += 997) lengths.push_back(len);
  lengths.push_back(bytes.size() - 1);
  for (size_t len : lengths) {
    {
      std::ofstream out(path, std::ios::binary | std::ios::trunc);
      out.write(bytes.data(), std::streamsize(len));
    }
    std::string kind, msg = error_of([&] { load_density_grid(path); }, &kind);
    EXPECT_EQ(kind, "IoError") << "length " << len << ": " << msg;
    EXPECT_NE(msg.find("truncated_test.vdb"), std::string::npos) << msg;
    if (len >= 100) EXPECT_NE(msg.find("(truncated: "), std::string::npos) << "length " << len << ": " << msg;
  }
  // Garbage that is not a VDB file at all.
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << "this is not a VDB file, just some text that goes on for a while............";
  }
  std::string kind, msg = error_of([&] { load_density_grid(path); }, &kind);
  EXPECT_EQ(kind, "IoError") << msg;
  EXPECT_NE(msg.find("corrupt"), std::string::npos) << msg;
  std::filesystem::remove(path);
}

TEST(VdbErrors, MissingDensityGridListsTheGridsPresent) {
  std::string kind, msg = error_of([] { load_density_grid(vdb("no_density.vdb")); }, &kind);
  EXPECT_EQ(kind, "InvalidArgument") << msg;
  EXPECT_NE(msg.find("no grid named 'density'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'temperature' (float)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'velocity' (vec3s)"), std::string::npos) << msg;
  msg = error_of([] { load_density_grid(vdb("density.vdb"), "smoke"); }, &kind);
  EXPECT_EQ(kind, "InvalidArgument") << msg;
  EXPECT_NE(msg.find("'density' (float)"), std::string::npos) << msg;
}

TEST(VdbErrors, EmptyAndNonFloatGrids) {
  std::string kind, msg = error_of([] { load_density_grid(vdb("empty.vdb")); }, &kind);
  EXPECT_EQ(kind, "InvalidArgument") << msg;
  EXPECT_NE(msg.find("no active voxels"), std::string::npos) << msg;
  msg = error_of([] { load_density_grid(vdb("vector.vdb")); }, &kind);
  EXPECT_EQ(kind, "InvalidArgument") << msg;
  EXPECT_NE(msg.find("vec3s"), std::string::npos) << msg;
  EXPECT_NE(msg.find("float grid is required"), std::string::npos) << msg;
}

}  // namespace
}  // namespace lt
