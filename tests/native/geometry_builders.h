// Core-level geometry for tests that work below the ABI (Geometry and its instances directly).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "geometry/geometry.h"

namespace lt_test {

// An axis-aligned box from lo to hi (flat: face normals), each face's two triangles wound outwards.
inline lt::Mesh box_mesh(const lt::Vec3& lo, const lt::Vec3& hi) {
  lt::Mesh m;
  for (int i = 0; i < 8; ++i)
    m.positions.push_back(lt::Vec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z));
  m.indices = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
               2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  return m;
}

// The mesh as g's one instance (identity transform, material 0), committed.
inline void add_lone_instance(lt::Geometry& g, lt::Mesh m) {
  std::vector<std::string> warnings;
  lt::Instance inst;
  static_cast<lt::Pose&>(inst) = lt::Pose::of(lt::Transform());
  inst.mesh = g.add_mesh(std::move(m), warnings);
  inst.materials = {0};
  g.add_instance(std::move(inst), warnings);
  g.commit();
}

}  // namespace lt_test
