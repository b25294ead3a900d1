// The camera: the thin lens (Cycles' depth of field) keeps the plane in focus sharp, samples its
// aperture uniformly and agrees with the projection BDPT's light tracing uses (a camera ray's
// points project back to its film position and lens point, and the camera's directional density
// integrates to one over the film); without an aperture the rays are the pinhole's. Panoramas map
// the film as Cycles' equirectangular and fisheye projections do, and leave the film outside a
// fisheye's circle black and opaque. The pixel filter's sampling has the density its pdf claims
// (BDPT's light tracing splats with it) and follows the filter's profile.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "api/handles.h"
#include "core/film.h"
#include "core/sampling.h"
#include "scene/camera.h"
#include "scene_builders.h"

using namespace lt_test;

namespace {

constexpr int kW = 64, kH = 48;

lt::Camera camera_of(const lt_camera_desc& d, int w = kW, int h = kH) {
  ScenePtr s = new_scene();
  set_camera(s.get(), d);  // through the ABI: its validation and conversions
  return lt::Camera(s->scene.camera, w, h);
}

float dist(const lt::Vec3& a, const lt::Vec3& b) { return lt::length(a - b); }

const Xform kView = look_at({1, -4, 2}, {0, 0, 0.5f});

}  // namespace

// Every lens sample's ray through a film position meets the plane in focus (at the focus
// distance along the view axis) at the pinhole ray's point there; points off that plane spread.
// With a 50 mm lens at F/1.4 the aperture radius is 17.9 mm (Cycles: focal length in metres /
// 2 F-stop), for a round aperture and for 6 rotated blades with an anamorphic ratio.
TEST(Camera, ThinLensKeepsThePlaneInFocusSharp) {
  for (int blades : {0, 6}) {
    const lt_camera_desc d = with_dof(perspective_camera(kView, 50), 3.5f, 1.4f, blades, 0.3f, 1.7f);
    const lt::Camera cam = camera_of(d), pin = camera_of(perspective_camera(kView, 50));
    ASSERT_TRUE(cam.has_lens());
    ASSERT_FALSE(pin.has_lens());
    if (blades == 0)  // the disk's rightmost point: the radius over the ratio
      EXPECT_NEAR(lt::length(cam.lens_point({1, 0.5f}) - cam.position()), 0.05f / (2 * 1.4f) / 1.7f, 1e-5f);
    lt::Sampler sampler(3, 0, 0);
    double spread_off_focus = 0;
    for (int i = 0; i < 200; ++i) {
      const float x = sampler.next_1d() * kW, y = sampler.next_1d() * kH;
      lt::Ray p;
      ASSERT_TRUE(pin.generate(x, y, &p));
      // The pinhole ray's point at depth 3.5 and at depth 2.
      const lt::Vec3 focus = p.o + p.d * (3.5f / lt::dot(p.d, pin.forward()));
      const lt::Vec3 near = p.o + p.d * (2.0f / lt::dot(p.d, pin.forward()));
      for (int k = 0; k < 16; ++k) {
        lt::Ray r;
        ASSERT_TRUE(cam.generate(x, y, sampler.next_2d(), &r));
        EXPECT_NEAR(lt::length(r.d), 1.0f, 1e-5f);
        EXPECT_NEAR(cam.depth(r.o), 0.0f, 1e-5f) << "the lens lies in the camera's plane";
        const float t = (3.5f - cam.depth(r.o)) / lt::dot(r.d, cam.forward());
        EXPECT_LT(dist(r.o + r.d * t, focus), 2e-5f * 3.5f) << "blades " << blades;
        const float tn = (2.0f - cam.depth(r.o)) / lt::dot(r.d, cam.forward());
        spread_off_focus += dist(r.o + r.d * tn, near);
        // The clipping range is the pinhole ray's (Cycles).
        EXPECT_NEAR(r.tmin, p.tmin, 1e-6f);
        EXPECT_NEAR(r.tmax, p.tmax, 1e-2f);
      }
    }
    EXPECT_GT(spread_off_focus / (200 * 16), 0.003) << "points off the focus plane must blur";
  }
}

// Without an aperture (use_dof off) the rays are exactly the pinhole's: the same origin for every
// lens sample, whatever the focus settings say.
TEST(Camera, NoApertureIsThePinhole) {
  lt_camera_desc d = with_dof(perspective_camera(kView, 35), 2, 2.8f, 5);
  d.use_dof = 0;
  const lt::Camera cam = camera_of(d), pin = camera_of(perspective_camera(kView, 35));
  EXPECT_FALSE(cam.has_lens());
  EXPECT_TRUE(cam.connectable());
  for (float x : {0.5f, 17.25f, 63.9f}) {
    lt::Ray a, b;
    ASSERT_TRUE(cam.generate(x, 11.5f, {0.9f, 0.1f}, &a));
    ASSERT_TRUE(pin.generate(x, 11.5f, &b));
    EXPECT_EQ(a.o.x, b.o.x);
    EXPECT_EQ(a.d.x, b.d.x);
    EXPECT_EQ(a.d.y, b.d.y);
    EXPECT_EQ(a.d.z, b.d.z);
    EXPECT_EQ(a.tmax, b.tmax);
  }
}

