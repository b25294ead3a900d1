// Writes the small .vdb files the native VDB tests read (build time; see CMakeLists.txt):
//   density.vdb     "density" (float ramp), "temperature" (float), "velocity" (vec3s)
//   no_density.vdb  "temperature" (float), "velocity" (vec3s): no density grid
//   empty.vdb       "density" (float) without active voxels
//   vector.vdb      "density" as a vec3s grid (wrong type)
//   tiles.vdb       "density" (float) made of constant tiles
//   cloud.vdb       "density" (float): a procedural cloud, a few noisy blobs in 48^3 voxels
//   smoke.vdb       "density" (float): a rising, widening noisy smoke plume in 40x40x64 voxels
//   two_grids.vdb   "density" (the smoke plume) and "cloud" (the cloud): a material's Density
//                   Attribute picks one
//   fire.vdb        "density", "flame", "temperature" (float, 24x24x32 voxels of 5 cm): a flame
//                   whose emission reads the flame and temperature grids, inside a smoke plume
// Usage: make_test_vdb <output directory>
#include "make_test_vdb.h"

#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace tv = lt::test_vdb;

namespace {

// Writes the grids, then replaces the random UUID OpenVDB puts in the header (36 ASCII characters
// at byte 21: magic, version, library version, offsets flag) by a fixed one, so that every machine
// generates the same bytes and tests that cut or corrupt these files see the same input.
void write(const std::string& path, const openvdb::GridPtrVec& grids) {
  openvdb::io::File file(path);
  file.write(grids);
  file.close();
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  char uuid[36];
  f.seekg(21);
  f.read(uuid, 36);
  if (!f || uuid[8] != '-' || uuid[13] != '-' || uuid[18] != '-' || uuid[23] != '-') {
    std::fprintf(stderr, "make_test_vdb: unexpected VDB header in %s\n", path.c_str());
    std::exit(1);
  }
  f.seekp(21);
  f.write("00000000-0000-4000-8000-000000000000", 36);
}

openvdb::FloatGrid::Ptr ramp_grid() {
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  auto xf = openvdb::math::Transform::createLinearTransform(tv::kVoxelSize);
  xf->postTranslate(openvdb::Vec3d(tv::kTranslation[0], tv::kTranslation[1], tv::kTranslation[2]));
  grid->setTransform(xf);
  auto acc = grid->getAccessor();
  for (int k = tv::kMin[2]; k <= tv::kMax[2]; ++k)
    for (int j = tv::kMin[1]; j <= tv::kMax[1]; ++j)
      for (int i = tv::kMin[0]; i <= tv::kMax[0]; ++i) acc.setValue(openvdb::Coord(i, j, k), float(tv::ramp(i, j, k)));
  return grid;
}

openvdb::FloatGrid::Ptr temperature() {
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("temperature");
  grid->tree().setValue(openvdb::Coord(1, 2, 3), 300.0f);
  return grid;
}

openvdb::Vec3SGrid::Ptr velocity(const std::string& name) {
  auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
  grid->setName(name);
  grid->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 2, 3));
  return grid;
}

// Deterministic value noise in [0, 1] (hashed lattice, smoothstep-interpolated), a few octaves.
double lattice(int x, int y, int z) {
  unsigned h = unsigned(x) * 73856093u ^ unsigned(y) * 19349663u ^ unsigned(z) * 83492791u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return (h & 0xffffu) / 65535.0;
}

double value_noise(double x, double y, double z) {
  const int xi = int(std::floor(x)), yi = int(std::floor(y)), zi = int(std::floor(z));
  auto s = [](double t) { return t * t * (3.0 - 2.0 * t); };
  const double fx = s(x - xi), fy = s(y - yi), fz = s(z - zi);
  double r = 0.0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    r += (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz) * lattice(xi + dx, yi + dy, zi + dz);
  }
  return r;
}

double fbm(double x, double y, double z) {
  double sum = 0.0, amp = 0.5, norm = 0.0;
  for (int o = 0; o < 3; ++o, amp *= 0.5, x *= 2.0, y *= 2.0, z *= 2.0) {
    sum += amp * value_noise(x, y, z);
    norm += amp;
  }
  return sum / norm;
}

// A fog grid from density(i, j, k) in [0, 1] over [0, n), voxel size `voxel`, centred on the
// origin in x and y and starting at z = z0; only voxels above 0.01 are active.
template <class F>
openvdb::FloatGrid::Ptr procedural(const int n[3], double voxel, double z0, F density) {
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  grid->setGridClass(openvdb::GRID_FOG_VOLUME);
  auto xf = openvdb::math::Transform::createLinearTransform(voxel);
  xf->postTranslate(openvdb::Vec3d(-0.5 * (n[0] - 1) * voxel, -0.5 * (n[1] - 1) * voxel, z0));
  grid->setTransform(xf);
  auto acc = grid->getAccessor();
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const double d = density(i, j, k);
        if (d > 0.01) acc.setValue(openvdb::Coord(i, j, k), float(std::min(d, 1.0)));
      }
  grid->pruneGrid();
  return grid;
}

