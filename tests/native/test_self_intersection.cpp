// Rays leaving a triangle that touches another object's (geometry/hit.h, leave; Geometry's
// find_contacts and query filter): they meet the surface touching it, and not the triangle they
// leave or its neighbour in its plane.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/sampling.h"
#include "geometry/geometry.h"
#include "geometry_builders.h"

using namespace lt;

namespace {

// A square of two triangles in the plane z = 0, from -h to h, facing +z.
Mesh floor_mesh(float h) {
  Mesh m;
  m.positions = {Vec3(-h, -h, 0), Vec3(h, -h, 0), Vec3(h, h, 0), Vec3(-h, h, 0)};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

// Whether the triangle touches another object's anywhere (Geometry::touches at its corners and
// its centre).
bool touches_anywhere(const Geometry& g, int instance, int prim) {
  Vec3 p[3];
  g.triangle(instance, prim, &p[0], &p[1], &p[2]);
  bool any = g.touches(instance, prim, (p[0] + p[1] + p[2]) / 3);
  for (const Vec3& q : p) any = any || g.touches(instance, prim, q);
  return any;
}

int add(Geometry& g, Mesh m, const Transform& xf) {
  std::vector<std::string> warnings;
  Instance inst;
  static_cast<Pose&>(inst) = Pose::of(xf);
  inst.mesh = g.add_mesh(std::move(m), warnings);
  inst.materials = {0};
  return g.add_instance(std::move(inst), warnings);
}

Transform rotation(const Vec3& axis, float angle) {
  const Vec3 a = normalize(axis);
  const float c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  Transform r;
  const float m[3][3] = {{t * a.x * a.x + c, t * a.x * a.y - s * a.z, t * a.x * a.z + s * a.y},
                         {t * a.x * a.y + s * a.z, t * a.y * a.y + c, t * a.y * a.z - s * a.x},
                         {t * a.x * a.z - s * a.y, t * a.y * a.z + s * a.x, t * a.z * a.z + c}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[4 * i + j] = m[i][j];
  return r;
}

// A ray from o along d (unit).
Ray ray(const Vec3& o, const Vec3& d) {
  Ray r;
  r.o = o;
  r.d = normalize(d);
  return r;
}

}  // namespace

// A box resting on a floor (its bottom face in the floor's plane), as users place objects: a ray
// that leaves the bottom face downwards (refracted out of a glass, or a subsurface exit's
// bounce) meets the floor at once and is occluded by it, and a ray leaving the floor upwards
// under the box meets the box. An origin offset forwards stepped over the other surface (4 % on a
// glass block's image mean against Cycles, tests/blender/test_agreement.py, resting). Both
// axis-aligned (exact corners) and turned about a slanted axis (corners rounded).
TEST(SelfIntersection, ARayLeavingAFaceMeetsTheSurfaceItRestsOn) {
  for (bool turned : {false, true}) {
    const Transform xf = turned ? rotation(Vec3(0.3f, -0.5f, 0.8f), 0.7f) : Transform();
    Geometry g;
    const int floor = add(g, floor_mesh(3), xf);
    const int box = add(g, lt_test::box_mesh(Vec3(-0.6f, -0.4f, 0), Vec3(0.5f, 0.7f, 0.9f)), xf);
    g.commit();
    const Vec3 up = normalize(xf.vector(Vec3(0, 0, 1)));
    Pcg32 rng(7, 1);
    int met = 0, n = 0;
    for (int k = 0; k < 200; ++k) {
      const float x = -0.55f + 1.0f * (rng.next_u32() * 0x1p-32f), y = -0.35f + 1.0f * (rng.next_u32() * 0x1p-32f);
      // The bottom face from inside the box (its own scene: the floor lies at the same distance).
      Hit h;
      ASSERT_TRUE(g.intersect_instance(ray(xf.point(Vec3(x, y, 0.5f)), -up), box, &h));
      const SurfacePoint bottom = g.surface(h);
      Vec3 d = xf.vector(Vec3(0.3f * (rng.next_u32() * 0x1p-32f - 0.5f), 0.3f, -1));
      Ray down = ray(Vec3(0.0f), d);
      ASSERT_TRUE(bottom.touching);
      leave(bottom, &down);
      Hit below;
      ++n;
      if (g.intersect(down, 31u, &below) && below.instance == floor && below.t < 1e-4f && g.occluded(down)) ++met;
      // And the floor under the box, leaving upwards.
      ASSERT_TRUE(g.intersect_instance(ray(xf.point(Vec3(x, y, -0.5f)), up), floor, &h));
      const SurfacePoint ground = g.surface(h);
      Ray rise = ray(Vec3(0.0f), xf.vector(Vec3(0.2f, -0.1f, 1)));
      ASSERT_TRUE(ground.touching);
      leave(ground, &rise);
      Hit above;
      ++n;
      if (g.intersect(rise, 31u, &above) && above.instance == box && above.t < 1e-4f && g.occluded(rise)) ++met;
    }
    EXPECT_EQ(met, n) << (turned ? "turned" : "axis-aligned");
  }
}

// Where triangles are found in contact: the floor's under a box resting on it and the box's bottom,
// not the box's sides or top, nor a tile of another object meeting the floor at an edge or apart
// from it.
TEST(SelfIntersection, TrianglesInAnotherObjectsPlaneOverlappingItTouch) {
  Geometry g;
  const int floor = add(g, floor_mesh(3), Transform());
  const int box = add(g, lt_test::box_mesh(Vec3(-0.6f, -0.4f, 0), Vec3(0.5f, 0.7f, 0.9f)), Transform());
  Mesh tile = floor_mesh(1);
  for (Vec3& p : tile.positions) p = p + Vec3(5, 0, 0);  // x from 4 to 6: apart
  const int near_tile = add(g, std::move(tile), Transform());
  Mesh edge_tile = floor_mesh(0.5f);
  for (Vec3& p : edge_tile.positions) p = p + Vec3(3.5f, 0, 0);  // x from 3 to 4: meets the floor at x = 3
  const int edge = add(g, std::move(edge_tile), Transform());
  g.commit();
  // The floor under the box, not away from it.
  EXPECT_TRUE(g.touches(floor, 0, Vec3(0.1f, 0.2f, 0)) || g.touches(floor, 1, Vec3(0.1f, 0.2f, 0)));
  EXPECT_FALSE(g.touches(floor, 0, Vec3(2, 2.5f, 0)) || g.touches(floor, 1, Vec3(2, 2.5f, 0)));
  int bottom = 0, others = 0;
  for (int t = 0; t < 12; ++t) {
    Vec3 p0, p1, p2;
    g.triangle(box, t, &p0, &p1, &p2);
    (p0.z == 0 && p1.z == 0 && p2.z == 0 ? bottom : others) += touches_anywhere(g, box, t);
  }
  EXPECT_EQ(bottom, 2);
  EXPECT_EQ(others, 0);
  for (int t = 0; t < 2; ++t) {
    EXPECT_FALSE(touches_anywhere(g, near_tile, t));
    EXPECT_FALSE(touches_anywhere(g, edge, t));
  }
}

// A ray leaving a triangle at its edge with a neighbour in the same plane, at grazing angles and
// towards the neighbour, meets nothing: from its origin drawn back behind the plane it crosses
// the neighbour's plane there, which its own object's triangles skip (a path would otherwise
// hop from one to the other; Bdpt.LongPathsStayFinite looks at the middle of such an edge).
TEST(SelfIntersection, ARayLeavingAtASharedEdgeDoesNotMeetTheNeighbourInItsPlane) {
  Geometry g;
  add(g, floor_mesh(1), Transform());
  g.commit();
  int hits = 0, n = 0;
  for (int k = 0; k <= 20; ++k) {
    const float s = -0.9f + 1.8f * float(k) / 20;
    // On the diagonal from (-1, -1) to (1, 1) (both triangles' edge), found from above and below.
    for (float side : {1.0f, -1.0f}) {
      Hit h;
      ASSERT_TRUE(g.intersect(ray(Vec3(s, s, side), Vec3(0, 0, -side)), 31u, &h));
      SurfacePoint sp = g.surface(h);
      sp.touching = true;  // as if something touched it
      for (float grazing : {0.5f, 0.05f, 0.002f})
        for (float across : {1.0f, -1.0f}) {
          Ray r = ray(Vec3(0.0f), Vec3(across, -across, side * grazing));
          leave(sp, &r);
          Hit other;
          hits += g.intersect(r, 31u, &other);
          hits += g.occluded(r);
          ++n;
        }
    }
  }
  EXPECT_EQ(hits, 0) << "of " << n << " rays";
}

// A face doubled back to back in one mesh (imported models' two-sided faces; a mesh flattened by
// a zero scale): a ray leaving either face on its front meets nothing and is not occluded. A
// concave neighbour in the same mesh (a floor and a wall meeting at a corner) is met, even from
// next to the corner.
TEST(SelfIntersection, DoubledFacesAreNotMetAndConcaveNeighboursAre) {
  Geometry g, walls;
  Mesh doubled = floor_mesh(1);
  doubled.indices.insert(doubled.indices.end(), {0, 2, 1, 0, 3, 2});  // the same squares, facing down
  add(g, std::move(doubled), Transform());
  Mesh corner;  // the floor z = 0 (facing +z) and the wall x = 2 (facing -x), sharing the edge x = 2
  corner.positions = {Vec3(1, -1, 0), Vec3(2, -1, 0), Vec3(2, 1, 0), Vec3(1, 1, 0), Vec3(2, -1, 1), Vec3(2, 1, 1)};
  corner.indices = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2};
  const int room = add(walls, std::move(corner), Transform());
  g.commit();
  walls.commit();
  for (float side : {1.0f, -1.0f}) {
    Hit h;
    ASSERT_TRUE(g.intersect(ray(Vec3(0.2f, 0.3f, side), Vec3(0, 0, -side)), 31u, &h));
    SurfacePoint sp = g.surface(h);
    sp.touching = true;
    for (float slant : {0.0f, 0.5f, 5.0f}) {
      Ray r = ray(Vec3(0.0f), Vec3(slant, 0.3f * slant, side));
      leave(sp, &r);
      Hit other;
      EXPECT_FALSE(g.intersect(r, 31u, &other)) << side << " " << slant << ": met primitive " << other.primitive;
      EXPECT_FALSE(g.occluded(r)) << side << " " << slant;
    }
  }
  for (float gap : {1e-1f, 1e-4f, 1e-6f}) {
    Hit at;
    ASSERT_TRUE(walls.intersect(ray(Vec3(2 - gap, 0.1f, 1), Vec3(0, 0, -1)), 31u, &at));
    ASSERT_EQ(at.instance, room);
    SurfacePoint sp = walls.surface(at);
    sp.touching = true;
    for (float rise : {1.0f, 0.01f}) {
      Ray r = ray(Vec3(0.0f), Vec3(1, 0, rise));
      leave(sp, &r);
      Hit wall;
      ASSERT_TRUE(walls.intersect(r, 31u, &wall)) << gap << " " << rise;
      EXPECT_EQ(wall.instance, room);
      EXPECT_GE(wall.primitive, 2) << gap << " " << rise;
    }
  }
}