// The lens points are uniform over the aperture: the fraction in each of 8 x 8 cells of its
// bounding box matches the cell's share of the aperture's area (measured on a fine grid against
// the disk or the regular polygon of Cycles' regular_polygon_sample: corners at rotation +
// (2k + 1) pi / blades), chi-square over the cells; lens_area is the shape's area.
TEST(Camera, LensSamplesAreUniformOverTheAperture) {
  struct Case {
    int blades;
    float rotation, ratio;
  };
  for (Case c : {Case{0, 0, 1}, Case{5, 0.4f, 1}, Case{3, -1.0f, 2.0f}, Case{0, 0, 0.6f}}) {
    const lt_camera_desc d = with_dof(perspective_camera(identity(), 50), 4, 2.0f, c.blades, c.rotation, c.ratio);
    const lt::Camera cam = camera_of(d);
    const float r = 0.05f / 4, rx = r / c.ratio;  // identity transform: lens x, y are world x, y
    auto inside = [&](float x, float y) {
      x *= c.ratio;  // back to the round / regular shape
      if (c.blades < 3) return x * x + y * y <= r * r;
      // Inside every edge: the apothem along each edge's mid-angle.
      const float a = float(M_PI) / c.blades, apothem = r * std::cos(a);
      for (int k = 0; k < c.blades; ++k) {
        const float mid = c.rotation + 2 * a * k;
        if (x * std::cos(mid) + y * std::sin(mid) > apothem) return false;
      }
      return true;
    };
    constexpr int kCells = 8, kFine = 64, kN = 200000;
    std::vector<double> expected(kCells * kCells, 0), observed(kCells * kCells, 0);
    double area = 0;
    for (int j = 0; j < kCells * kFine; ++j)
      for (int i = 0; i < kCells * kFine; ++i) {
        const float x = -rx + 2 * rx * (i + 0.5f) / (kCells * kFine), y = -r + 2 * r * (j + 0.5f) / (kCells * kFine);
        if (!inside(x, y)) continue;
        expected[(j / kFine) * kCells + i / kFine] += 1;
        area += 4 * rx * r / double(kCells * kFine * kCells * kFine);
      }
    EXPECT_NEAR(cam.lens_area(), area, 0.01 * area) << "blades " << c.blades;
    double total = 0;
    for (double& e : expected) total += e;
    for (double& e : expected) e *= kN / total;
    lt::Sampler sampler(9, 1, 2);
    for (int n = 0; n < kN; ++n) {
      const lt::Vec3 p = cam.lens_point(sampler.next_2d());
      ASSERT_TRUE(inside(p.x * (1 - 1e-5f), p.y * (1 - 1e-5f))) << p.x << " " << p.y;
      const int i = std::min(kCells - 1, int((p.x + rx) / (2 * rx) * kCells));
      const int j = std::min(kCells - 1, int((p.y + r) / (2 * r) * kCells));
      observed[j * kCells + i] += 1;
    }
    // Chi-square over the cells with a fair share of the aperture (edge cells the fine grid
    // barely reaches would be dominated by its discretisation error).
    double chi2 = 0;
    int dof = -1;
    for (int k = 0; k < kCells * kCells; ++k) {
      if (expected[k] < 0.2 * kN / (kCells * kCells)) continue;
      chi2 += (observed[k] - expected[k]) * (observed[k] - expected[k]) / expected[k];
      ++dof;
    }
    // The 1e-4 quantile of chi-square is below dof + 5 sqrt(2 dof) for these dof (about 40..64).
    EXPECT_LT(chi2, dof + 5 * std::sqrt(2.0 * dof)) << "blades " << c.blades << " ratio " << c.ratio;
  }
}

// A perspective camera zooming over the shutter (Cycles' perspective motion): the view plane at
// the shutter's opening 0.6 times the centre's, at its closing 1.7 times.
lt_camera_desc zooming(lt_camera_desc d) {
  d.zoom_pre = 0.6f;
  d.zoom_post = 1.7f;
  return d;
}

// A camera ray's points, within its clipping range, project back (Camera::project, BDPT's t = 1)
// to the ray's film position, direction and start (its near clip) from its lens point (and the
// pinhole's; and a zooming camera's, at the ray's time); beyond the range they do not.
TEST(Camera, LensRaysProjectBackToTheirFilmPosition) {
  lt_camera_desc pin = perspective_camera(kView, 28);
  pin.clip_start = 0.5f;
  pin.clip_end = 20;
  pin.shift_x = 0.1f;
  int checked = 0;
  const lt_camera_desc lens = with_dof(pin, 2.5f, 0.7f, 7, 0.2f, 1.4f);
  for (const lt_camera_desc& d : {lens, pin, zooming(lens)}) {
    const lt::Camera cam = camera_of(d);
    lt::Sampler sampler(5, 0, 0);
    for (int i = 0; i < 2000; ++i) {
      const float x = sampler.next_1d() * kW, y = sampler.next_1d() * kH;
      const float time = d.zoom_pre > 0 ? sampler.next_1d() : 0.5f;
      lt::Ray r;
      ASSERT_TRUE(cam.generate(x, y, sampler.next_2d(), &r, time));
      // Inside the range (its ends are where rounding decides).
      const float t = r.tmin * 1.001f + (r.tmax * 0.999f - r.tmin * 1.001f) * std::pow(sampler.next_1d(), 3.0f);
      lt::Camera::Projection pr;
      ASSERT_TRUE(cam.project(r.o, r.o + r.d * t, 0, &pr, time)) << t;
      ASSERT_EQ(pr.count, 1);
      EXPECT_NEAR(pr.at[0].film.x, x, 2e-3f * (1 + t));
      EXPECT_NEAR(pr.at[0].film.y, y, 2e-3f * (1 + t));
      EXPECT_NEAR(pr.distance, t, 1e-4f * t);
      EXPECT_NEAR(pr.near, r.tmin, 1e-5f * r.tmin);  // where the ray starts: t = 1's connection ends there
      EXPECT_GT(lt::dot(pr.dir, r.d), 1 - 1e-6f);
      EXPECT_FALSE(cam.project(r.o, r.o + r.d * (r.tmin * 0.98f), 1, &pr, time));
      EXPECT_FALSE(cam.project(r.o, r.o + r.d * (r.tmax * 1.02f), 1, &pr, time));
      ++checked;
    }
  }
  EXPECT_EQ(checked, 6000);
}

