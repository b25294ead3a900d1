// Analytic interior: the camera and a point light of power P at the centre of a closed diffuse
// sphere of radius R and albedo rho (normals facing in).
//
// Direct light on the wall: E0 = P / (4 pi R^2) (Lantern's point light, as Cycles: intensity
// P / (4 pi)), so L_direct = rho E0 / pi. Every wall point sees the whole enclosure, whose
// form-factor kernel integrates to pi for any closed enclosure; the sphere's kernel is moreover
// constant, so all bounces give L = L_direct / (1 - rho) everywhere.
//
// Tessellation: the wall is an icosphere whose vertices lie on the sphere. On a face at plane
// distance h from the centre the direct term is L_direct cos^3(theta) R^2 / h^2, which lies in
// [h / R, R^2 / h^2] x L_direct (theta = 0 at the foot point, cos = h / R at the vertices). So the
// direct radiance deviates from the sphere's by at most b = max(delta, 1 / (1 - delta)^2 - 1) with
// delta = max over faces of 1 - h / R. The transport operator (rho / pi) x integral of G over a
// closed enclosure maps [a, c] into [rho a, rho c], so the full solution obeys the same relative
// bound b (a maximum principle): the test allows b x L on top of 5 standard errors, and checks
// that this allowance is small beside the statistical one (the test stays noise-limited).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "scene_builders.h"

using namespace lt_test;

namespace {

// delta = max over faces of 1 - h / R for a mesh whose vertices lie at distance R from the origin.
double tessellation_delta(const MeshData& m, double radius) {
  double delta = 0;
  for (int t = 0; t < m.triangle_count(); ++t) {
    double p[3][3];
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) p[c][k] = m.positions[3 * m.triangles[3 * t + c] + k];
    double e1[3], e2[3], n[3];
    for (int k = 0; k < 3; ++k) e1[k] = p[1][k] - p[0][k], e2[k] = p[2][k] - p[0][k];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    double h = std::abs(n[0] * p[0][0] + n[1] * p[0][1] + n[2] * p[0][2]) / len;
    delta = std::max(delta, 1 - h / radius);
  }
  return delta;
}

struct Interior {
  ScenePtr scene;
  double delta = 0;
};

Interior build_interior(float radius, float rho, float watts) {
  Interior in;
  in.scene = new_scene();
  lt_scene* s = in.scene.get();
  MeshData wall = icosphere(radius, 6);
  flip_winding(wall);  // facing the inside
  in.delta = tessellation_delta(wall, radius);
  add_object(s, wall, add_diffuse(s, {rho, rho, rho}));
  add_light(s, point_light({0, 0, 0}, watts));
  // Wide-angle camera at the centre, looking slightly off the axes.
  set_camera(s, perspective_camera(look_at({0, 0, 0}, {1, 0.3f, 0.2f}), 18));
  EXPECT_EQ(lt_scene_commit(s), LT_OK) << lt_last_error();
  return in;
}

// Checks all three channels against `expected`, with the tessellation allowance `bias` (relative) on
// top of 5 standard errors: every block x block pixel block's mean, then the image mean. Blocks
// rather than single pixels when the estimator is skewed (Russian roulette at low throughput makes
// a few rare long paths carry much of the mean): a pixel's 64 samples would underestimate its own
// variance, while a block's thousands of samples are well inside the normal approximation.
void check_uniform(const Passes& p, double expected, double bias, int block, bool require_noise) {
  int failures = 0;
  for (int by = 0; by + block <= p.height; by += block)
    for (int bx = 0; bx + block <= p.width; bx += block)
      for (int c = 0; c < 3; ++c) {
        RegionStats st = region_stats(p, c, bx, bx + block, by, by + block);
        double tol = 5 * st.standard_error + (bias + 1e-5) * expected;
        if (std::abs(st.mean - expected) > tol && failures++ < 10)
          ADD_FAILURE() << "block at (" << bx << ", " << by << ") channel " << c << ": " << st.mean << ", expected "
                        << expected << " +- " << tol;
      }
  EXPECT_EQ(failures, 0);
  for (int c = 0; c < 3; ++c) {
    RegionStats st = region_stats(p, c, 0, p.width, 0, p.height);
    double statistical = 5 * st.standard_error;
    EXPECT_NEAR(st.mean, expected, statistical + (bias + 1e-5) * expected)
        << "image mean, channel " << c << ": standard error " << st.standard_error << ", tessellation allowance "
        << bias * expected;
    if (require_noise) {
      EXPECT_LT(bias * expected, 0.2 * statistical) << "the tessellation allowance should be far below the noise";
    }
  }
}

}  // namespace

TEST(ApiInterior, PointLightInDiffuseSphereAllBounces) {
  const float R = 2.0f, P = 1000.0f;
  for (float rho : {0.5f, 0.8f}) {
    SCOPED_TRACE("albedo " + std::to_string(rho));
    Interior in = build_interior(R, rho, P);
    const double bias = std::max(in.delta, 1 / ((1 - in.delta) * (1 - in.delta)) - 1);
    ASSERT_LT(bias, 2e-4) << "tessellation too coarse";

    const double E0 = P / (4 * kPi * R * R);
    const double expected = rho * E0 / (kPi * (1 - rho));

    lt_render_settings rs = render_settings(24, 16, rho < 0.6f ? 256 : 512, 5);
    rs.max_bounces = rs.diffuse_bounces = 1024;  // effectively unlimited: rho^1024 is nothing
    Passes p = render(in.scene.get(), rs);
    ASSERT_EQ(p.first_non_finite(), "");
    EXPECT_EQ(p.status.nan_samples, 0u);
    check_uniform(p, expected, bias, 8, /*require_noise=*/true);
  }
}

TEST(ApiInterior, PointLightInDiffuseSphereDirectOnly) {
  // max_bounces 0: direct light only, L = rho E0 / pi. A delta light on a wall whose radiance
  // barely changes inside a pixel: the Variance pass is almost zero and the allowance is the
  // tessellation bound (about 1e-4) plus float rounding.
  const float R = 2.0f, P = 1000.0f, rho = 0.5f;
  Interior in = build_interior(R, rho, P);
  const double bias = std::max(in.delta, 1 / ((1 - in.delta) * (1 - in.delta)) - 1);
  const double expected = rho * (P / (4 * kPi * R * R)) / kPi;

  lt_render_settings rs = render_settings(24, 16, 16, 9);
  rs.max_bounces = 0;
  rs.diffuse_bounces = 1024;
  Passes p = render(in.scene.get(), rs);
  ASSERT_EQ(p.first_non_finite(), "");
  check_uniform(p, expected, bias, 1, /*require_noise=*/false);
}
