// Light units against closed forms (Cycles 3.4's conventions, DESIGN.md): an orthographic camera
// looks straight down at a large diffuse plane of albedo 1 (z = 0), so a pixel reads
// L = E / pi with E the irradiance there. Nothing else is in the scene: no interreflection.
//
//   point, P watts, h above:   E = P / (4 pi) cos(theta) / d^2         (centre: P / (4 pi h^2))
//   spot, pointing down:       the point's E times cos(angle to the axis) times
//                              smoothstep(0, (1 - cos(size / 2)) blend, cos(angle) - cos(size / 2))
//   sun, strength S, angle 0:  E = S cos(incidence)
//   area, P watts, A m^2:      radiance P / (4 A), one-sided towards local -Z; E from the rectangle
//                              form factor (sum of four corner rectangles, below)
//   emission plane / world:    seen directly, L = colour x strength
//
// Tolerances: the expected value of a pixel is the closed form averaged over the pixel (box
// filter of width 1: a sample lands uniformly in its pixel), integrated numerically; then
// 5 standard errors from the Variance pass plus a relative allowance: 1e-3 for delta lights (whose
// only noise is the position inside the pixel), 1e-4 for constants (float rounding).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "scene_builders.h"

using namespace lt_test;

namespace {

// Ortho camera 0.5 m above the origin looking down; image x = world x, image y = world y.
struct View {
  int size = 16;
  float width_m = 2.0f;  // ortho scale
  double pixel_x(double x) const { return (x / size - 0.5) * width_m; }
};
// The centre reading: 8 pixels over 1 cm, so the centre 2 x 2 pixels span +-2.5 mm, where every
// closed form below stays within 2e-5 of its value at the centre (cos^3 falloff: 1.5 x 0.0025^2 x 2).
const View kNarrow{8, 0.01f};

ScenePtr plane_scene(const View& v) {
  ScenePtr s = new_scene();
  add_object(s.get(), plane(200, 200), add_diffuse(s.get(), {1, 1, 1}));
  set_camera(s.get(), orthographic_camera(look_at({0, 0, 0.5f}, {0, 0, 0}, {0, 1, 0}), v.width_m));
  return s;
}

lt_render_settings settings(const View& v, int samples, unsigned seed) {
  lt_render_settings rs = render_settings(v.size, v.size, samples, seed);
  rs.filter = LT_FILTER_BOX;
  rs.filter_width = 1;
  rs.max_bounces = 4;
  return rs;
}

// Mean and variance of the closed form over pixel (px, py), by the midpoint rule on sub x sub points.
struct Moments {
  double mean = 0, variance = 0;
};
Moments pixel_moments(const View& v, int px, int py, const std::function<double(double, double)>& f, int sub) {
  double sum = 0, sum2 = 0;
  for (int j = 0; j < sub; ++j)
    for (int i = 0; i < sub; ++i) {
      double e = f(v.pixel_x(px + (i + 0.5) / sub), v.pixel_x(py + (j + 0.5) / sub));
      sum += e;
      sum2 += e * e;
    }
  const double n = double(sub) * sub;
  return {sum / n, std::max(0.0, sum2 / n - (sum / n) * (sum / n))};
}

// Every pixel and the image mean, all channels, against the pixel-averaged closed form.
//
// Delta lights (delta = true): a sample's value is the closed form at the sample's position, so a
// pixel mean's true variance is the closed form's variance over the pixel / n, known exactly; the
// per-pixel check uses it instead of the Variance pass's estimate, which is unreliable where a
// pixel is barely grazed by a cone edge (a few percent of it lit: most pixels of 64 samples see no
// lit sample and estimate a variance of zero). The image mean uses the Variance pass.
void check_image(const Passes& p, const View& v, const std::function<double(double, double)>& radiance, double relative,
                 int sub, bool delta) {
  ASSERT_EQ(p.first_non_finite(), "");
  EXPECT_EQ(p.status.nan_samples, 0u);
  int failures = 0;
  double sum_expected = 0, sum[3] = {0, 0, 0}, var[3] = {0, 0, 0};
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x) {
      const Moments e = pixel_moments(v, x, y, radiance, sub);
      const double n = p.sample_count[size_t(y) * p.width + x];
      sum_expected += e.mean;
      for (int c = 0; c < 3; ++c) {
        const double m = p.rgba(x, y)[c];
        const double se = delta ? std::sqrt(e.variance / n) : std::sqrt(double(p.var(x, y)[c]));
        const double tol = 5 * se + relative * std::abs(e.mean) + 1e-7;
        sum[c] += m;
        var[c] += p.var(x, y)[c];
        if (std::abs(m - e.mean) > tol && failures++ < 8)
          ADD_FAILURE() << "pixel (" << x << ", " << y << ") channel " << c << ": " << m << ", expected " << e.mean
                        << " +- " << tol;
      }
    }
  EXPECT_EQ(failures, 0);
  const int n = p.width * p.height;
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(sum[c] / n, sum_expected / n, 5 * std::sqrt(var[c]) / n + relative * std::abs(sum_expected / n))
        << "image mean, channel " << c;
}