// The camera's directional density from a lens point, the film's importance (pixels per
// steradian; 1 / (a cos^3) for a view-plane area a per pixel, pbrt-v4's
// PerspectiveCamera::PDF_We) over the film's pixels, integrates to one over the directions that
// reach the film: Monte Carlo over the sphere of directions from several lens points (4 standard
// errors). It holds the projection's film scale and importance (Camera::project) to the density
// BDPT uses (bdpt.h, camera_pdf_dir); the lens offset itself only shifts the film and is held by
// LensRaysProjectBackToTheirFilmPosition.
TEST(Camera, DirectionalDensityIntegratesToOne) {
  const lt_camera_desc d = with_dof(perspective_camera(kView, 20), 0.6f, 0.25f, 0, 0, 1);
  const lt::Camera still = camera_of(d), zoom = camera_of(zooming(d));
  const float film_area = kW * kH;
  lt::Sampler sampler(8, 0, 0);
  // A zooming camera at a time of its shutter: its film covers another solid angle.
  for (auto [u, time] : {std::pair{lt::Vec2{0.5f, 0.5f}, -1.0f}, std::pair{lt::Vec2{0.95f, 0.5f}, -1.0f},
                         std::pair{lt::Vec2{0.1f, 0.85f}, -1.0f}, std::pair{lt::Vec2{0.3f, 0.6f}, 0.15f},
                         std::pair{lt::Vec2{0.7f, 0.2f}, 0.9f}}) {
    const lt::Camera& cam = time < 0 ? still : zoom;
    time = time < 0 ? 0.5f : time;
    const lt::Vec3 o = cam.lens_point(u, time);
    constexpr int kN = 400000;
    double sum = 0, sum2 = 0;
    for (int n = 0; n < kN; ++n) {
      const lt::Vec3 w = lt::sample_uniform_sphere(sampler.next_2d());
      lt::Camera::Projection pr;
      double f = 0;
      if (cam.project(o, o + w * 5.0f, 0, &pr, time)) f = pr.at[0].importance / film_area / lt::uniform_sphere_pdf();
      sum += f;
      sum2 += f * f;
    }
    const double mean = sum / kN, se = std::sqrt((sum2 / kN - mean * mean) / kN);
    EXPECT_NEAR(mean, 1.0, 4 * se + 1e-3) << "lens point " << o.x << " " << o.y << " " << o.z << " time " << time;
  }
}

// Orthographic cameras (BDPT's t = 1 as a sun seen backwards): a camera ray's points, within its
// clipping range, connect (Camera::connection_point, from the ray's lens sample) to the ray's
// origin and project back to its film position; beyond the range they do not.
TEST(Camera, OrthographicRaysProjectBackToTheirFilmPosition) {
  lt_camera_desc pin = orthographic_camera(kView, 4);
  pin.clip_start = 0.5f;
  pin.clip_end = 20;
  pin.shift_x = 0.1f;
  for (const lt_camera_desc& d : {pin, with_dof(pin, 3, 0.4f, 6, 0.3f, 1.6f)}) {
    const lt::Camera cam = camera_of(d);
    ASSERT_TRUE(cam.connectable());
    lt::Sampler sampler(6, 0, 0);
    for (int i = 0; i < 2000; ++i) {
      const float x = sampler.next_1d() * kW, y = sampler.next_1d() * kH;
      const lt::Vec2 u = sampler.next_2d();
      lt::Ray r;
      ASSERT_TRUE(cam.generate(x, y, u, &r));
      // With a lens the rays start on the near clip plane (tmin 0): from 1 cm past it, as a
      // direction from a point that close loses float's digits.
      const float lo = std::max(r.tmin * 1.001f, 0.01f);
      const float t = lo + (r.tmax * 0.999f - lo) * std::pow(sampler.next_1d(), 3.0f);
      const lt::Vec3 p = r.o + r.d * t;
      const lt::Vec3 o = cam.connection_point(p, u);
      EXPECT_LT(dist(o, r.o), 2e-5f * (1 + t));
      lt::Camera::Projection pr;
      ASSERT_TRUE(cam.project(o, p, 0, &pr)) << t;
      ASSERT_EQ(pr.count, 1);
      EXPECT_TRUE(pr.parallel);
      EXPECT_NEAR(pr.at[0].film.x, x, 2e-3f * (1 + t));
      EXPECT_NEAR(pr.at[0].film.y, y, 2e-3f * (1 + t));
      EXPECT_NEAR(pr.distance, t, 1e-4f * t);
      EXPECT_NEAR(pr.near, r.tmin, 1e-5f * r.tmin);
      for (float beyond : {r.tmin > 0 ? r.tmin * 0.98f : -0.1f, r.tmax * 1.02f}) {
        const lt::Vec3 q = r.o + r.d * beyond;
        EXPECT_FALSE(cam.project(cam.connection_point(q, u), q, 1, &pr));
      }
    }
  }
}

