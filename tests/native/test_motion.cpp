// Motion blur: Cycles' transform interpolation (translation and scale linear, rotation by
// quaternion slerp), Embree's instance and vertex motion agreeing with it, camera motion, the
// ABI's motion steps, and determinism across thread counts with motion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <tuple>
#include <vector>

#include "geometry/geometry.h"
#include "geometry/motion.h"
#include "scene/camera.h"
#include "scene_builders.h"

using namespace lt;

namespace {

Transform rot_z(float radians, float s = 1, Vec3 t = Vec3(0.0f)) {
  const float c = std::cos(radians), n = std::sin(radians);
  Transform m;
  const float v[12] = {c * s, -n * s, 0, t.x, n * s, c * s, 0, t.y, 0, 0, s, t.z};
  std::copy(v, v + 12, m.m);
  return m;
}

void expect_near(const Transform& a, const Transform& b, float tol, const std::string& what) {
  for (int i = 0; i < 12; ++i) EXPECT_NEAR(a.m[i], b.m[i], tol) << what << ", element " << i;
}

// A strip 2 long along +x, 0.1 wide, in the z = 0 plane, of `quads` quads along its length.
Mesh strip(int quads = 1) {
  Mesh m;
  for (int i = 0; i <= quads; ++i) {
    const float x = 2.0f * float(i) / float(quads);
    m.positions.push_back(Vec3(x, -0.05f, 0));
    m.positions.push_back(Vec3(x, 0.05f, 0));
  }
  for (uint32_t i = 0; i < uint32_t(quads); ++i)
    m.indices.insert(m.indices.end(), {2 * i, 2 * i + 2, 2 * i + 3, 2 * i, 2 * i + 3, 2 * i + 1});
  return m;
}

// Straight down onto the z = 0 plane at (x, y), at a time.
Ray down(float x, float y, float time) {
  Ray r;
  r.o = Vec3(x, y, 1);
  r.d = Vec3(0, 0, -1);
  r.time = time;
  return r;
}

bool hit_down(const Geometry& g, float x, float y, float time, Hit* hit) {
  return g.intersect(down(x, y, time), 31u, hit);
}

constexpr float kDeg = float(kPi / 180);

// A 2 x 2 quad about `centre` in a z = const plane, deforming: at motion step k its z is z[k].
Mesh rising_quad(std::initializer_list<float> z, Vec3 centre = Vec3(0.0f)) {
  Mesh m;
  const Vec3 corners[4] = {Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)};
  for (const Vec3& c : corners) m.positions.push_back(c + centre);
  m.indices = {0, 1, 2, 0, 2, 3};
  m.motion_steps = int(z.size());
  for (float zk : z)
    for (const Vec3& c : corners) m.motion_positions.push_back(c + centre + Vec3(0, 0, zk));
  return m;
}

}  // namespace

TEST(Motion, DecompositionRoundTripsRotationScaleAndMirror) {
  // Blender's loc/rot/scale (rotation about a tilted axis, non-uniform scale), and a mirror.
  Transform tilt;  // 0.3 radians about x
  tilt.m[5] = tilt.m[10] = std::cos(0.3f);
  tilt.m[6] = -std::sin(0.3f);
  tilt.m[9] = std::sin(0.3f);
  Transform m = lt::compose(rot_z(0.7f), tilt);
  for (int i = 0; i < 3; ++i) {
    m.m[4 * i + 0] *= 1.5f;
    m.m[4 * i + 2] *= 0.4f;
  }
  m.m[3] = 1, m.m[7] = -2, m.m[11] = 3;
  expect_near(recompose(decompose(m)), m, 1e-5f, "scaled");
  Transform mirror = m;
  for (int i = 0; i < 3; ++i) mirror.m[4 * i + 1] = -mirror.m[4 * i + 1];
  expect_near(recompose(decompose(mirror)), mirror, 1e-5f, "mirrored");
}

// Between two steps the rotation turns at constant speed and the scale stays (a linear blend of
// the matrices would shrink the object by cos(angle / 2) half-way).
TEST(Motion, InterpolationSlerpsRotationAndLerpsTheRest) {
  const std::vector<Transform> steps = {rot_z(0, 2, Vec3(0, 0, 0)), rot_z(45 * kDeg, 2, Vec3(1, 0, 0)),
                                        rot_z(90 * kDeg, 2, Vec3(2, 2, 0))};
  const std::vector<DecomposedTransform> d = decompose_motion(steps);
  expect_near(interpolate_motion(d, 0.25f), rot_z(22.5f * kDeg, 2, Vec3(0.5f, 0, 0)), 1e-5f, "time 0.25");
  expect_near(interpolate_motion(d, 0.75f), rot_z(67.5f * kDeg, 2, Vec3(1.5f, 1, 0)), 1e-5f, "time 0.75");
  expect_near(interpolate_motion(d, 0.0f), steps[0], 1e-6f, "time 0");
  expect_near(interpolate_motion(d, 1.0f), steps[2], 1e-5f, "time 1");
  // The shorter arc, whatever the quaternions' signs: -170 to +170 degrees turns through 180.
  const std::vector<DecomposedTransform> wrap =
      decompose_motion({rot_z(-170 * kDeg), rot_z(180 * kDeg), rot_z(170 * kDeg)});
  expect_near(interpolate_motion(wrap, 0.25f), rot_z(-175 * kDeg), 1e-5f, "across +-180 degrees");
}