// Centre 2 x 2 pixels' mean, per channel, against `expected` (5 standard errors + relative), in a
// render of the kNarrow view.
void check_centre(const Passes& p, double expected, double relative) {
  ASSERT_EQ(p.first_non_finite(), "");
  const int x0 = p.width / 2 - 1, y0 = p.height / 2 - 1;
  for (int c = 0; c < 3; ++c) {
    RegionStats st = region_stats(p, c, x0, x0 + 2, y0, y0 + 2);
    EXPECT_NEAR(st.mean, expected, 5 * st.standard_error + relative * expected)
        << "channel " << c << ", standard error " << st.standard_error;
  }
}

double smoothstep(double e0, double e1, double x) {
  if (e1 <= e0) return x < e0 ? 0 : 1;
  double t = std::min(1.0, std::max(0.0, (x - e0) / (e1 - e0)));
  return t * t * (3 - 2 * t);
}

// Form factor (times pi: the irradiance per unit radiance) at a point on the normal through a
// corner of an a x b rectangle at distance c (Howell's catalogue, configuration B-3, for the
// differential element): E / L = 1/2 [A / sqrt(1 + A^2) atan(B / sqrt(1 + A^2)) + same with A, B
// swapped], A = a / c, B = b / c. Odd in A and in B, so signed corner rectangles add up for any
// point under the plane of the rectangle.
double corner_irradiance_per_radiance(double a, double b, double c) {
  const double A = a / c, B = b / c;
  const double sa = std::sqrt(1 + A * A), sb = std::sqrt(1 + B * B);
  return 0.5 * (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb));
}

// Irradiance per unit radiance at (x, y, 0) from the rectangle [-hx, hx] x [-hy, hy] at height h,
// facing down.
double rectangle_irradiance_per_radiance(double hx, double hy, double h, double x, double y) {
  double e = 0;
  for (double sx : {-1.0, 1.0})
    for (double sy : {-1.0, 1.0}) e += corner_irradiance_per_radiance(hx - sx * x, hy - sy * y, h);
  return e;
}

}  // namespace

TEST(ApiLightUnits, RectangleFormulaSelfCheck) {
  // The formula used below against a brute-force integral of cos cos / (pi r^2) over the square.
  const double h = 1, half = 0.5;
  for (double x : {0.0, 0.3, 0.9}) {
    double sum = 0;
    const int n = 600;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        double u = -half + (i + 0.5) * 2 * half / n - x, v = -half + (j + 0.5) * 2 * half / n;
        double r2 = u * u + v * v + h * h;
        sum += h * h / (r2 * r2) / kPi * (2 * half / n) * (2 * half / n);
      }
    EXPECT_NEAR(rectangle_irradiance_per_radiance(half, half, h, x, 0) / kPi, sum, 1e-5) << "x = " << x;
  }
}

// Renders the plane lit by `light` in view v.
Passes render_plane(const View& v, const lt_light_desc& light, int samples, unsigned seed) {
  ScenePtr s = plane_scene(v);
  add_light(s.get(), light);
  EXPECT_EQ(lt_scene_commit(s.get()), LT_OK) << lt_last_error();
  return render(s.get(), settings(v, samples, seed));
}