// Cycles' orthographic depth of field (camera_sample_orthographic) starts the rays on the near clip
// plane and aims them at the focus distance from there: one film position's rays meet at depth
// Clip Start + focus distance, not at the focus distance.
TEST(Camera, OrthographicDepthOfFieldFocusesAtClipStartPlusFocusDistance) {
  lt_camera_desc d = orthographic_camera(kView, 4);
  d.clip_start = 2;
  d.clip_end = 50;
  const lt::Camera cam = camera_of(with_dof(d, 3, 0.5f));
  ASSERT_TRUE(cam.has_lens());
  auto at_depth = [&](float x, float y, lt::Vec2 u, float depth) {
    lt::Ray r;
    EXPECT_TRUE(cam.generate(x, y, u, &r));
    EXPECT_NEAR(cam.depth(r.o + r.d * r.tmin), 2.0f, 1e-5f);  // on the near clip plane
    const float d0 = cam.depth(r.o), per_t = cam.depth(r.o + r.d) - d0;
    return r.o + r.d * ((depth - d0) / per_t);
  };
  for (const lt::Vec2 film : {lt::Vec2{3.5f, 7.25f}, lt::Vec2{40.5f, 20.0f}}) {
    const lt::Vec3 a = at_depth(film.x, film.y, {0.1f, 0.2f}, 5), b = at_depth(film.x, film.y, {0.9f, 0.7f}, 5);
    EXPECT_LT(dist(a, b), 1e-4f);
    const lt::Vec3 c = at_depth(film.x, film.y, {0.1f, 0.2f}, 3), e = at_depth(film.x, film.y, {0.9f, 0.7f}, 3);
    EXPECT_GT(dist(c, e), 0.05f);  // out of focus at the focus distance from the camera
  }
}

// An orthographic camera's importance (pixels per unit area across its parallel rays) integrated
// over a plane across the rays of one lens sample is the film's area in pixels: Monte Carlo over
// a square that holds the film's footprint (4 standard errors). It holds the importance
// (1 / (a cos) for a plane area a per pixel and rays at angle acos(cos) from the axis) and the
// film mapping to the camera's rays.
TEST(Camera, OrthographicImportanceIntegratesToTheFilm) {
  lt_camera_desc pin = orthographic_camera(kView, 3);
  pin.shift_y = -0.05f;
  for (const lt_camera_desc& d : {pin, with_dof(pin, 2, 0.3f, 5, 0.2f, 1.3f)}) {
    const lt::Camera cam = camera_of(d);
    for (lt::Vec2 u : {lt::Vec2{0.5f, 0.5f}, lt::Vec2{0.97f, 0.4f}}) {
      lt::Ray centre;
      ASSERT_TRUE(cam.generate(kW / 2.0f, kH / 2.0f, u, &centre));
      const lt::Frame f(centre.d);
      const lt::Vec3 c = centre.o + centre.d * 4.0f;
      const float half = 3;  // the film's 3 x 2.25 footprint, and more
      constexpr int kN = 200000;
      lt::Sampler sampler(9, 0, 0);
      double sum = 0, sum2 = 0;
      for (int n = 0; n < kN; ++n) {
        const lt::Vec2 ab = sampler.next_2d();
        const lt::Vec3 p = c + f.s * ((2 * ab.x - 1) * half) + f.t * ((2 * ab.y - 1) * half);
        lt::Camera::Projection pr;
        double v = 0;
        if (cam.project(cam.connection_point(p, u), p, 0, &pr)) v = pr.at[0].importance * (4 * half * half);
        sum += v;
        sum2 += v * v;
      }
      const double mean = sum / kN, se = std::sqrt((sum2 / kN - mean * mean) / kN);
      EXPECT_NEAR(mean, double(kW) * kH, 4 * se + 1e-3 * kW * kH) << "lens sample " << u.x << " " << u.y;
    }
  }
}