// The slerp to float's rounding at every angle a step can turn (up to 180 degrees: the
// quaternions' half angle up to 90) and every time between, against rotations computed in
// double and rounded once (the steps too): within 3e-7, recompose's products' rounding (about
// 2 ulp of 1). A small turn's angle by acos lost digits (1e-6 at 10 degrees a step).
TEST(Motion, SlerpIsExactToRoundingAtEveryStepAngle) {
  const auto rotation = [](double radians) {
    Transform m;
    m.m[0] = m.m[5] = float(std::cos(radians));
    m.m[4] = float(std::sin(radians));
    m.m[1] = -m.m[4];
    return m;
  };
  for (const double degrees : {0.5, 10.0, 60.0, 120.0, 170.0, 179.9}) {
    const double step = degrees * kPi / 180;
    const std::vector<DecomposedTransform> d = decompose_motion({rotation(0), rotation(step), rotation(2 * step)});
    for (int k = 0; k <= 64; ++k)
      expect_near(interpolate_motion(d, float(k) / 64), rotation(2 * step * k / 64), 3e-7f,
                  std::to_string(degrees) + " degrees a step, time " + std::to_string(k) + "/64");
  }
}

// Embree's instance motion traverses the object where the shading interpolation puts it: a ray at
// time 0 and at time 1 sees the rotating strip in different places, and at a quarter of the
// shutter the strip has its full length (slerp), which a linear blend of the matrices would not
// reach.
TEST(Motion, InstanceMotionHitsWhereTheInterpolatedTransformIs) {
  Geometry g;
  std::vector<std::string> warnings;
  Instance inst;
  inst.mesh = g.add_mesh(strip(), warnings);
  inst.xf = rot_z(45 * kDeg);
  inst.motion = {rot_z(0), rot_z(45 * kDeg), rot_z(90 * kDeg)};
  g.add_instance(inst, warnings);
  g.commit();
  EXPECT_TRUE(warnings.empty());
  EXPECT_EQ(g.motion_instances(), 1u);
  EXPECT_TRUE(g.has_motion());
  Hit h;
  EXPECT_TRUE(hit_down(g, 1.9f, 0, 0.0f, &h));
  EXPECT_FALSE(hit_down(g, 1.9f, 0, 1.0f, &h));
  EXPECT_TRUE(hit_down(g, 0, 1.9f, 1.0f, &h));
  EXPECT_FALSE(hit_down(g, 0, 1.9f, 0.0f, &h));
  const float a = 22.5f * kDeg, r = 1.95f;  // beyond 2 cos(22.5 deg) = 1.85
  ASSERT_TRUE(hit_down(g, r * std::cos(a), r * std::sin(a), 0.25f, &h));
  const SurfacePoint sp = g.surface(h);
  EXPECT_NEAR(sp.p.x, r * std::cos(a), 1e-3f);
  EXPECT_NEAR(sp.p.y, r * std::sin(a), 1e-3f);
  EXPECT_NEAR(std::abs(sp.ng.z), 1.0f, 1e-5f);
  EXPECT_EQ(sp.time, 0.25f);
  expect_near(g.pose(0, 0.25f).xf, rot_z(a), 1e-5f, "pose at 0.25");
  Vec3 p0, p1, p2;
  g.triangle(0, 0, &p0, &p1, &p2, 1.0f);
  EXPECT_NEAR(p1.y, 2.0f, 1e-5f);  // corner (2, -0.05) turned by 90 degrees
  EXPECT_NEAR(p1.x, 0.05f, 1e-5f);
}

// A moving object alone in Embree's motion BVH is given to Embree as one instance per motion
// segment (Embree tests no bounds at the root of a one-primitive BVH), each valid over its own time
// range; beside a few still instances it shares their BVH (build_top), unless they are flattened
// into the top level (flattens_beside_motion); one that does not turn is traced through its
// triangles baked in world space at each step (bakes_motion) unless its mesh is large and shared.
// Every way, at every time the object is hit where its interpolated transform puts it and nowhere
// a segment would be at another time, by the scene's rays and by intersect_instance's. Probed over
// a grid of points and times, for matrix motion (translation and scale) and quaternion motion
// (turning, two and three steps).
TEST(Motion, ALoneMovingObjectIsHitOnlyWhereItIsAtTheRaysTime) {
  struct Case {
    const char* name;
    std::vector<Transform> steps;
    bool large_shared;  // 4200 triangles, shared with the still instances: not baked
    int still;          // still instances of the same mesh, far away
    int copies;         // world-space copies built: the moving one baked, or the still ones flattened
  };
  const std::vector<Transform> translating = {rot_z(0, 1, Vec3(-1, 0, 0)), rot_z(0, 1.5f, Vec3(1, 0.5f, 0))};
  const std::vector<Transform> turning = {rot_z(0), rot_z(70 * kDeg), rot_z(140 * kDeg, 1, Vec3(0, 0.3f, 0))};
  const Case cases[] = {
      {"translating, baked", translating, false, 0, 1},
      {"translating, sharing the still instance's motion BVH", translating, true, 1, 0},
      {"translating, beside 300 still instances: split in the middle", translating, true, 300, 0},
      {"turning, 2 steps, split", {rot_z(-60 * kDeg), rot_z(60 * kDeg, 1, Vec3(0.2f, 0, 0))}, false, 0, 0},
      {"turning, 3 steps, split", turning, false, 0, 0},
      {"turning, 3 steps, sharing the still instance's motion BVH", turning, true, 1, 0},
      {"turning, 3 steps, beside 2 still instances flattened into the top level: split", turning, false, 2, 2},
  };
  for (const Case& c : cases) {
    Geometry g;
    std::vector<std::string> warnings;
    Instance inst;
    inst.mesh = g.add_mesh(strip(c.large_shared ? 2100 : 1), warnings);
    inst.xf = c.steps[0];
    inst.motion = c.steps;
    g.add_instance(inst, warnings);
    for (int k = 0; k < c.still; ++k) {
      Instance still = inst;
      still.motion.clear();
      still.xf = rot_z(0, 1, Vec3(1000.0f + 3.0f * float(k), 0, 0));
      g.add_instance(still, warnings);
    }
    g.commit();
    EXPECT_EQ(g.mesh_builds(), 1u + unsigned(c.copies)) << c.name << ": a world-space copy is a build of its own";
    const std::vector<DecomposedTransform> d = decompose_motion(c.steps);
    int hits = 0, checked = 0;
    for (int k = 0; k <= 20; ++k) {
      const float time = float(k) / 20;
      const Transform inv = affine_inverse(interpolate_motion(d, time));
      for (float x = -2.5f; x <= 2.5f; x += 0.05f)
        for (float y = -2.5f; y <= 2.5f; y += 0.05f) {
          const Vec3 o = inv.point(Vec3(x, y, 0));  // where the point is on the strip's plane
          const float margin = std::min({o.x, 2 - o.x, 0.05f - std::abs(o.y)});
          if (std::abs(margin) < 2e-3f) continue;  // too close to an edge to call
          Hit h;
          const bool hit = hit_down(g, x, y, time, &h);
          EXPECT_EQ(hit, margin > 0) << c.name << " at time " << time << ", (" << x << ", " << y << ")";
          hits += hit;
          ++checked;
          if (!hit) continue;
          EXPECT_EQ(h.instance, 0) << c.name;
          Hit own;
          ASSERT_TRUE(g.intersect_instance(down(x, y, time), 0, &own)) << c.name << " at time " << time;
          EXPECT_NEAR(own.t, h.t, 1e-5f) << c.name;
          EXPECT_EQ(own.primitive, h.primitive) << c.name;
        }
    }
    EXPECT_GT(hits, 100) << c.name;
    EXPECT_GT(checked, 200000) << c.name;
  }
}

