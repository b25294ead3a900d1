// Cycles' shadow terminator Geometry Offset (geometry/terminator.h, Geometry::shadow_origin).
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/geometry.h"
#include "geometry/terminator.h"

using namespace lt;

namespace {

// A small triangle on the unit sphere around +Z, wound counter-clockwise seen from outside, its
// corner normals the sphere's.
void sphere_patch(Vec3 v[3], Vec3 n[3]) {
  const float a = 0.3f;
  const Vec3 d[3] = {Vec3(std::sin(a), 0, std::cos(a)), Vec3(-0.5f * std::sin(a), 0.866f * std::sin(a), std::cos(a)),
                     Vec3(-0.5f * std::sin(a), -0.866f * std::sin(a), std::cos(a))};
  for (int k = 0; k < 3; ++k) v[k] = n[k] = normalize(d[k]);
}

bool same(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

struct Patch {
  Geometry g;
  SurfacePoint sp;
  // One instance of the sphere patch (smooth, or with the face normal at every corner), scaled by
  // `scale`; `users` instances of the mesh.
  Patch(float offset, bool smooth, float scale = 1, int users = 1) {
    std::vector<std::string> warnings;
    Mesh m;
    Vec3 v[3], n[3];
    sphere_patch(v, n);
    m.positions.assign(v, v + 3);
    m.indices = {0, 1, 2};
    const Vec3 face = normalize(cross(v[1] - v[0], v[2] - v[0]));
    for (int k = 0; k < 3; ++k) m.corner_normals.push_back(smooth ? n[k] : face);
    Instance inst;
    inst.mesh = g.add_mesh(std::move(m), warnings);
    inst.xf = Transform();
    for (int r = 0; r < 3; ++r) inst.xf.m[5 * r] = scale;
    inst.terminator_geometry = offset;
    for (int i = 0; i < users; ++i) g.add_instance(inst, warnings);
    g.commit();
    Hit h;
    h.instance = 0;
    h.primitive = 0;
    h.u = h.v = 1.0f / 3;
    sp = g.surface(h);
  }
  // A light direction at `deg` degrees from the geometric normal, in the xz plane.
  Vec3 light(float deg) const {
    const float r = deg * kPi / 180;
    return normalize(sp.ng * std::cos(r) + normalize(cross(sp.ng, Vec3(0, 1, 0))) * std::sin(r));
  }
  Vec3 origin(const Vec3& wi) const { return g.shadow_origin(sp, sp.ns, sp.ng, wi); }
};

}  // namespace

TEST(Terminator, OffsetAmountFollowsCycles) {
  // Above the cutoff: 1 - NgL / cutoff; below it: 2 - (NgL + NL) / cutoff; clamped to [0, 1].
  EXPECT_FLOAT_EQ(terminator_offset_amount(0.1f, 0.5f, 0.05f), 0.5f);
  EXPECT_FLOAT_EQ(terminator_offset_amount(0.1f, 0.5f, 0.5f), 0.0f);
  EXPECT_FLOAT_EQ(terminator_offset_amount(0.1f, 0.08f, 0.04f), 0.8f);
  EXPECT_FLOAT_EQ(terminator_offset_amount(0.1f, 0.02f, -0.3f), 1.0f);
}

TEST(Terminator, SmoothOffsetRisesTowardsThePhongSurface) {
  Vec3 v[3], n[3];
  sphere_patch(v, n);
  const Vec3 ng = normalize(cross(v[1] - v[0], v[2] - v[0]));
  ASSERT_GT(ng.z, 0);
  const Vec3 p = (v[0] + v[1] + v[2]) / 3.0f;
  const Vec3 off = smooth_surface_offset(v, n, 1.0f / 3, 1.0f / 3, ng);
  // Along the interpolated normal, outwards, to the corners' tangent planes (the linear envelope,
  // here above half the parabola's height): for this patch each plane lies 1 - cos^2(0.3) above
  // the centroid along that corner's normal, a little beyond the sphere the normals imply.
  const Vec3 nn = (n[0] + n[1] + n[2]) / 3.0f;
  EXPECT_NEAR(length(cross(off, nn)), 0.0f, 1e-6f);
  const float height = dot(off, nn) / length_squared(nn);
  EXPECT_NEAR(height, 1 - std::cos(0.3f) * std::cos(0.3f), 2e-5f);
  EXPECT_GT(height, 1 - length(p));
  // The corners lie on that surface: no offset there.
  EXPECT_NEAR(length(smooth_surface_offset(v, n, 0, 0, ng)), 0.0f, 1e-6f);
  EXPECT_NEAR(length(smooth_surface_offset(v, n, 1, 0, ng)), 0.0f, 1e-6f);
  // Seen from the other side (normals facing away from the ray's side): the offset is not outwards.
  EXPECT_LE(dot(smooth_surface_offset(v, n, 1.0f / 3, 1.0f / 3, -ng), nn), 0.0f);
  // Flat corner normals: the surface is the triangle itself.
  const Vec3 flat[3] = {ng, ng, ng};
  EXPECT_NEAR(length(smooth_surface_offset(v, flat, 1.0f / 3, 1.0f / 3, ng)), 0.0f, 1e-6f);
}

TEST(Terminator, ShadowOriginMovesOnlySmoothTrianglesAtGrazingLight) {
  const Patch on(0.1f, true), off(0.0f, true), flat(0.1f, false);
  const Vec3 grazing = on.light(88), steep = on.light(30);
  // Offset 0 and flat triangles: exactly today's origin.
  EXPECT_TRUE(same(off.origin(grazing), spawn_origin(off.sp, grazing)));
  EXPECT_TRUE(same(flat.origin(grazing), spawn_origin(flat.sp, grazing)));
  // Light well above the cutoff: untouched too.
  EXPECT_TRUE(same(on.origin(steep), spawn_origin(on.sp, steep)));
  // Grazing light on the smooth triangle (cosines within the cutoff: the whole offset): the origin
  // rises off the triangle past the sphere, up to the envelope's height along the normals.
  const Vec3 o = on.origin(grazing);
  const float rise = dot(o - on.sp.p, on.sp.ng);
  EXPECT_GT(rise, 1 - length(on.sp.p));
  EXPECT_LT(rise, 1 - std::cos(0.3f) * std::cos(0.3f));
}

TEST(Terminator, InstancedMeshesOffsetInObjectSpaceAlike) {
  // Cycles works in world space for a single user and in object space for instances; under a
  // uniform scale both give the same origin.
  const Patch one(0.1f, true, 2.0f, 1), two(0.1f, true, 2.0f, 2);
  const Vec3 wi = one.light(88);
  const Vec3 a = one.origin(wi), b = two.origin(wi);
  EXPECT_GT(dot(a - one.sp.p, one.sp.ng), 2 - length(one.sp.p));
  EXPECT_NEAR(length(a - b), 0.0f, 1e-5f);
}