// Blender's F-stop 0 (its minimum) is Cycles' 1e-5: a finite, huge aperture; a negative F-stop,
// a focus distance of 0 with depth of field and a non-positive aperture ratio are refused.
TEST(Camera, BadDepthOfFieldInput) {
  const lt::Camera wide = camera_of(with_dof(perspective_camera(kView, 50), 3, 0.0f));
  EXPECT_NEAR(lt::length(wide.lens_point({1, 0.5f}) - wide.position()), 0.05f / 2e-5f, 1.0f);
  ScenePtr s = new_scene();
  auto set = [&](const lt_camera_desc& c) { return lt_scene_set_camera(s.get(), &c); };
  EXPECT_EQ(set(with_dof(perspective_camera(kView), 3, -1)), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(set(with_dof(perspective_camera(kView), 0, 2)), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(set(with_dof(perspective_camera(kView), 2, 2, 0, 0, 0)), LT_ERROR_INVALID_ARGUMENT);
  lt_camera_desc nan = with_dof(perspective_camera(kView), 2, 2);
  nan.aperture_rotation = NAN;
  EXPECT_EQ(lt_scene_set_camera(s.get(), &nan), LT_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(lt_last_error()).find("finite"), std::string::npos);
  // Orthographic: Cycles' 1 / (2 F-stop), in scene units, and every ray aimed at the focus point
  // on the view axis (camera_sample_orthographic): at the focus depth a ray is off the pinhole
  // ray's point by the film position's offset from the axis.
  const lt::Camera ortho = camera_of(with_dof(orthographic_camera(kView, 4), 3, 5));
  const lt::Camera ortho_pin = camera_of(orthographic_camera(kView, 4));
  EXPECT_NEAR(lt::length(ortho.lens_point({1, 0.5f}) - ortho.position()), 0.1f, 1e-5f);
  EXPECT_TRUE(ortho.connectable());
  lt::Ray centre, r, p;
  ASSERT_TRUE(ortho_pin.generate(kW / 2.0f, kH / 2.0f, &centre));
  ASSERT_TRUE(ortho_pin.generate(10, 40, &p));
  for (lt::Vec2 u : {lt::Vec2{0.1f, 0.7f}, lt::Vec2{0.9f, 0.2f}}) {
    ASSERT_TRUE(ortho.generate(10, 40, u, &r));
    const lt::Vec3 at_focus = r.o + r.d * (3 / lt::dot(r.d, ortho.forward()));
    EXPECT_LT(dist(at_focus, centre.o + centre.d * 3.0f + (p.o - centre.o)), 1e-4f);
    EXPECT_GT(dist(r.o, p.o), 1e-3f) << "the ray starts on the lens";
  }
}

// Equirectangular (Blender's defaults: the whole sphere): the film's centre looks along the view
// axis, its left and right edges behind, its top up; longitude grows to the right. A reduced
// range maps the film onto it.
TEST(Camera, EquirectangularDirections) {
  const Xform view = look_at({0, 0, 0}, {0, 1, 0});  // forward +Y, right +X, up +Z
  lt::Camera cam = camera_of(panorama_camera(view, LT_PANORAMA_EQUIRECTANGULAR), 200, 100);
  EXPECT_TRUE(cam.connectable());  // without a lens
  auto dir = [&](float x, float y) {
    lt::Ray r;
    EXPECT_TRUE(cam.generate(x, y, &r));
    return r.d;
  };
  EXPECT_LT(dist(dir(100, 50), {0, 1, 0}), 1e-5f);
  EXPECT_LT(dist(dir(150, 50), {1, 0, 0}), 1e-5f);  // a quarter turn right
  EXPECT_LT(dist(dir(50, 50), {-1, 0, 0}), 1e-5f);
  EXPECT_LT(dist(dir(0, 50), {0, -1, 0}), 1e-5f);
  EXPECT_LT(dist(dir(100, 100), {0, 0, 1}), 1e-5f);
  EXPECT_LT(dist(dir(100, 75), lt::normalize(lt::Vec3(0, 1, 1))), 1e-5f);
  lt_camera_desc d = panorama_camera(view, LT_PANORAMA_EQUIRECTANGULAR);
  d.longitude_min = 0;
  d.longitude_max = float(M_PI / 2);
  d.latitude_min = 0;
  cam = camera_of(d, 200, 100);
  EXPECT_LT(dist(dir(0, 0), {0, 1, 0}), 1e-5f);
  EXPECT_LT(dist(dir(200, 0), {1, 0, 0}), 1e-5f);
  EXPECT_LT(dist(dir(0, 100), {0, 0, 1}), 1e-5f);
  // Depth is the distance from the camera for panoramas (Cycles' camera_z_depth).
  EXPECT_NEAR(cam.depth({3, -4, 0}), 5, 1e-5f);
}

// Equiangular cubemap face (Cycles' equiangular_cubemap_face_to_direction): a 90-degree face whose
// film steps in equal angles; the centre looks forward, the edges 45 degrees aside, a quarter of
// the way from the centre to the right edge 22.5 degrees right. Depth: the distance.
TEST(Camera, EquiangularCubemapFaceDirections) {
  const Xform view = look_at({0, 0, 0}, {0, 1, 0});  // forward +Y, right +X, up +Z
  lt::Camera cam = camera_of(panorama_camera(view, LT_PANORAMA_EQUIANGULAR_CUBEMAP_FACE), 200, 100);
  EXPECT_TRUE(cam.connectable());
  auto dir = [&](float x, float y) {
    lt::Ray r;
    EXPECT_TRUE(cam.generate(x, y, &r));
    return r.d;
  };
  const float q = float(M_PI / 8);
  EXPECT_LT(dist(dir(100, 50), {0, 1, 0}), 1e-5f);
  EXPECT_LT(dist(dir(200, 50), lt::normalize(lt::Vec3(1, 1, 0))), 1e-5f);
  EXPECT_LT(dist(dir(0, 50), lt::normalize(lt::Vec3(-1, 1, 0))), 1e-5f);
  EXPECT_LT(dist(dir(150, 50), {std::sin(q), std::cos(q), 0}), 1e-5f);
  EXPECT_LT(dist(dir(100, 75), {0, std::cos(q), std::sin(q)}), 1e-5f);  // v on the frame's own axis
  EXPECT_LT(dist(dir(200, 100), lt::normalize(lt::Vec3(1, 1, 1))), 1e-5f);
  EXPECT_NEAR(cam.depth({3, -4, 0}), 5, 1e-5f);
}

// Fisheyes: the angle from the axis at film radius r is r fov / 2 over the frame's inscribed
// circle (equidistant) or 2 asin(r / 2 lens) with r on the sensor fitted to the frame (equisolid,
// in mm); outside the circle (equidistant) or the field of view (equisolid) the film sees nothing.
TEST(Camera, FisheyeDirections) {
  const Xform view = look_at({0, 0, 0}, {0, 1, 0});
  lt_camera_desc d = panorama_camera(view, LT_PANORAMA_FISHEYE_EQUIDISTANT);
  d.fisheye_fov = 3.0f;
  lt::Camera cam = camera_of(d, 100, 80);
  lt::Ray r;
  ASSERT_TRUE(cam.generate(50, 40, &r));
  EXPECT_LT(dist(r.d, {0, 1, 0}), 1e-5f);
  // Half way to the circle's right edge (the circle spans each axis of the frame).
  ASSERT_TRUE(cam.generate(75, 40, &r));
  EXPECT_NEAR(std::acos(r.d.y), 0.5f * 1.5f, 1e-4f);
  EXPECT_GT(r.d.x, 0);
  ASSERT_TRUE(cam.generate(50, 60, &r));
  EXPECT_NEAR(std::acos(r.d.y), 0.5f * 1.5f, 1e-4f);
  EXPECT_GT(r.d.z, 0);
  EXPECT_FALSE(cam.generate(99, 79, &r));

  d = panorama_camera(view, LT_PANORAMA_FISHEYE_EQUISOLID);
  d.fisheye_lens = 8;
  d.fisheye_fov = 2.5f;
  cam = camera_of(d, 120, 80);                 // horizontal fit: sensor 36 x 24 mm
  ASSERT_TRUE(cam.generate(60 + 30, 40, &r));  // 9 mm right of the centre
  EXPECT_NEAR(std::acos(r.d.y), 2 * std::asin(9.0f / 16), 1e-4f);
  EXPECT_GT(r.d.x, 0);
  // Beyond the field of view: r > 2 lens sin(fov / 4) = 9.5 mm.
  EXPECT_FALSE(cam.generate(60 + 32, 40, &r));
  EXPECT_TRUE(cam.generate(60 + 31, 40, &r));
}

// Rendering through the ABI inside a sphere around an equirectangular camera sees it everywhere
// at its radius (depth pass); a fisheye's film outside its circle is black and opaque, as in
// Cycles, even with a transparent film; depth of field on panoramas renders finite pixels.
TEST(Camera, PanoramaRenders) {
  ScenePtr s = new_scene();
  add_object(s.get(), uv_sphere(2, 64, 32), add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}));
  add_light(s.get(), point_light({0.5f, 0.3f, 0.2f}, 50));
  check(lt_scene_commit(s.get()), "commit");
  set_camera(s.get(), panorama_camera(look_at({0, 0, 0}, {0, 1, 0}), LT_PANORAMA_EQUIRECTANGULAR));
  lt_render_settings rs = render_settings(32, 16, 2, 1);
  Passes p = render(s.get(), rs);
  ASSERT_EQ(p.first_non_finite(), "");
  EXPECT_GT(p.rgba(16, 8)[0], 0.0f);
  for (int y = 1; y < 15; ++y)
    for (int x = 0; x < 32; ++x) EXPECT_NEAR(p.depth[size_t(y) * 32 + x], 2.0f, 0.02f) << x << " " << y;
  set_camera(s.get(), panorama_camera(look_at({0, 0, 0}, {0, 1, 0}), LT_PANORAMA_FISHEYE_EQUIDISTANT));
  rs = render_settings(32, 32, 2, 1);
  rs.transparent_background = 1;
  p = render(s.get(), rs);
  ASSERT_EQ(p.first_non_finite(), "");
  EXPECT_EQ(p.rgba(0, 0)[0], 0.0f);
  EXPECT_EQ(p.rgba(0, 0)[3], 1.0f);
  EXPECT_GT(p.rgba(16, 16)[0], 0.0f);
  set_camera(s.get(),
             with_dof(panorama_camera(look_at({0, 0, 0}, {0, 1, 0}), LT_PANORAMA_FISHEYE_EQUISOLID), 1.5f, 0.1f, 5));
  for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
    rs.integrator = integrator;
    p = render(s.get(), rs);
    EXPECT_EQ(p.first_non_finite(), "");
    EXPECT_EQ(p.status.nan_samples, 0u);
  }
}