// Beside a turning object, still triangle meshes are traced as world-space triangles in the top
// level (flattens_beside_motion), and so is a flat one (zero scale, always baked): hit as their own
// instance, on the same triangle at the same t as when instanced (the scene without motion), by
// intersect, occluded and intersect_instance, and hidden from the ray kinds they hide from. Fails
// if a flattened hit reports Embree's empty instance id or the visibility filter reads it.
TEST(Motion, StillObjectsBesideATurningOneAreHitAsTheirInstances) {
  const std::vector<Transform> turning = {rot_z(0), rot_z(60 * kDeg)};
  Transform tilted = rot_z(30 * kDeg, 1.5f, Vec3(-3, 4, 0));
  Geometry moving, still;
  for (Geometry* g : {&moving, &still}) {
    std::vector<std::string> warnings;
    Instance spinner;
    spinner.mesh = g->add_mesh(strip(), warnings);
    spinner.xf = turning[0];
    if (g == &moving) spinner.motion = turning;
    g->add_instance(spinner, warnings);
    Instance a;  // its own mesh of 8 quads, turned, scaled and moved
    a.mesh = g->add_mesh(strip(8), warnings);
    a.xf = tilted;
    g->add_instance(a, warnings);
    Instance b = a;  // the same mesh 10 m on, hidden from camera rays (visibility bit 1)
    b.xf = rot_z(0, 1, Vec3(10, 0, 0));
    b.visibility = 31u & ~1u;
    g->add_instance(b, warnings);
    Instance c = a;  // the same mesh at y = -5, flattened onto z = 0 (no inverse: baked)
    c.xf = rot_z(0, 1, Vec3(0, -5, 0));
    c.xf.m[10] = 0;
    g->add_instance(c, warnings);
    g->commit();
  }
  EXPECT_EQ(moving.mesh_builds(), still.mesh_builds() + 2) << "the two still instances flattened";
  int checked = 0;
  for (int quad = 0; quad < 8; ++quad) {  // a point 0.01 from each quad's diagonal (strip's winding)
    const float u = 0.25f * float(quad) + 0.075f;
    const Vec3 on_a = tilted.point(Vec3(u, -0.03f, 0)), on_b = Vec3(10 + u, -0.03f, 0);
    for (const float time : {0.0f, 0.5f, 1.0f}) {
      Hit h, ref;
      ASSERT_TRUE(moving.intersect(down(on_a.x, on_a.y, time), 1u, &h)) << u;
      ASSERT_TRUE(still.intersect(down(on_a.x, on_a.y, time), 1u, &ref)) << u;
      EXPECT_EQ(h.instance, 1);
      EXPECT_EQ(h.primitive, ref.primitive);
      EXPECT_NEAR(h.t, ref.t, 1e-5f);
      EXPECT_NEAR(h.u, ref.u, 1e-4f);
      EXPECT_NEAR(h.v, ref.v, 1e-4f);
      const SurfacePoint sp = moving.surface(h), sref = still.surface(ref);
      EXPECT_NEAR(length(sp.p - sref.p), 0.0f, 1e-5f);
      EXPECT_NEAR(std::abs(dot(sp.ng, sref.ng)), 1.0f, 1e-6f);
      Hit own;
      ASSERT_TRUE(moving.intersect_instance(down(on_a.x, on_a.y, time), 1, &own));
      EXPECT_EQ(own.primitive, ref.primitive);
      EXPECT_FALSE(moving.intersect(down(on_b.x, on_b.y, time), 1u, &h)) << "camera rays do not see b";
      ASSERT_TRUE(moving.intersect(down(on_b.x, on_b.y, time), 2u, &h)) << "other rays do";
      EXPECT_EQ(h.instance, 2);
      EXPECT_TRUE(moving.occluded(down(on_b.x, on_b.y, time)));
      ASSERT_TRUE(moving.intersect(down(u, -5.03f, time), 1u, &h)) << "the flat one";
      ASSERT_TRUE(still.intersect(down(u, -5.03f, time), 1u, &ref));
      EXPECT_EQ(h.instance, 3);
      EXPECT_EQ(h.primitive, ref.primitive);
      EXPECT_NEAR(h.t, ref.t, 1e-5f);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 24);
}

// A turning object hidden from camera rays, alone (one Embree instance per motion segment, whose
// further top-level ids carry its visibility: attach_moving) or among 8 more in Embree's motion
// BVH: camera rays pass through it, other rays hit it where it is at their time, and it casts
// shadows.
TEST(Motion, AMovingObjectHiddenFromCameraRaysIsSeenByTheOthers) {
  for (const int more : {0, 8}) {
    Geometry g;
    std::vector<std::string> warnings;
    Instance inst;
    inst.mesh = g.add_mesh(strip(), warnings);
    inst.xf = rot_z(0);
    inst.motion = {rot_z(0), rot_z(90 * kDeg)};
    inst.visibility = 31u & ~1u;
    g.add_instance(inst, warnings);
    for (int k = 0; k < more; ++k) {
      Instance far = inst;
      far.visibility = 31u;
      far.motion = {rot_z(0, 1, Vec3(1000.0f + 3.0f * float(k), 0, 0)),
                    rot_z(90 * kDeg, 1, Vec3(1000.0f + 3.0f * float(k), 0, 0))};
      far.xf = far.motion[0];
      g.add_instance(far, warnings);
    }
    g.commit();
    const std::string name = more ? "among 8 more" : "alone, split";
    Hit h;
    EXPECT_FALSE(g.intersect(down(1.5f, 0, 0.0f), 1u, &h)) << name;
    ASSERT_TRUE(g.intersect(down(1.5f, 0, 0.0f), 2u, &h)) << name;
    EXPECT_EQ(h.instance, 0) << name;
    EXPECT_FALSE(g.intersect(down(1.5f, 0, 1.0f), 2u, &h)) << name << ": turned away at the end";
    EXPECT_TRUE(g.intersect(down(0, 1.5f, 1.0f), 2u, &h)) << name;
    EXPECT_EQ(h.instance, 0) << name;
    EXPECT_FALSE(g.intersect(down(0, 1.5f, 1.0f), 1u, &h)) << name << ": nor at the end (a later segment's id)";
    EXPECT_TRUE(g.occluded(down(1.5f, 0, 0.0f))) << name;
    EXPECT_FALSE(g.occluded(down(1.5f, 0, 1.0f))) << name;
  }
}

// Motion is baked into world-space triangles only when every moving object can be (none turns):
// beside a turning object, whose motion BVH stays, a translating one keeps Embree's instance motion.
TEST(Motion, ObjectsThatDoNotTurnAreBakedOnlyWhenNoneTurns) {
  const std::vector<Transform> sliding = {rot_z(0, 1, Vec3(-1, 0, 0)), rot_z(0, 1, Vec3(1, 0, 0))};
  const std::vector<Transform> turning = {rot_z(0), rot_z(60 * kDeg)};
  for (const bool with_turning : {false, true}) {
    Geometry g;
    std::vector<std::string> warnings;
    for (const auto& motion : {sliding, with_turning ? turning : sliding}) {
      Instance inst;
      inst.mesh = g.add_mesh(strip(), warnings);
      inst.xf = motion[0];
      inst.motion = motion;
      g.add_instance(inst, warnings);
    }
    g.commit();
    EXPECT_EQ(g.mesh_builds(), with_turning ? 2u : 4u) << (with_turning ? "with" : "without") << " a turning object";
    Hit h;
    EXPECT_TRUE(hit_down(g, 1.5f, 0, 1.0f, &h));  // a sliding strip at its end, x in [1, 3]
    EXPECT_FALSE(hit_down(g, 2.5f, 0, 0.0f, &h)) << "nothing is there at the start";
  }
}

// Copies baked into world space (a sliding strip's motion, a strip flattened onto z = 0) are
// Embree scenes of their own: when a visibility edit after the commit first hides an instance
// from some rays, they take Embree's context filter flag as the meshes' scenes do (Debian's
// Embree asserts it in every instanced scene a filtered ray enters; found by fuzz_abi).
TEST(Motion, BakedCopiesKeepBeingHitAfterAVisibilityEdit) {
  Geometry g;
  std::vector<std::string> warnings;
  Instance sliding;
  sliding.mesh = g.add_mesh(strip(), warnings);
  sliding.motion = {rot_z(0, 1, Vec3(-1, 0, 0)), rot_z(0, 1, Vec3(1, 0, 0))};
  sliding.xf = rot_z(0);
  g.add_instance(sliding, warnings);
  Instance flat;  // no inverse: baked
  flat.mesh = g.add_mesh(strip(), warnings);
  flat.xf = rot_z(0, 1, Vec3(0, -5, 0));
  flat.xf.m[10] = 0;
  g.add_instance(flat, warnings);
  Instance plain;
  plain.mesh = g.add_mesh(strip(), warnings);
  plain.xf = rot_z(0, 1, Vec3(10, 0, 0));
  const int hidden = g.add_instance(plain, warnings);
  g.commit();
  Instance values;
  values.visibility = 31u & ~1u;  // hidden from camera rays from now on
  g.set_instance_values(hidden, std::move(values));
  g.commit();
  Hit h;
  ASSERT_TRUE(hit_down(g, 1.5f, 0, 1.0f, &h)) << "the sliding strip at its end, to camera rays";
  EXPECT_EQ(h.instance, 0);
  ASSERT_TRUE(g.intersect(down(0.5f, -5.03f, 0.5f), 1u, &h)) << "the flat strip, to camera rays";
  EXPECT_EQ(h.instance, 1);
  EXPECT_FALSE(g.intersect(down(10.5f, 0, 0.5f), 1u, &h)) << "camera rays no longer see the third";
  ASSERT_TRUE(g.intersect(down(10.5f, 0, 0.5f), 2u, &h)) << "other rays do";
  EXPECT_EQ(h.instance, hidden);
}

// Vertex motion: a quad rising from z = 0 to z = 1 over the shutter.
TEST(Motion, DeformingMeshHitsAtTheRaysTime) {
  Geometry g;
  std::vector<std::string> warnings;
  Instance inst;
  inst.mesh = g.add_mesh(rising_quad({0.0f, 0.5f, 1.0f}), warnings);
  g.add_instance(inst, warnings);
  g.commit();
  EXPECT_EQ(g.motion_meshes(), 1u);
  for (float time : {0.0f, 0.25f, 0.5f, 0.9f, 1.0f}) {
    Ray r;
    r.o = Vec3(0.3f, 0.2f, 2);
    r.d = Vec3(0, 0, -1);
    r.time = time;
    Hit h;
    ASSERT_TRUE(g.intersect(r, 31u, &h)) << time;
    EXPECT_NEAR(h.t, 2 - time, 1e-5f) << time;
    EXPECT_NEAR(g.surface(h).p.z, time, 1e-5f) << time;
  }
}

// Motion steps a constant velocity makes redundant are left out (motion blur's cost in Embree):
// a steady translation's 3 and 5 steps become 2; one that speeds up keeps its 3, and is still
// where its steps put it (0.1 at a quarter of the shutter, not 0.25); a steady spin keeps its
// steps (a longer segment would loosen its bounds). A deforming mesh whose middle step is off the
// midpoint is hit where its steps put it too.
TEST(Motion, StepsAConstantVelocityMakesRedundantAreLeftOut) {
  EXPECT_EQ(redundant_stride(5, [](int, int k, int) { return k != 2; }), 2);
  EXPECT_EQ(redundant_stride(9, [](int, int, int) { return true; }), 8);
  EXPECT_EQ(redundant_stride(4, [](int, int, int) { return true; }), 1);
  Geometry g;
  std::vector<std::string> warnings;
  Instance inst;
  inst.mesh = g.add_mesh(strip(), warnings);
  auto at_x = [](float x) { return rot_z(0, 1.5f, Vec3(x, 0, 0)); };
  inst.xf = at_x(0.5f);
  inst.motion = {at_x(0), at_x(0.5f), at_x(1)};
  g.add_instance(inst, warnings);
  inst.motion = {at_x(0), at_x(0.25f), at_x(0.5f), at_x(0.75f), at_x(1)};
  g.add_instance(inst, warnings);
  inst.motion = {at_x(0), at_x(0.2f), at_x(1)};
  g.add_instance(inst, warnings);
  inst.motion = {rot_z(0), rot_z(45 * kDeg), rot_z(90 * kDeg)};
  g.add_instance(inst, warnings);
  Instance quad;
  quad.mesh = g.add_mesh(rising_quad({0.0f, 0.2f, 1.0f}, Vec3(5, 0, 0)), warnings);
  g.add_instance(quad, warnings);
  g.commit();
  EXPECT_EQ(g.instance(0).motion.size(), 2u);
  EXPECT_EQ(g.instance(1).motion.size(), 2u);
  EXPECT_EQ(g.instance(2).motion.size(), 3u);
  EXPECT_EQ(g.instance(3).motion.size(), 3u);
  expect_near(g.pose(1, 0.3f).xf, at_x(0.3f), 1e-6f, "steady, at 0.3");
  expect_near(g.pose(2, 0.25f).xf, at_x(0.1f), 1e-6f, "speeding up, at 0.25");
  for (float time : {0.25f, 0.75f}) {
    Hit h;
    ASSERT_TRUE(hit_down(g, 5.3f, 0.2f, time, &h)) << time;
    const float z = time < 0.5f ? 0.4f * time : 0.2f + 1.6f * (time - 0.5f);
    EXPECT_NEAR(h.t, 1 - z, 1e-5f) << time;
  }
}

TEST(Motion, CameraMovesWithTheSamplesTime) {
  CameraDesc d;
  Transform left, centre, right;
  left.m[3] = -1, right.m[3] = 1;
  d.xf = centre;
  d.motion = {left, centre, right};
  Camera cam(d, 32, 32);
  EXPECT_TRUE(cam.has_motion());
  for (float time : {0.0f, 0.25f, 0.5f, 1.0f}) {
    Ray r;
    ASSERT_TRUE(cam.generate(16, 16, Vec2{0.5f, 0.5f}, &r, time));
    EXPECT_NEAR(r.o.x, 2 * time - 1, 1e-6f);
    EXPECT_EQ(r.time, time);
    EXPECT_NEAR(cam.position(time).x, 2 * time - 1, 1e-6f);
  }
  lt::Camera::Projection pr;
  ASSERT_TRUE(cam.project(cam.position(1.0f), Vec3(1, 0, -5), 0, &pr, 1.0f));
  ASSERT_EQ(pr.count, 1);
  EXPECT_NEAR(pr.at[0].film.x, 16, 1e-3f);  // straight ahead of the camera at time 1
}

namespace {

using namespace lt_test;

// A moving box, a rising quad and a panning camera over a floor, under an area light and an
// emissive quad that moves; `motion` false: the same scene at the shutter's centre.
ScenePtr moving_scene(bool motion) {
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  add_object(s, plane(20, 20), add_diffuse(s, {0.7f, 0.6f, 0.5f}));
  const Xform centre = translate({0, 0, 0});
  const std::vector<Xform> box_steps = {translate({-0.8f, 0, 0}), centre, translate({0.8f, 0, 0})};
  std::vector<float> flat;
  for (const Xform& x : box_steps) flat.insert(flat.end(), x.begin(), x.end());
  MeshData b = box({-0.4f, -0.4f, 0}, {0.4f, 0.4f, 0.8f});
  lt_instance_desc d{};
  const int mat = add_diffuse(s, {0.2f, 0.5f, 0.8f});
  d.mesh = add_mesh(s, b);
  std::copy(centre.begin(), centre.end(), d.transform);
  d.materials = &mat;
  d.material_count = 1;
  d.visibility = LT_VISIBLE_ALL;
  if (motion) d.motion_transforms = flat.data(), d.motion_step_count = 3;
  int id;
  check(lt_scene_add_instance(s, &d, &id), "instance");
  MeshData q = plane(1, 1);
  std::vector<float> steps;
  for (float z : {0.2f, 0.6f, 1.0f})
    for (size_t i = 0; i < q.positions.size(); ++i) steps.push_back(q.positions[i] + (i % 3 == 2 ? z : 0.0f));
  for (size_t i = 2; i < q.positions.size(); i += 3) q.positions[i] += 0.6f;
  lt_mesh_desc md = q.desc();
  if (motion) md.motion_positions = steps.data(), md.motion_step_count = 3;
  int mesh;
  check(lt_scene_add_mesh(s, &md, &mesh), "mesh");
  add_instance(s, mesh, add_emission(s, {1, 0.8f, 0.6f}, 4), translate({1.2f, 0.5f, 0}));
  add_light(s, area_light(LT_AREA_RECTANGLE, 1, 0.5f, look_at({0, -1, 3}, {0, 0, 0}), 300));
  set_world(s, {0.2f, 0.3f, 0.5f}, 0.3f);
  lt_camera_desc c = perspective_camera(look_at({0.5f, -5, 2.5f}, {0, 0, 0.5f}), 35);
  const std::vector<Xform> cam = {look_at({0.3f, -5, 2.5f}, {0, 0, 0.5f}), look_at({0.5f, -5, 2.5f}, {0, 0, 0.5f}),
                                  look_at({0.7f, -5, 2.5f}, {0, 0, 0.5f})};
  std::vector<float> cflat;
  for (const Xform& x : cam) cflat.insert(cflat.end(), x.begin(), x.end());
  if (motion) c.motion_transforms = cflat.data(), c.motion_step_count = 3;
  set_camera(s, c);
  check(lt_scene_commit(s), "commit");
  return sp;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST(Motion, ThreadCountDoesNotChangeABitWithMotion) {
  ScenePtr still = moving_scene(false), moving = moving_scene(true);
  lt_scene_stats st{};
  check(lt_scene_get_stats(moving.get(), &st), "stats");
  EXPECT_EQ(st.motion_instances, 1u);
  EXPECT_EQ(st.motion_meshes, 1u);
  EXPECT_EQ(st.camera_motion_steps, 3u);
  check(lt_scene_get_stats(still.get(), &st), "stats");
  EXPECT_EQ(st.motion_instances + st.motion_meshes + st.camera_motion_steps, 0u);
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    lt_render_settings rs = render_settings(48, 32, 4, 7);
    rs.integrator = integrator;
    rs.threads = 1;
    Passes one = render(moving.get(), rs);
    rs.threads = 2;
    Passes two = render(moving.get(), rs);
    Passes centre = render(still.get(), rs);
    ASSERT_EQ(one.first_non_finite(), "");
    const std::string what = "integrator " + std::to_string(integrator);
    EXPECT_TRUE(same_bits(one.combined, two.combined)) << what << ": 1 vs 2 threads";
    EXPECT_EQ(one.status.rays, two.status.rays) << what;
    EXPECT_FALSE(same_bits(one.combined, centre.combined)) << what << ": motion changes nothing";
  }
}

TEST(Motion, BadMotionStepsAreRefusedOrLeftStill) {
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  const int mat = add_diffuse(s, {0.5f, 0.5f, 0.5f});
  MeshData b = box({0, 0, 0}, {1, 1, 1});
  const int mesh = add_mesh(s, b);
  std::vector<float> steps(12 * 131, 0.0f);
  for (int k = 0; k < 131; ++k) steps[12 * k] = steps[12 * k + 5] = steps[12 * k + 10] = 1;
  lt_instance_desc d{};
  d.mesh = mesh;
  d.transform[0] = d.transform[5] = d.transform[10] = 1;
  d.materials = &mat;
  d.material_count = 1;
  d.motion_transforms = steps.data();
  int id;
  for (int count : {-1, 1, 2, 4, 131}) {
    d.motion_step_count = count;
    EXPECT_EQ(lt_scene_add_instance(s, &d, &id), LT_ERROR_INVALID_ARGUMENT) << count;
    EXPECT_NE(std::string(lt_last_error()).find("motion steps"), std::string::npos) << lt_last_error();
  }
  d.motion_step_count = 3;
  d.motion_transforms = nullptr;
  EXPECT_EQ(lt_scene_add_instance(s, &d, &id), LT_ERROR_INVALID_ARGUMENT);
  // A step not finite: the instance stays at its centre transform, with a warning. A step scaled
  // to nothing (growing from nothing) keeps its motion (AnObjectGrowingFromNothing...).
  d.motion_transforms = steps.data();
  steps[0] = steps[5] = steps[10] = 0;
  const int before = lt_scene_warning_count(s);
  EXPECT_EQ(lt_scene_add_instance(s, &d, &id), LT_OK);
  EXPECT_EQ(lt_scene_warning_count(s), before);
  steps[0] = steps[5] = steps[10] = 1;
  steps[3] = NAN;
  EXPECT_EQ(lt_scene_add_instance(s, &d, &id), LT_OK);
  EXPECT_EQ(lt_scene_warning_count(s), before + 1);
  // 129 steps (Cycles' 7 motion steps) are accepted.
  steps[3] = 0;
  d.motion_step_count = 129;
  EXPECT_EQ(lt_scene_add_instance(s, &d, &id), LT_OK);
  // Deforming positions must be finite.
  MeshData q = plane(1, 1);
  std::vector<float> mp(3 * q.positions.size(), 0.0f);
  mp[4] = INFINITY;
  lt_mesh_desc md = q.desc();
  md.motion_positions = mp.data();
  md.motion_step_count = 3;
  int m2;
  EXPECT_EQ(lt_scene_add_mesh(s, &md, &m2), LT_ERROR_INVALID_ARGUMENT);
  set_camera(s, perspective_camera(look_at({3, -5, 2}, {0.5f, 0.5f, 0.5f})));
  check(lt_scene_commit(s), "commit");
  lt_scene_stats st{};
  check(lt_scene_get_stats(s, &st), "stats");
  EXPECT_EQ(st.motion_instances, 2u);  // the one growing from nothing and the 129-step one
  lt_render_settings rs = render_settings(16, 16, 2, 1);
  Passes p = render(s, rs);
  EXPECT_EQ(p.first_non_finite(), "");
}

// ---- The Vector pass (Cycles' motion pass: motion steps are the previous and next frames) -------

namespace {

// The film position of p seen by a camera at xf (35 mm over a 36 mm sensor, fitted to the
// width; look_at's axes: right, up, back), as a pinhole projects it.
lt_test::V3 raster(const lt_test::Xform& xf, lt_test::V3 p, int width, int height) {
  const lt_test::V3 v{p.x - xf[3], p.y - xf[7], p.z - xf[11]};
  const float x = xf[0] * v.x + xf[4] * v.y + xf[8] * v.z, y = xf[1] * v.x + xf[5] * v.y + xf[9] * v.z;
  const float z = -(xf[2] * v.x + xf[6] * v.y + xf[10] * v.z);
  const float scale = width * 35.0f / 36.0f;
  return {0.5f * width + scale * x / z, 0.5f * height + scale * y / z, 0};
}

}  // namespace

// moving_scene's motion steps taken as the previous, this and the next frame: the box moves 0.8
// along x per frame, the quad rises 0.4, the camera pans 0.2; the floor stays. Each pixel's
// Vector is (film position then - now) for the previous frame and (now - then) for the next, the
// mean over its samples; with a Gaussian filter of width 0.01 px every sample lands within
// 0.015 px of the pixel's centre, so where the pixel's 3x3 neighbourhood shows one object the
// pass equals the motion of the first sample's Position (the point the test projects itself) up
// to 0.03 px times the motion's change to a neighbour, plus float rounding.
TEST(Motion, VectorPassIsTheFilmMotionToTheNeighbouringFrames) {
  ScenePtr moving = moving_scene(true);
  const int w = 96, h = 64;
  lt_render_settings rs = render_settings(w, h, 2, 3);
  rs.filter = LT_FILTER_GAUSSIAN;
  rs.filter_width = 0.01f;
  rs.passes |= 1u << LT_PASS_VECTOR;
  rs.motion_pass = 1;
  const std::vector<Xform> cam = {look_at({0.3f, -5, 2.5f}, {0, 0, 0.5f}), look_at({0.5f, -5, 2.5f}, {0, 0, 0.5f}),
                                  look_at({0.7f, -5, 2.5f}, {0, 0, 0.5f})};
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_VOLPATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    rs.integrator = integrator;
    const Passes p = render(moving.get(), rs);
    ASSERT_EQ(p.first_non_finite(), "");
    const std::vector<float>& vec = p.pass(LT_PASS_VECTOR);
    const std::vector<float>& pos = p.pass(LT_PASS_POSITION);
    ASSERT_EQ(vec.size(), size_t(4 * w * h));
    // Which object a Position is on (0: none, 1 floor, 2 box, 3 quad) and its expected Vector.
    auto object = [&](int i) {
      const V3 q{pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]};
      if (p.depth[i] >= 1e9f) return 0;
      if (std::abs(q.z) < 1e-4f) return 1;
      if (std::abs(q.z - 0.6f) < 1e-4f && q.x > 0.65f) return 3;
      return std::abs(q.x) < 0.401f && std::abs(q.y) < 0.401f && q.z > -1e-4f && q.z < 0.801f ? 2 : -1;
    };
    auto expected = [&](int i, float out[4]) {
      const V3 q{pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]};
      const int o = object(i);
      const V3 d = o == 2 ? V3{0.8f, 0, 0} : o == 3 ? V3{0, 0, 0.4f} : V3{0, 0, 0};
      const V3 pre = raster(cam[0], {q.x - d.x, q.y - d.y, q.z - d.z}, w, h), now = raster(cam[1], q, w, h);
      const V3 post = raster(cam[2], {q.x + d.x, q.y + d.y, q.z + d.z}, w, h);
      out[0] = pre.x - now.x, out[1] = pre.y - now.y, out[2] = now.x - post.x, out[3] = now.y - post.y;
    };
    int checked[4] = {0, 0, 0, 0}, bad = 0;
    for (int y = 1; y + 1 < h; ++y)
      for (int x = 1; x + 1 < w; ++x) {
        const int i = y * w + x, o = object(i);
        float e[4];
        if (o <= 0) {
          if (o == 0)
            for (int k = 0; k < 4; ++k) EXPECT_EQ(vec[4 * i + k], 0.0f) << "background pixel " << i;
          continue;
        }
        expected(i, e);
        double step = 0;
        bool one_object = true;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int j = (y + dy) * w + x + dx;
            one_object = one_object && object(j) == o;
            float en[4];
            if (one_object) expected(j, en);
            for (int k = 0; k < 4 && one_object; ++k) step = std::max(step, double(std::abs(en[k] - e[k])));
          }
        if (!one_object) continue;
        ++checked[o];
        for (int k = 0; k < 4; ++k) {
          const double tol = 0.03 * step + 1e-4 * (1 + std::abs(e[k]));
          if (!(std::abs(vec[4 * i + k] - e[k]) <= tol) && bad++ < 5)
            ADD_FAILURE() << "integrator " << integrator << " pixel (" << x << ", " << y << ") object " << o
                          << " channel " << k << ": " << vec[4 * i + k] << ", expected " << e[k] << " +- " << tol;
        }
      }
    EXPECT_EQ(bad, 0);
    EXPECT_GT(checked[1], 100);
    EXPECT_GT(checked[2], 20);
    EXPECT_GT(checked[3], 10);
  }
  // With the steps a shutter (motion blur) the pass stays zero, as Cycles'.
  rs.motion_pass = 0;
  rs.integrator = LT_INTEGRATOR_PATH;
  const Passes blurred = render(moving.get(), rs);
  for (float v : blurred.pass(LT_PASS_VECTOR)) ASSERT_EQ(v, 0.0f);
}

