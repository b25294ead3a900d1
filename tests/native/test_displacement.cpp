// True displacement (shading/displacement.*, Cycles 3.4's mesh_displace.cpp): each vertex moved
// once by the Material Output's Displacement at its corner of the first displacing triangle, in
// object space through the mesh's first instance, normals recomputed (True) or kept (Both),
// Generated read from the undisplaced mesh, motion steps moved alike, and meshes without
// displacing materials left as they are.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "program_builder.h"
#include "scene/scene.h"
#include "scene_builders.h"
#include "shading/displacement.h"

namespace lt {
namespace {

// A 3 x 3 vertex grid over [0, 2]^2 at z = 0, 8 triangles, smooth normals +Z.
Mesh grid() {
  Mesh m;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) m.positions.push_back(Vec3(float(x), float(y), 0));
  for (uint32_t y = 0; y < 2; ++y)
    for (uint32_t x = 0; x < 2; ++x) {
      const uint32_t a = 3 * y + x;
      for (uint32_t i : {a, a + 1, a + 4, a, a + 4, a + 3}) m.indices.push_back(i);
    }
  m.corner_normals.assign(m.indices.size(), Vec3(0, 0, 1));
  m.texspace_location = Vec3(1, 1, 0);
  m.texspace_size = Vec3(1, 1, 1);
  return m;
}

Transform scaled(float s, const Vec3& t) {
  Transform xf;
  xf.m[0] = xf.m[5] = xf.m[10] = s;
  xf.m[3] = t.x;
  xf.m[7] = t.y;
  xf.m[11] = t.z;
  return xf;
}

Program compiled(const ShaderCode& c) { return Program(c.code, c.k, c.registers, 0); }

// Displacement node in object space: height Generated.x, midlevel 0, scale 0.5, default normal.
Program generated_height() {
  ShaderCode c;
  const uint32_t gen = c.tex_coord()[0];
  const uint32_t x = c.emit(kOpToFloat, {gen}, {1}, {1})[0];  // average of (gx, gy, gz)
  const uint32_t d = c.emit(kOpDisplacement, {x, c.c1(0), c.c1(1.5f), c.c3({0, 0, 0})}, {3}, {0})[0];
  c.emit(kOpSetDisplacement, {d}, {});
  return compiled(c);
}

// As generated_height, along Generated (normalised) instead of the normal: a curved surface.
Program generated_height_along_generated() {
  ShaderCode c;
  const uint32_t gen = c.tex_coord()[0];
  const uint32_t x = c.emit(kOpToFloat, {gen}, {1}, {1})[0];
  const uint32_t d = c.emit(kOpDisplacement, {x, c.c1(0), c.c1(1.5f), gen}, {3}, {0})[0];
  c.emit(kOpSetDisplacement, {d}, {});
  return compiled(c);
}

// A constant world-space offset.
Program constant_offset(Rgb d) {
  ShaderCode c;
  c.emit(kOpSetDisplacement, {c.c3(d)}, {});
  return compiled(c);
}

Material displacing(Program p, DisplacementMethod method) {
  ShaderCode surface;
  surface.diffuse(surface.one(), {0.8f, 0.8f, 0.8f});
  Material m(compiled(surface));
  m.set_displacement(std::make_shared<const Program>(std::move(p)), method);
  return m;
}

int add_instance(Scene& s, int mesh, const Transform& xf, std::vector<int> materials) {
  Instance inst;
  inst.mesh = mesh;
  inst.xf = xf;
  inst.materials = std::move(materials);
  return s.geometry.add_instance(inst, s.warnings);
}

void expect_near(const Vec3& a, const Vec3& b, const std::string& what) {
  EXPECT_NEAR(a.x, b.x, 1e-5f) << what;
  EXPECT_NEAR(a.y, b.y, 1e-5f) << what;
  EXPECT_NEAR(a.z, b.z, 1e-5f) << what;
}

// The height at each vertex, along the object-space normal whatever the object's scale;
// Displacement Only recomputes the smooth normals (the tilted plane's), Both keeps them.
TEST(Displacement, VerticesMoveByTheProgramAtEachVertex) {
  for (DisplacementMethod method : {DisplacementMethod::True, DisplacementMethod::Both}) {
    Scene s;
    s.materials.push_back(displacing(generated_height(), method));
    const int mesh = s.geometry.add_mesh(grid(), s.warnings);
    add_instance(s, mesh, scaled(2, Vec3(5, 0, 0)), {0});
    s.commit();
    const Mesh& m = s.geometry.mesh(mesh);
    ASSERT_EQ(m.positions.size(), 9u);
    for (size_t v = 0; v < 9; ++v) {
      const Vec3 p0 = m.undisplaced[v];
      // Generated = p / 2 here; its average (gx + gy + 0.5) / 3 times 1.5.
      const float h = 1.5f * (p0.x / 2 + p0.y / 2 + 0.5f) / 3;
      expect_near(m.positions[v], p0 + Vec3(0, 0, h), "vertex " + std::to_string(v));
    }
    // The plane z = (x + y) / 4 + 0.25: normal (-1, -1, 4) / sqrt(18).
    const Vec3 tilted = normalize(Vec3(-1, -1, 4));
    for (const Vec3& n : m.corner_normals)
      expect_near(n, method == DisplacementMethod::True ? tilted : Vec3(0, 0, 1), "corner normal");
    // Generated still reads the undisplaced mesh.
    Hit hit;
    hit.instance = 0;
    hit.primitive = 0;
    hit.u = 0.25f;
    hit.v = 0.5f;
    const SurfacePoint sp = s.geometry.surface(hit);
    expect_near(sp.generated, Vec3(0.75f / 2, 0.5f / 2, 0.5f), "generated");
    EXPECT_GT(sp.po.z, 0.25f);
  }
}

// A vertex shared by faces of different materials takes the first displacing triangle's (Cycles'
// fill_shader_input); a shared mesh is displaced once, in its first instance's object space.
TEST(Displacement, FirstTriangleAndFirstInstanceDecide) {
  Scene s;
  s.materials.push_back(displacing(constant_offset({0, 0, 2}), DisplacementMethod::True));
  s.materials.push_back(displacing(constant_offset({0, 0, 8}), DisplacementMethod::True));
  Mesh g = grid();
  g.slots = {1, 1, 0, 0, 0, 0, 0, 0};  // the first quad (vertices 0, 1, 3, 4) material 1
  const int mesh = s.geometry.add_mesh(std::move(g), s.warnings);
  add_instance(s, mesh, scaled(2, Vec3(0.0f)), {0, 1});
  add_instance(s, mesh, scaled(4, Vec3(9, 0, 0)), {0, 1});
  s.commit();
  const Mesh& m = s.geometry.mesh(mesh);
  for (size_t v = 0; v < 9; ++v) {
    const bool first_quad = v == 0 || v == 1 || v == 3 || v == 4;
    expect_near(m.positions[v] - m.undisplaced[v], Vec3(0, 0, first_quad ? 4.0f : 1.0f), "vertex " + std::to_string(v));
  }
}

// Only triangles of displacing materials move their vertices; a mesh without any is untouched.
TEST(Displacement, OtherMeshesAndTrianglesStay) {
  Scene s;
  s.materials.push_back(displacing(constant_offset({0, 0, 1}), DisplacementMethod::True));
  ShaderCode plain;
  plain.diffuse(plain.one(), {0.5f, 0.5f, 0.5f});
  s.materials.emplace_back(compiled(plain));
  Mesh g = grid();
  g.slots = {0, 0, 1, 1, 1, 1, 1, 1};  // only the first quad displaces
  const int a = s.geometry.add_mesh(std::move(g), s.warnings);
  const int b = s.geometry.add_mesh(grid(), s.warnings);
  add_instance(s, a, Transform(), {0, 1});
  add_instance(s, b, Transform(), {1});
  s.commit();
  const Mesh& ma = s.geometry.mesh(a);
  for (size_t v = 0; v < 9; ++v) {
    const bool first_quad = v == 0 || v == 1 || v == 3 || v == 4;
    EXPECT_FLOAT_EQ(ma.positions[v].z, first_quad ? 1.0f : 0.0f) << v;
  }
  EXPECT_TRUE(s.geometry.mesh(b).undisplaced.empty());
  for (const Vec3& p : s.geometry.mesh(b).positions) EXPECT_EQ(p.z, 0.0f);
}

// A flat triangle of a mixed mesh takes its displaced face normal; smooth corners the sum of
// their vertex's displaced faces' normals; a deforming mesh's steps move by the same offsets.
TEST(Displacement, FlatTrianglesAndMotionSteps) {
  Scene s;
  s.materials.push_back(displacing(generated_height_along_generated(), DisplacementMethod::True));
  Mesh g = grid();
  g.flat.assign(8, 0);
  g.flat[7] = 1;
  g.motion_steps = 3;
  for (int step = 0; step < 3; ++step)
    for (const Vec3& p : g.positions) g.motion_positions.push_back(p + Vec3(0, 0, float(step)));
  const int mesh = s.geometry.add_mesh(std::move(g), s.warnings);
  add_instance(s, mesh, Transform(), {0});
  s.commit();
  const Mesh& m = s.geometry.mesh(mesh);
  for (int step = 0; step < 3; ++step)
    for (size_t v = 0; v < 9; ++v)
      expect_near(m.motion_positions[size_t(step) * 9 + v], m.positions[v] + Vec3(0, 0, float(step)), "step");
  auto face = [&](size_t t) {
    const Vec3 p0 = m.positions[m.indices[3 * t]], p1 = m.positions[m.indices[3 * t + 1]],
               p2 = m.positions[m.indices[3 * t + 2]];
    return normalize(cross(p1 - p0, p2 - p0));
  };
  ASSERT_GT(length(face(0) - face(7)), 0.05f) << "the displaced grid should not be planar";
  for (int c = 0; c < 3; ++c) expect_near(m.corner_normals[21 + size_t(c)], face(7), "flat triangle 7");
  // Vertex 0 (triangles 0 and 1), vertex 8 (triangles 6 and 7, the flat one counted too).
  expect_near(m.corner_normals[0], normalize(face(0) + face(1)), "vertex 0");
  expect_near(m.corner_normals[20], normalize(face(6) + face(7)), "vertex 8 in triangle 6");
  EXPECT_TRUE(m.motion_corner_normals.empty());  // none were given
}

}  // namespace
}  // namespace lt