namespace {

// Panoramas of every type, including what makes a direction seen from several film positions: a
// fisheye of more than a turn, a lens polynomial that turns back and changes sign, and the
// equirectangular seam and poles (with the filter's margin).
struct PanoramaCase {
  const char* name;
  lt_camera_desc desc;
};

std::vector<PanoramaCase> panorama_cases() {
  const Xform view = look_at({0.3f, -1, 0.5f}, {0, 1, 0.7f});
  std::vector<PanoramaCase> cases;
  auto add = [&](const char* name, int type, auto tweak) {
    lt_camera_desc d = panorama_camera(view, type);
    d.clip_start = 0.01f;
    tweak(d);
    cases.push_back({name, d});
  };
  add("equirectangular", LT_PANORAMA_EQUIRECTANGULAR, [](lt_camera_desc&) {});
  add("equirectangular ranges", LT_PANORAMA_EQUIRECTANGULAR, [](lt_camera_desc& d) {
    d.latitude_min = -1.0f, d.latitude_max = 1.3f, d.longitude_min = -2.6f, d.longitude_max = 2.1f;
    d.shift_x = 0.04f, d.shift_y = -0.03f;
  });
  add("equidistant 200", LT_PANORAMA_FISHEYE_EQUIDISTANT, [](lt_camera_desc& d) { d.fisheye_fov = 3.49f; });
  add("equidistant 400", LT_PANORAMA_FISHEYE_EQUIDISTANT, [](lt_camera_desc& d) { d.fisheye_fov = 7.0f; });
  add("equisolid", LT_PANORAMA_FISHEYE_EQUISOLID,
      [](lt_camera_desc& d) { d.fisheye_lens = 9, d.fisheye_fov = 2.97f, d.shift_x = 0.05f; });
  add("mirror ball", LT_PANORAMA_MIRRORBALL, [](lt_camera_desc& d) { d.shift_y = 0.06f; });
  add("cubemap face", LT_PANORAMA_EQUIANGULAR_CUBEMAP_FACE, [](lt_camera_desc& d) { d.shift_x = 0.04f; });
  // A viewport's region beyond the face: past u = 1.5 and v = -0.5 the film sees it again.
  add("cubemap face beyond", LT_PANORAMA_EQUIANGULAR_CUBEMAP_FACE, [](lt_camera_desc& d) {
    const float vp[4] = {-0.3f, 1.9f, -0.7f, 1.1f};
    std::copy(vp, vp + 4, d.panorama_viewplane);
  });
  add("polynomial", LT_PANORAMA_FISHEYE_LENS_POLYNOMIAL, [](lt_camera_desc& d) { d.fisheye_fov = 2.6f; });
  add("polynomial turning", LT_PANORAMA_FISHEYE_LENS_POLYNOMIAL, [](lt_camera_desc& d) {
    // theta = -0.05 + 0.08 r - 2e-4 r^3: rises to 0.56 at r = 11.5 mm, then falls below 0.
    const float k[5] = {0.05f, -0.08f, 0, 2e-4f, 0};
    std::copy(k, k + 5, d.fisheye_polynomial);
    d.fisheye_fov = 6.2f;
  });
  return cases;
}

}  // namespace