// An object growing from nothing (scale 0 at the shutter's opening, 1 at its centre, 2 at its
// closing: an animator's "pop in"), turning or not: Cycles blurs the growth, the step scaled to
// nothing taking its neighbour's rotation (transform_motion_decompose). It keeps its motion (no
// warning) and is hit where its interpolated scale puts it: at time 0.25 the 2-long strip is 1 long,
// at 0.75 3 long, along its interpolated direction.
TEST(Motion, AnObjectGrowingFromNothingIsHitWhereItsScaleIsAtTheRaysTime) {
  for (float turn : {0.0f, 40.0f}) {
    Geometry g;
    std::vector<std::string> warnings;
    Instance inst;
    inst.mesh = g.add_mesh(strip(), warnings);
    inst.xf = rot_z(turn * kDeg, 1);
    inst.motion = {rot_z(0, 0), rot_z(turn * kDeg, 1), rot_z(2 * turn * kDeg, 2)};
    g.add_instance(inst, warnings);
    g.commit();
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    EXPECT_EQ(g.motion_instances(), 1u);
    // The step scaled to nothing takes the centre's rotation: over the first half the strip grows
    // along turn, over the second it grows and turns from turn to 2 turn.
    for (auto [time, length, angle] : {std::tuple{0.25f, 1.0f, turn}, std::tuple{0.75f, 3.0f, 1.5f * turn}}) {
      const float c = std::cos(angle * kDeg), s = std::sin(angle * kDeg);
      Hit h;
      EXPECT_TRUE(hit_down(g, 0.9f * length * c, 0.9f * length * s, time, &h)) << turn << " " << time;
      EXPECT_FALSE(hit_down(g, 1.1f * length * c, 1.1f * length * s, time, &h)) << turn << " " << time;
      if (hit_down(g, 0.5f * length * c, 0.5f * length * s, time, &h)) {
        const SurfacePoint sp = g.surface(h);
        EXPECT_NEAR(std::abs(sp.ng.z), 1.0f, 1e-5f);
        EXPECT_TRUE(is_finite(sp.p) && is_finite(sp.ns));
      } else {
        ADD_FAILURE() << "no hit half way along at " << time;
      }
    }
  }
}