TEST(ApiLightUnits, PointLight) {
  const double P = 1000;
  const lt_light_desc light = point_light({0, 0, 1}, float(P));
  // Centre: 1000 W at 1 m reads 1000 / (4 pi^2) = 25.33.
  check_centre(render_plane(kNarrow, light, 16, 1), P / (4 * kPi * kPi), 1e-3);
  // Everywhere: L = P / (4 pi^2) cos^3 / h^2 with h = 1.
  const View v;
  check_image(
      render_plane(v, light, 16, 1), v,
      [&](double x, double y) { return P / (4 * kPi * kPi) * std::pow(1 + x * x + y * y, -1.5); }, 1e-3, 32, true);
}

TEST(ApiLightUnits, SpotLight) {
  const double P = 1000;
  const double size = kPi / 2;  // 90 degrees: the cone edge crosses the wide view's corners
  for (double blend : {0.0, 0.3}) {
    SCOPED_TRACE("blend " + std::to_string(blend));
    const lt_light_desc light = spot_light({0, 0, 1}, {0, 0, 0}, float(P), float(size), float(blend));
    // On the axis the spot reads like the point light: 25.33.
    check_centre(render_plane(kNarrow, light, 16, 2), P / (4 * kPi * kPi), 1e-3);
    const double cos_half = std::cos(size / 2);
    auto radiance = [&](double x, double y) {
      double d2 = 1 + x * x + y * y, c = 1 / std::sqrt(d2);  // cos to the axis = cos at the plane
      if (c <= cos_half) return 0.0;
      double spot = c * smoothstep(0, (1 - cos_half) * blend, c - cos_half);
      return P / (4 * kPi * kPi) * spot * c / d2;
    };
    // A hard edge (blend 0) needs a fine sub-grid for the pixels it crosses.
    const View v;
    check_image(render_plane(v, light, 64, 2), v, radiance, 1e-3, blend == 0 ? 256 : 64, true);
  }
}

TEST(ApiLightUnits, SunLight) {
  for (double incidence : {0.0, kPi / 3}) {
    SCOPED_TRACE("incidence " + std::to_string(incidence));
    const lt_light_desc light = sun_light({float(std::sin(incidence)), 0, float(-std::cos(incidence))}, 1.0f);
    // Strength 1 facing the plane: L = 1 / pi; at 60 degrees, cos 60 / pi.
    const double expected = std::cos(incidence) / kPi;
    check_centre(render_plane(kNarrow, light, 4, 3), expected, 1e-4);
    const View v;
    check_image(
        render_plane(v, light, 4, 3), v, [&](double, double) { return expected; }, 1e-4, 1, true);
  }
}

TEST(ApiLightUnits, SquareAreaLight) {
  // 1 m x 1 m, 1000 W, 1 m above the plane facing down: radiance P / (4 A) = 250.
  const double P = 1000, side = 1, h = 1;
  const double L = P / (4 * side * side);
  const lt_light_desc light =
      area_light(LT_AREA_SQUARE, float(side), float(side), look_at({0, 0, float(h)}, {0, 0, 0}, {0, 1, 0}), float(P));
  // Centre: E / L = 4 x corner(0.5, 0.5, 1) = 0.752, so L_plane = 250 x 0.752 / pi = 59.86.
  const double centre = L * rectangle_irradiance_per_radiance(0.5 * side, 0.5 * side, h, 0, 0) / kPi;
  EXPECT_NEAR(centre, 59.86, 0.01);
  check_centre(render_plane(kNarrow, light, 1024, 4), centre, 1e-4);
  const View v;
  check_image(
      render_plane(v, light, 256, 4), v,
      [&](double x, double y) { return L * rectangle_irradiance_per_radiance(0.5 * side, 0.5 * side, h, x, y) / kPi; },
      1e-4, 8, false);
}