// A panoramic camera ray's points project back (Camera::project, BDPT's t = 1) with the ray's
// direction and distance, and one of the film positions found is the ray's own.
TEST(Camera, PanoramaRaysProjectBackToTheirFilmPosition) {
  for (const PanoramaCase& c : panorama_cases()) {
    const lt::Camera cam = camera_of(c.desc);
    ASSERT_TRUE(cam.connectable()) << c.name;
    lt::Sampler sampler(11, 0, 0);
    int checked = 0, several = 0;
    for (int i = 0; i < 3000; ++i) {
      const float x = sampler.next_1d() * kW, y = sampler.next_1d() * kH;
      lt::Ray r;
      if (!cam.generate(x, y, &r)) continue;
      const float t = 0.05f + 3 * sampler.next_1d();
      lt::Camera::Projection pr;
      ASSERT_TRUE(cam.project(r.o, r.o + r.d * t, 0, &pr)) << c.name << " at " << x << " " << y;
      EXPECT_NEAR(pr.distance, t, 1e-4f * t);
      EXPECT_NEAR(pr.near, r.tmin, 1e-5f * r.tmin);
      EXPECT_GT(lt::dot(pr.dir, r.d), 1 - 1e-5f);
      float nearest = INFINITY;
      for (int k = 0; k < pr.count; ++k)
        nearest = std::min(nearest, std::hypot(pr.at[k].film.x - x, pr.at[k].film.y - y));
      EXPECT_LT(nearest, 0.02f) << c.name << " at " << x << " " << y;
      several += pr.count > 1;
      ++checked;
    }
    EXPECT_GT(checked, 1000) << c.name;
    if (std::string(c.name) == "equidistant 400" || std::string(c.name) == "polynomial turning" ||
        std::string(c.name) == "cubemap face beyond")
      EXPECT_GT(several, 100) << c.name << ": directions seen twice";
  }
}

// The film's importance summed over a direction's film positions (pixels per steradian),
// integrated over the sphere of directions, is the film area (pixels) that sees something:
// Monte Carlo over directions against Monte Carlo over the film (4 standard errors). It holds
// each projection's inverse and Jacobian to its direction map (Camera::generate).
TEST(Camera, PanoramaImportanceIntegratesToTheFilmSeen) {
  for (const PanoramaCase& c : panorama_cases()) {
    const lt::Camera cam = camera_of(c.desc);
    lt::Sampler sampler(12, 0, 0);
    constexpr int kN = 200000;
    double sum = 0, sum2 = 0, seen = 0;
    for (int n = 0; n < kN; ++n) {
      const lt::Vec3 w = lt::sample_uniform_sphere(sampler.next_2d());
      lt::Camera::Projection pr;
      double f = 0;
      if (cam.project(cam.position(), cam.position() + w, 0, &pr))
        for (int k = 0; k < pr.count; ++k) f += pr.at[k].importance / lt::uniform_sphere_pdf();
      sum += f;
      sum2 += f * f;
      lt::Ray r;
      seen += cam.generate(sampler.next_1d() * kW, sampler.next_1d() * kH, &r) ? 1 : 0;
    }
    const double mean = sum / kN, se = std::sqrt(std::max(0.0, sum2 / kN - mean * mean) / kN);
    const double p = seen / kN, area = p * kW * kH, se_area = std::sqrt(p * (1 - p) / kN) * kW * kH;
    EXPECT_NEAR(mean, area, 4 * std::hypot(se, se_area) + 1e-3 * area) << c.name;
  }
}