namespace {

// A turning box (quaternion motion) and a still one over a floor under an area light; `motion`
// null: the turning box still at its centre transform. The turning box is instance 1.
ScenePtr box_scene(const float* motion) {
  ScenePtr sp = new_scene();
  lt_scene* s = sp.get();
  add_object(s, plane(20, 20), add_diffuse(s, {0.7f, 0.6f, 0.5f}));
  const int mat = add_diffuse(s, {0.2f, 0.5f, 0.8f});
  MeshData b = box({-0.6f, -0.2f, 0}, {0.6f, 0.2f, 0.8f});
  lt_instance_desc d{};
  d.mesh = add_mesh(s, b);
  const Xform centre = identity();
  std::copy(centre.begin(), centre.end(), d.transform);
  d.materials = &mat;
  d.material_count = 1;
  d.visibility = LT_VISIBLE_ALL;
  d.motion_transforms = motion;
  d.motion_step_count = motion ? 3 : 0;
  int id;
  check(lt_scene_add_instance(s, &d, &id), "instance");
  EXPECT_EQ(id, 1);
  add_object(s, b, mat, translate({1.5f, 0.8f, 0}));
  add_light(s, area_light(LT_AREA_RECTANGLE, 1, 0.5f, look_at({0, -1, 3}, {0, 0, 0}), 300));
  set_camera(s, perspective_camera(look_at({0.5f, -5, 2.5f}, {0, 0, 0.5f}), 35));
  check(lt_scene_commit(s), "commit");
  return sp;
}

}  // namespace