TEST(ApiLightUnits, EmissionPlaneAndWorldSeenDirectly) {
  const View v;
  // An emission plane below the camera: radiance colour x strength, from both sides.
  for (bool flipped : {false, true}) {
    SCOPED_TRACE(flipped ? "back side" : "front side");
    ScenePtr s = new_scene();
    MeshData m = plane(10, 10);
    if (flipped) flip_winding(m);
    add_object(s.get(), m, add_emission(s.get(), {0.2f, 0.5f, 1.0f}, 3));
    set_camera(s.get(), orthographic_camera(look_at({0, 0, 0.5f}, {0, 0, 0}, {0, 1, 0}), v.width_m));
    ASSERT_EQ(lt_scene_commit(s.get()), LT_OK) << lt_last_error();
    Passes p = render(s.get(), settings(v, 4, 5));
    ASSERT_EQ(p.first_non_finite(), "");
    const double expected[3] = {0.6, 1.5, 3.0};
    for (int y = 0; y < p.height; ++y)
      for (int x = 0; x < p.width; ++x) {
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(p.rgba(x, y)[c], expected[c], 1e-6 * expected[c]);
        ASSERT_EQ(p.rgba(x, y)[3], 1.0f);
      }
  }
  // The world seen directly: colour x strength, alpha 1; with a transparent film, alpha 0 and black.
  ScenePtr s = new_scene();
  set_world(s.get(), {0.25f, 0.5f, 0.75f}, 2);
  set_camera(s.get(), perspective_camera(look_at({0, 0, 0}, {1, 0, 0})));
  ASSERT_EQ(lt_scene_commit(s.get()), LT_OK) << lt_last_error();
  lt_render_settings rs = settings(v, 4, 6);
  Passes p = render(s.get(), rs);
  ASSERT_EQ(p.first_non_finite(), "");
  rs.transparent_background = 1;
  Passes t = render(s.get(), rs);
  ASSERT_EQ(t.first_non_finite(), "");
  const double expected[3] = {0.5, 1.0, 1.5};
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        ASSERT_NEAR(p.rgba(x, y)[c], expected[c], 1e-6 * expected[c]);
        ASSERT_EQ(t.rgba(x, y)[c], 0.0f);
      }
      ASSERT_EQ(p.rgba(x, y)[3], 1.0f);
      ASSERT_EQ(t.rgba(x, y)[3], 0.0f);
    }
}

// A mesh light 10 cm under a ceiling lights the ceiling (with its back: Cycles' mesh lights are
// two-sided) as an area lamp of the same radiance facing the ceiling does: per 8x8 tile within 5
// standard errors, and the image mean within 4. Most of the ceiling sees the emitter at a grazing
// angle, where a shadow ray aimed from its offset origin at the unmoved light point met the
// emitter before its end (the ceiling stayed black; issue 12).
TEST(ApiLightUnits, MeshLightAtGrazingAnglesAsAnAreaLamp) {
  const float h = 1.9f, side = 0.5f, strength = 50;
  auto render_ceiling = [&](bool mesh_light, int integrator) {
    ScenePtr s = new_scene();
    MeshData ceiling = plane(6, 6);
    flip_winding(ceiling);  // facing down
    add_object(s.get(), ceiling, add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}), translate({0, 0, 2}));
    if (mesh_light) {
      MeshData quad = plane(side, side);
      flip_winding(quad);  // its front faces down, its back lights the ceiling
      add_object(s.get(), quad, add_emission(s.get(), {1, 1, 1}, strength), translate({0, 0, h}));
    } else {  // radiance P / (4 A) = strength, facing up
      add_light(s.get(), area_light(LT_AREA_SQUARE, side, side, look_at({0, 0, h}, {0, 0, 3}, {0, 1, 0}),
                                    4 * side * side * strength));
    }
    // Looking up at the ceiling from between it and the light, which the camera does not see.
    set_camera(s.get(), orthographic_camera(look_at({0, 0, 1.95f}, {0, 0, 3}, {0, 1, 0}), 5));
    EXPECT_EQ(lt_scene_commit(s.get()), LT_OK) << lt_last_error();
    lt_render_settings rs = render_settings(32, 32, 64, 7);
    rs.integrator = integrator;
    rs.max_bounces = 1;  // direct light, by both next-event estimation and BSDF sampling
    return render(s.get(), rs);
  };
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_VOLPATH}) {
    SCOPED_TRACE(integrator == LT_INTEGRATOR_PATH ? "PATH" : "VOLPATH");
    Passes mesh = render_ceiling(true, integrator), lamp = render_ceiling(false, integrator);
    ASSERT_EQ(mesh.first_non_finite(), "");
    EXPECT_EQ(differing_tiles(mesh, lamp, 8, 5), "");
    for (int c = 0; c < 3; ++c) {
      RegionStats a = region_stats(mesh, c, 0, mesh.width, 0, mesh.height);
      RegionStats b = region_stats(lamp, c, 0, lamp.width, 0, lamp.height);
      EXPECT_GT(b.mean, 0.1);
      EXPECT_NEAR(a.mean, b.mean, 4 * std::hypot(a.standard_error, b.standard_error)) << "channel " << c;
    }
  }
}

