// The shared scene builders (scene_builders.h) are what the other tests stand on: closed meshes
// must be closed and wound outward, transforms must map as documented.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <utility>

#include "scene_builders.h"

using namespace lt_test;

namespace {

double signed_volume(const MeshData& m) {
  double v = 0;
  for (int t = 0; t < m.triangle_count(); ++t) {
    const float* a = &m.positions[3 * m.triangles[3 * t]];
    const float* b = &m.positions[3 * m.triangles[3 * t + 1]];
    const float* c = &m.positions[3 * m.triangles[3 * t + 2]];
    v += (a[0] * (double(b[1]) * c[2] - double(b[2]) * c[1]) - a[1] * (double(b[0]) * c[2] - double(b[2]) * c[0]) +
          a[2] * (double(b[0]) * c[1] - double(b[1]) * c[0])) /
         6.0;
  }
  return v;
}

// Closed and consistently oriented: each directed edge once, and its reverse once. Positions are
// compared by value so that boxes (which repeat corners per face) count as closed.
bool closed_and_oriented(const MeshData& m) {
  std::map<std::pair<std::array<float, 3>, std::array<float, 3>>, int> edges;
  auto pos = [&](int i) {
    return std::array<float, 3>{m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]};
  };
  for (int t = 0; t < m.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) ++edges[{pos(m.triangles[3 * t + k]), pos(m.triangles[3 * t + (k + 1) % 3])}];
  for (const auto& [e, n] : edges) {
    auto it = edges.find({e.second, e.first});
    if (n != 1 || it == edges.end() || it->second != 1) return false;
  }
  return true;
}

}  // namespace

TEST(ApiBuilders, ClosedMeshesAreClosedAndWoundOutward) {
  const double pi = 3.14159265358979323846;
  MeshData b = box({-1, -2, -3}, {1, 2, 3});
  EXPECT_TRUE(closed_and_oriented(b));
  EXPECT_NEAR(signed_volume(b), 2 * 4 * 6, 1e-4);
  EXPECT_FALSE(closed_and_oriented(box({0, 0, 0}, {1, 1, 1}, true)));

  MeshData ico = icosphere(2, 3);
  EXPECT_EQ(ico.triangle_count(), 20 * 64);
  EXPECT_TRUE(closed_and_oriented(ico));
  EXPECT_NEAR(signed_volume(ico), 4.0 / 3 * pi * 8, 0.02 * 4.0 / 3 * pi * 8);
  for (int i = 0; i < ico.vertex_count(); ++i) {
    const float* p = &ico.positions[3 * i];
    ASSERT_NEAR(std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), 2.0, 1e-5);
  }
  flip_winding(ico);
  EXPECT_LT(signed_volume(ico), 0);

  MeshData uv = uv_sphere(1, 32, 16, true);
  EXPECT_TRUE(closed_and_oriented(uv));
  EXPECT_NEAR(signed_volume(uv), 4.0 / 3 * pi, 0.03 * 4.0 / 3 * pi);
  EXPECT_EQ(uv.corner_normals.size(), uv.triangles.size() * 3);

  MeshData pl = plane(2, 4);
  const float* a = &pl.positions[0];
  const float* c = &pl.positions[3 * 2];
  EXPECT_FLOAT_EQ(c[0] - a[0], 2);
  EXPECT_FLOAT_EQ(c[1] - a[1], 4);
  // Counter-clockwise seen from +Z: the normal is +Z.
  const float* p0 = &pl.positions[3 * pl.triangles[0]];
  const float* p1 = &pl.positions[3 * pl.triangles[1]];
  const float* p2 = &pl.positions[3 * pl.triangles[2]];
  EXPECT_GT((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]), 0);
}

TEST(ApiBuilders, TransformsMapAsDocumented) {
  // look_at: the local -Z axis points at the target, the origin sits at the eye.
  Xform m = look_at({1, 2, 3}, {1, 2, -7}, {0, 1, 0});
  V3 o = apply_point(m, {0, 0, 0}), f = apply_point(m, {0, 0, -1});
  EXPECT_NEAR(o.x, 1, 1e-6);
  EXPECT_NEAR(o.y, 2, 1e-6);
  EXPECT_NEAR(o.z, 3, 1e-6);
  EXPECT_NEAR(f.z - o.z, -1, 1e-6);
  V3 up = apply_point(m, {0, 1, 0});
  EXPECT_NEAR(up.y - o.y, 1, 1e-6);
  // compose applies the right-hand transform first.
  Xform ts = compose(translate({1, 0, 0}), scale({2, 2, 2}));
  V3 p = apply_point(ts, {1, 1, 1});
  EXPECT_FLOAT_EQ(p.x, 3);
  EXPECT_FLOAT_EQ(p.y, 2);
  V3 r = apply_point(rotate({0, 0, 1}, 3.14159265f / 2), {1, 0, 0});
  EXPECT_NEAR(r.x, 0, 1e-6);
  EXPECT_NEAR(r.y, 1, 1e-6);
}