namespace lt_test {

// The ABI's checks: method and program go together, the material exists, and vertices move at the
// first commit only (later settings are refused).
TEST(Displacement, AbiRefusesWhatItCannotDo) {
  ScenePtr s = new_scene();
  const int mat = add_diffuse(s.get(), {0.5f, 0.5f, 0.5f});
  ShaderCode c;
  c.emit(lt::kOpSetDisplacement, {c.c3({0, 0, 1})}, {});
  const lt_shader_program p = c.desc();
  EXPECT_EQ(lt_scene_set_material_displacement(s.get(), mat, &p, 7), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_scene_set_material_displacement(s.get(), mat, nullptr, LT_DISPLACEMENT_TRUE), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_scene_set_material_displacement(s.get(), mat, &p, LT_DISPLACEMENT_BUMP), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_scene_set_material_displacement(s.get(), mat + 1, &p, LT_DISPLACEMENT_TRUE), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_scene_set_material_displacement(s.get(), mat, &p, LT_DISPLACEMENT_TRUE), LT_OK);
  EXPECT_EQ(lt_scene_set_material_displacement(s.get(), mat, nullptr, LT_DISPLACEMENT_BUMP), LT_OK);
  EXPECT_EQ(lt_scene_set_material_displacement(s.get(), mat, &p, LT_DISPLACEMENT_BOTH), LT_OK);
  add_object(s.get(), plane(1, 1), mat);
  EXPECT_EQ(lt_scene_commit(s.get()), LT_OK);
  EXPECT_EQ(lt_scene_set_material_displacement(s.get(), mat, &p, LT_DISPLACEMENT_TRUE), LT_ERROR_STATE);
}

}  // namespace lt_test