// Bad input: a polynomial that turns back, or one whose angle leaves the field of view, and the
// film outside a mirror ball's circle render defined values (no NaN): the film that sees nothing
// is black and opaque.
TEST(Camera, PanoramaBadInput) {
  const Xform view = look_at({0, 0, 0}, {0, 1, 0});
  lt_camera_desc d = panorama_camera(view, LT_PANORAMA_MIRRORBALL);
  lt::Camera cam = camera_of(d, 64, 48);
  lt::Ray r;
  EXPECT_FALSE(cam.generate(1, 1, &r));  // outside the circle
  ASSERT_TRUE(cam.generate(32, 24, &r));
  EXPECT_LT(dist(r.d, {0, 1, 0}), 1e-5f);    // the centre looks forward
  ASSERT_TRUE(cam.generate(63.5f, 24, &r));  // the circle spans the frame (an ellipse on a wide film)
  EXPECT_LT(r.d.y, -0.9f);                   // the rim behind
  EXPECT_GT(r.d.x, 0);
  d = panorama_camera(view, LT_PANORAMA_FISHEYE_LENS_POLYNOMIAL);
  const float huge[5] = {1e30f, -1e30f, 1e30f, -1e30f, 1e30f};
  std::copy(huge, huge + 5, d.fisheye_polynomial);
  ScenePtr s = new_scene();
  add_object(s.get(), uv_sphere(2, 32, 16), add_diffuse(s.get(), {0.8f, 0.8f, 0.8f}));
  add_light(s.get(), point_light({0.5f, 0.3f, 0.2f}, 50));
  check(lt_scene_commit(s.get()), "commit");
  for (const lt_camera_desc& c : {d, panorama_cases().back().desc}) {
    set_camera(s.get(), c);
    for (int integrator : {LT_INTEGRATOR_PATH, LT_INTEGRATOR_BIDIRECTIONAL}) {
      lt_render_settings rs = render_settings(16, 12, 2, 1);
      rs.integrator = integrator;
      Passes p = render(s.get(), rs);
      EXPECT_EQ(p.first_non_finite(), "");
      EXPECT_EQ(p.status.nan_samples, 0u);
    }
  }
}

float filter_profile(lt::FilterType type, float width, float x) {
  switch (type) {
    case lt::FilterType::Box:
      return 1;
    case lt::FilterType::Gaussian:
      return std::exp(-2 * (2 * x / width) * (2 * x / width));
    case lt::FilterType::BlackmanHarris:
      break;
  }
  const float a = 2 * lt::kPi * (x / (2 * width) + 0.5f);
  return 0.35875f - 0.48829f * std::cos(a) + 0.14128f * std::cos(2 * a) - 0.01168f * std::cos(3 * a);
}

// Evenly spaced u (a deterministic stand-in for uniform numbers) binned over the filter's range
// give, bin by bin, the integral of pdf() to within rounding: the offsets are sampled with the
// density BDPT divides by. And that density is the filter's profile, normalised.
TEST(PixelFilter, SamplesHaveTheDensityPdfClaimsAndTheFiltersProfile) {
  for (lt::FilterType type : {lt::FilterType::Box, lt::FilterType::Gaussian, lt::FilterType::BlackmanHarris}) {
    for (float width : {0.01f, 1.5f, 4.0f}) {
      SCOPED_TRACE(testing::Message() << "type " << int(type) << " width " << width);
      const lt::FilterSampler f(type, width);
      const float r = f.radius();
      constexpr int kBins = 48, kN = 1 << 20, kQuad = 2000;
      std::vector<double> observed(kBins, 0.0), expected(kBins, 0.0);
      for (int k = 0; k < kN; ++k) {
        const float x = f.sample((k + 0.5f) / kN);
        ASSERT_TRUE(std::abs(x) <= r) << x;
        observed[std::min(kBins - 1, int((x + r) / (2 * r) * kBins))] += 1;
      }
      double integral = 0, worst = 0;
      for (int b = 0; b < kBins; ++b) {
        for (int q = 0; q < kQuad; ++q) expected[b] += f.pdf(-r + 2 * r * (b + (q + 0.5) / kQuad) / kBins);
        expected[b] *= 2.0 * r / kBins / kQuad * kN;
        integral += expected[b] / kN;
        worst = std::max(worst, std::abs(observed[b] - expected[b]) / (expected[b] + 100));
      }
      EXPECT_NEAR(integral, 1.0, 1e-3);
      EXPECT_LT(worst, 0.01);
      // The profile: within 1 % of the peak's value wherever it is above a tenth of it.
      const float peak = f.pdf(0), p0 = filter_profile(type, width, 0);
      for (int k = -99; k <= 99; ++k) {
        const float x = r * k / 100.0f, want = filter_profile(type, width, x) / p0;
        if (want > 0.1f) EXPECT_NEAR(f.pdf(x) / peak, want, 0.01f) << "at " << x;
      }
      EXPECT_EQ(f.pdf(r), 0.0f);
      EXPECT_EQ(f.pdf(-1.01f * r), 0.0f);
    }
  }
}
