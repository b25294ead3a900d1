// The contents of the small .vdb files make_test_vdb writes, shared with the tests that read them.
#pragma once

namespace lt::test_vdb {

// density.vdb, grid "density": a linear ramp on the voxels [kMin, kMax] (inclusive), so trilinear
// interpolation reproduces it exactly between voxel centres; voxel size 0.1, origin offset below.
constexpr int kMin[3] = {-3, 0, 2};
constexpr int kMax[3] = {12, 15, 17};
constexpr double kVoxelSize = 0.1;
constexpr double kTranslation[3] = {1.0, -2.0, 0.5};
inline double ramp(double i, double j, double k) { return 0.25 + 0.05 * i + 0.02 * j + 0.01 * k; }

// tiles.vdb, grid "density": constant boxes stored as tiles (lower- and upper-node tiles).
constexpr int kBoxA[2][3] = {{0, 0, 0}, {31, 31, 31}};
constexpr float kBoxAValue = 2.0f;
constexpr int kBoxB[2][3] = {{128, 128, 128}, {255, 255, 255}};
constexpr float kBoxBValue = 0.5f;

}  // namespace lt::test_vdb
