// Writes the small .vdb files the native VDB tests read (build time; see CMakeLists.txt):
//   density.vdb     "density" (float ramp), "temperature" (float), "velocity" (vec3s)
//   no_density.vdb  "temperature" (float), "velocity" (vec3s): no density grid
//   empty.vdb       "density" (float) without active voxels
//   vector.vdb      "density" as a vec3s grid (wrong type)
//   tiles.vdb       "density" (float) made of constant tiles
// Usage: make_test_vdb <output directory>
#include <openvdb/openvdb.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "make_test_vdb.h"

namespace tv = lt::test_vdb;

namespace {

void write(const std::string& path, const openvdb::GridPtrVec& grids) {
  openvdb::io::File file(path);
  file.write(grids);
  file.close();
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
      for (int i = tv::kMin[0]; i <= tv::kMax[0]; ++i)
        acc.setValue(openvdb::Coord(i, j, k), float(tv::ramp(i, j, k)));
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
  return 0;
}