// Negative energy and negative emission strength are negative light (Blender allows both; Cycles
// 3.4 renders a scene whose every light is negated as the exact negative of the positive image,
// measured at 64 spp, same seed). Lights are picked by the magnitude of their power and Russian
// roulette looks at the throughput's magnitude, so every random decision is the same with either
// sign: the negated scene's RGB must be the exact negative, for every integrator. A closed
// coloured room, so that paths live past the bounce where Russian roulette starts.
TEST(ApiLightUnits, NegativeLightsRenderAsTheNegativeOfThePositiveScene) {
  auto build = [](float sign) {
    ScenePtr s = new_scene();
    MeshData room = box({-3, -5, -0.01f}, {3, 3, 4});
    flip_winding(room);
    add_object(s.get(), room, add_diffuse(s.get(), {0.9f, 0.6f, 0.3f}));
    add_object(s.get(), plane(6, 6), add_diffuse(s.get(), {0.8f, 0.7f, 0.6f}));
    add_object(s.get(), box({-0.4f, -0.4f, 0}, {0.4f, 0.4f, 0.8f}), add_glossy(s.get(), {0.9f, 0.9f, 0.9f}, 0.3f));
    add_object(s.get(), plane(0.5f, 0.5f), add_emission(s.get(), {1.0f, 0.5f, 0.25f}, sign * 20),
               compose(translate({-1, 0.5f, 1.2f}), rotate({1, 0, 0}, 3.0f)));
    add_light(s.get(), point_light({1, -0.5f, 1.5f}, sign * 300));
    lt_light_desc area = area_light(LT_AREA_SQUARE, 0.5f, 0.5f, look_at({0.5f, 1, 2}, {0, 0, 0}), sign * 200);
    add_light(s.get(), area);
    add_light(s.get(), sun_light({0.3f, 0.2f, -1}, sign * 2, 0.1f));
    set_camera(s.get(), perspective_camera(look_at({0, -4, 3}, {0, 0, 0.3f}), 35));
    EXPECT_EQ(lt_scene_commit(s.get()), LT_OK) << lt_last_error();
    return s;
  };
  ScenePtr positive = build(1), negative = build(-1);
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_BIDIRECTIONAL, LT_INTEGRATOR_VOLPATH}) {
    SCOPED_TRACE("integrator " + std::to_string(integrator));
    lt_render_settings rs = render_settings(24, 16, 8, 7);
    rs.integrator = integrator;
    Passes p = render(positive.get(), rs), n = render(negative.get(), rs);
    ASSERT_EQ(p.first_non_finite(), "");
    ASSERT_EQ(n.first_non_finite(), "");
    double sum = 0;
    for (int y = 0; y < p.height; ++y)
      for (int x = 0; x < p.width; ++x)
        for (int c = 0; c < 3; ++c) {
          ASSERT_EQ(n.rgba(x, y)[c], -p.rgba(x, y)[c]) << "pixel " << x << ", " << y << " channel " << c;
          sum += p.rgba(x, y)[c];
        }
    EXPECT_GT(sum / (3.0 * p.width * p.height), 0.05) << "the positive scene must be lit";
    EXPECT_EQ(n.status.nan_samples, 0u);
  }
}