openvdb::FloatGrid::Ptr cloud_grid() {
  const int n[3] = {48, 48, 48};
  // Blobs (centre in voxels, radius in voxels).
  const double blobs[5][4] = {{24, 24, 22, 12}, {14, 22, 20, 8}, {33, 27, 21, 9}, {22, 32, 28, 7}, {28, 16, 27, 6}};
  return procedural(n, 0.04, -0.94, [&](int i, int j, int k) {
    double shape = 0.0;
    for (const auto& b : blobs) {
      const double dx = i - b[0], dy = j - b[1], dz = k - b[2];
      shape += std::exp(-(dx * dx + dy * dy + dz * dz) / (2.0 * b[3] * b[3] * 0.45));
    }
    const double noise = fbm(i * 0.15, j * 0.15, k * 0.15);
    return std::max(0.0, 1.6 * shape * (0.35 + noise) - 0.35);
  });
}

openvdb::FloatGrid::Ptr smoke_grid() {
  const int n[3] = {40, 40, 64};
  return procedural(n, 0.03, 0.0, [&](int i, int j, int k) {
    const double h = k / 63.0;             // 0 at the source, 1 at the top
    const double radius = 3.0 + 14.0 * h;  // the plume widens as it rises
    const double cx = 19.5 + 4.0 * std::sin(6.0 * h), cy = 19.5 + 3.0 * std::cos(5.0 * h);
    const double r = std::hypot(i - cx, j - cy) / radius;
    const double noise = fbm(i * 0.2, j * 0.2, k * 0.12);
    const double d = std::exp(-2.0 * r * r) * (0.3 + 1.2 * noise) * (1.0 - 0.5 * h);
    return d * (k < 62 ? 1.0 : 0.0) - 0.05;
  });
}

// A fire: smoke widening as it rises, a flame core low in it and a hot region around the flame,
// each grid named after what it holds (as Blender's smoke simulations write them).
openvdb::GridPtrVec fire_grids() {
  const int n[3] = {24, 24, 32};
  auto radius = [](int i, int j) { return std::hypot(i - 11.5, j - 11.5); };
  auto density = procedural(n, 0.05, 0.0, [&](int i, int j, int k) {
    const double h = k / 31.0, r = radius(i, j) / (5.0 + 6.0 * h);
    return std::exp(-2.0 * r * r) * (0.4 + 0.8 * fbm(i * 0.2, j * 0.2, k * 0.15)) - 0.04;
  });
  auto flame = procedural(n, 0.05, 0.0, [&](int i, int j, int k) {
    const double r = radius(i, j) / 3.0, z = (k - 8.0) / 6.0;
    return std::exp(-3.0 * r * r - z * z) * (0.5 + fbm(i * 0.3 + 7.0, j * 0.3, k * 0.2)) - 0.02;
  });
  flame->setName("flame");
  auto temperature = procedural(n, 0.05, 0.0, [&](int i, int j, int k) {
    const double r = radius(i, j) / 4.0, z = (k - 10.0) / 8.0;
    return std::exp(-2.0 * r * r - z * z) * (0.8 + 0.4 * fbm(i * 0.25, j * 0.25 + 3.0, k * 0.2));
  });
  temperature->setName("temperature");
  return {density, flame, temperature};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <output directory>\n", argv[0]);
    return 2;
  }
  openvdb::initialize();
  const std::string dir = argv[1];
  std::filesystem::create_directories(dir);

  write(dir + "/density.vdb", {ramp_grid(), temperature(), velocity("velocity")});
  write(dir + "/no_density.vdb", {temperature(), velocity("velocity")});

  auto empty = openvdb::FloatGrid::create(0.0f);
  empty->setName("density");
  write(dir + "/empty.vdb", {empty});

  write(dir + "/vector.vdb", {velocity("density")});

  auto tiles = openvdb::FloatGrid::create(0.0f);
  tiles->setName("density");
  tiles->tree().sparseFill(openvdb::CoordBBox(openvdb::Coord(tv::kBoxA[0][0], tv::kBoxA[0][1], tv::kBoxA[0][2]),
                                              openvdb::Coord(tv::kBoxA[1][0], tv::kBoxA[1][1], tv::kBoxA[1][2])),
                           tv::kBoxAValue, true);
  tiles->tree().sparseFill(openvdb::CoordBBox(openvdb::Coord(tv::kBoxB[0][0], tv::kBoxB[0][1], tv::kBoxB[0][2]),
                                              openvdb::Coord(tv::kBoxB[1][0], tv::kBoxB[1][1], tv::kBoxB[1][2])),
                           tv::kBoxBValue, true);
  write(dir + "/tiles.vdb", {tiles});

  write(dir + "/cloud.vdb", {cloud_grid()});
  write(dir + "/smoke.vdb", {smoke_grid()});
  auto cloud = cloud_grid();
  cloud->setName("cloud");
  write(dir + "/two_grids.vdb", {smoke_grid(), cloud});
  write(dir + "/fire.vdb", fire_grids());
  return 0;
}