// Persistent Data with motion blur (scene_sync.py): a committed scene's instance given motion,
// other motion and none again renders as a scene built with that motion, to the bit.
TEST(Motion, AnInstancesMotionEditedAfterCommitIsTheMotionItWouldBeBuiltWith) {
  std::vector<float> turn, slide;
  for (float a : {-0.8f, 0.0f, 0.8f}) {
    const Xform r = rotate({0, 0, 1}, a), t = translate({a, 0, 0});
    turn.insert(turn.end(), r.begin(), r.end());
    slide.insert(slide.end(), t.begin(), t.end());
  }
  ScenePtr edited = box_scene(nullptr);
  lt_render_settings rs = render_settings(40, 30, 4, 3);
  rs.threads = 1;
  lt_scene_stats st{};
  for (const std::vector<float>* motion : std::vector<const std::vector<float>*>{&turn, &slide, nullptr}) {
    const float* m = motion ? motion->data() : nullptr;
    check(lt_scene_set_instance_motion(edited.get(), 1, m, m ? 3 : 0), "motion");
    check(lt_scene_commit(edited.get()), "commit");
    check(lt_scene_get_stats(edited.get(), &st), "stats");
    EXPECT_EQ(st.motion_instances, m ? 1u : 0u);
    ScenePtr built = box_scene(m);
    for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
      rs.integrator = integrator;
      const Passes a = render(edited.get(), rs), b = render(built.get(), rs);
      EXPECT_TRUE(same_bits(a.combined, b.combined)) << "integrator " << integrator << (m ? " moving" : " still");
    }
  }
  // Bad input: refused, or (a step not finite) the instance left still with a warning.
  EXPECT_EQ(lt_scene_set_instance_motion(edited.get(), 3, turn.data(), 3), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_scene_set_instance_motion(edited.get(), 1, turn.data(), 2), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(lt_scene_set_instance_motion(edited.get(), 1, nullptr, 3), LT_ERROR_INVALID_ARGUMENT);
  turn[12 + 3] = NAN;
  const int before = lt_scene_warning_count(edited.get());
  EXPECT_EQ(lt_scene_set_instance_motion(edited.get(), 1, turn.data(), 3), LT_OK);
  EXPECT_EQ(lt_scene_warning_count(edited.get()), before + 1);
  check(lt_scene_commit(edited.get()), "commit");
  check(lt_scene_get_stats(edited.get(), &st), "stats");
  EXPECT_EQ(st.motion_instances, 0u);
}
