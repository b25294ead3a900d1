// Subsurface scattering (integrators/subsurface.h, bsdf.h's bssrdf_radius): the closed forms
// against Cycles 3.4's numbers, and the random walk's energy in a closed mesh.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "geometry/geometry.h"
#include "geometry_builders.h"
#include "integrators/subsurface.h"
#include "media/phase.h"
#include "shading/bsdf.h"

using namespace lt;

namespace {

// Cycles 3.4's bssrdf_dipole_compute_alpha_prime at IOR 1.4 and the Random Walk radius factor
// sqrt(3 (1 - alpha')), as its float code computes them (12 bisections).
TEST(Subsurface, AlbedoInversionMatchesCycles) {
  const struct {
    float albedo, alpha_prime, factor;
  } cases[] = {{0.05f, 0.386962890625f, 1.3561383f},
               {0.2f, 0.813232421875f, 0.7485337f},
               {0.5f, 0.977783203125f, 0.2581674f},
               {0.8f, 0.998291015625f, 0.0716027f},
               {0.95f, 0.999755859375f, 0.0270633f}};
  for (const auto& c : cases) {
    EXPECT_NEAR(bssrdf_alpha_prime(c.albedo, 1.4f), c.alpha_prime, 1e-6f) << c.albedo;
    const Spectrum r = bssrdf_radius(Spectrum(2.0f), Spectrum(c.albedo), SubsurfaceMethod::RandomWalk, 1.4f);
    EXPECT_NEAR(r.x, 2 * c.factor, 2e-5f) << c.albedo;
  }
  // Burley and the fixed radius: 1/(4 pi) whatever the albedo.
  const Spectrum b = bssrdf_radius(Spectrum(1.0f), Spectrum(0.3f), SubsurfaceMethod::Burley, 1.4f);
  EXPECT_NEAR(b.y, 0.25f / kPi, 1e-7f);
  EXPECT_EQ(bssrdf_alpha_prime(0.0f, 1.4f), 0.0f);
  EXPECT_EQ(bssrdf_alpha_prime(0.999f, 1.4f), 0.999999f);
}

// The anisotropic fit at g = 0 is Chiang et al. 2016's isotropic inversion, within the fit's
// accuracy; sigma_t = 1 / (d (1 - g)).
TEST(Subsurface, RemapMatchesChiangAtZeroAnisotropy) {
  for (float A : {0.1f, 0.3f, 0.5f, 0.8f, 0.95f}) {
    const float s = 4.09712f + 4.20863f * A - std::sqrt(9.59217f + 41.6808f * A + 17.7126f * A * A);
    float sigma_t, alpha;
    random_walk_remap(A, 0.5f, 0.0f, &sigma_t, &alpha);
    EXPECT_NEAR(alpha, 1 - s * s, 0.01f) << A;
    EXPECT_FLOAT_EQ(sigma_t, 2.0f);
    random_walk_remap(A, 0.5f, 0.5f, &sigma_t, &alpha);
    EXPECT_FLOAT_EQ(sigma_t, 4.0f);
  }
}

// A closed sphere of radius R (outward winding), as one instance.
struct SphereScene {
  Geometry g;
  float R;
  explicit SphereScene(float radius) : R(radius) {
    Mesh m;
    const int seg = 96, rings = 48;
    for (int i = 0; i <= rings; ++i) {
      const float th = kPi * float(i) / rings;
      for (int j = 0; j < seg; ++j) {
        const float ph = 2 * kPi * float(j) / seg;
        m.positions.push_back(Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)) * R);
      }
    }
    for (int i = 0; i < rings; ++i)
      for (int j = 0; j < seg; ++j) {
        const uint32_t a = i * seg + j, b = i * seg + (j + 1) % seg, c = a + seg, d = b + seg;
        if (i > 0) m.indices.insert(m.indices.end(), {a, c, b});
        if (i < rings - 1) m.indices.insert(m.indices.end(), {b, c, d});
      }
    lt_test::add_lone_instance(g, std::move(m));
  }
  // The top of the sphere as a ray straight down meets it.
  SurfacePoint top() const {
    Ray r;
    r.o = Vec3(0.01f, 0.02f, 2 * R);
    r.d = Vec3(0, 0, -1);
    Hit hit;
    EXPECT_TRUE(g.intersect(r, 31u, &hit));
    return g.surface(hit);
  }
};

struct WalkStats {
  double mean = 0, se = 0;
  int exits = 0;
};

// The mean exit weight of n walks from the sphere's top under a white-weighted lobe (beta = the
// lobe's weight = its albedo, as a path tracer hands it over); every exit on the sphere, leaving it.
WalkStats walk(const SphereScene& s, float R, const Lobe& l, int n) {
  const SurfacePoint sp = s.top();
  const Vec3 n_up = dot(sp.ng, Vec3(0, 0, 1)) > 0 ? sp.ng : -sp.ng;
  double sum = 0, sum2 = 0;
  WalkStats out;
  for (int i = 0; i < n; ++i) {
    Sampler sampler(7, 0, uint32_t(i));
    Spectrum beta = l.weight;
    SubsurfaceExit exit;
    double w = 0;
    if (subsurface_scatter(s.g, sp, n_up, n_up, false, l, 0.5f, sampler, &beta, &exit)) {
      ++out.exits;
      w = beta.x;
      EXPECT_NEAR(length(exit.sp.p), R, 2e-3f * R);
      const Vec3 out_n = dot(exit.sp.ng, exit.sp.p) > 0 ? exit.sp.ng : -exit.sp.ng;
      EXPECT_GT(dot(exit.wo, out_n), 0.0f);  // shaded from outside
    }
    sum += w;
    sum2 += w * w;
  }
  out.mean = sum / n;
  out.se = std::sqrt(std::max(0.0, sum2 / n - out.mean * out.mean) / n);
  return out;
}

// A lobe of radius d after bssrdf_radius (the walk's 1 / sigma_t (1 - g)).
Lobe walk_lobe(float albedo, float d, float g) {
  Lobe l;
  l.type = LobeType::Subsurface;
  l.weight = Spectrum(albedo);
  l.sss_albedo = Spectrum(albedo);
  l.sss_anisotropy = g;
  l.sss_radius = Spectrum(d);
  return l;
}

// Geometry::local_hits, as the Burley disk probes a sphere (subsurface.cpp, disk): from points on
// a tessellated sphere, along its normal or a tangent, offset sideways. A line meets a convex
// closed mesh at most twice, so no probe may visit more than 2 hits, each farther than the last.
// Embree may report a crossing again at or below tmin (it rounds the distance after its range
// test): visited again, one probe in about 1500 met the same crossing 256 times on the machine
// where subsurface_burley disagreed with Cycles by 1.3 % (2026-12-07).
TEST(Subsurface, DiskProbesMeetAConvexMeshAtMostTwice) {
  SphereScene s(0.5f);
  Pcg32 rng(7, 3);
  auto u01 = [&] { return u32_to_unit(rng.next_u32()); };
  int most = 0, probes = 0;
  for (int i = 0; i < 200000; ++i) {
    const Vec3 dir = sample_uniform_sphere(Vec2{u01(), u01()});
    Ray in;
    in.o = dir * 2.0f;
    in.d = -dir;
    in.tmax = 4;
    Hit h;
    if (!s.g.intersect_instance(in, 0, &h)) continue;
    const SurfacePoint sp = s.g.surface(h);
    const Frame f(sp.ng);
    const int k = int(u01() * 3);
    const Vec3 axis = k == 0 ? f.n : k == 1 ? f.s : f.t, a1 = k == 0 ? f.s : f.n, a2 = k == 2 ? f.s : f.t;
    const float r = 0.6f * u01(), phi = 2 * kPi * u01(), height = std::sqrt(1.0f - r * r);
    Ray probe;
    probe.o = sp.p + axis * height + a1 * (r * std::cos(phi)) + a2 * (r * std::sin(phi));
    probe.d = -axis;
    probe.tmax = 2 * height;
    int count = 0;
    float last = -1;
    s.g.local_hits(probe, 0, [&](const Hit& hit) {
      EXPECT_GT(hit.t, last);
      last = hit.t;
      ++count;
      return true;
    });
    most = std::max(most, count);
    ++probes;
  }
  EXPECT_GT(probes, 190000);
  EXPECT_LE(most, 2);
}

// Furnace: with albedo 1 the walk absorbs nothing (alpha 0.999999) and every walk leaves the
// closed sphere: the mean weight is 1, with and without anisotropy (Dwivedi guiding and the
// similarity relation past 9 bounces are unbiased). A mean free path of 0.3 in a unit sphere:
// few walks reach Cycles' 256 bounces.
TEST(Subsurface, WalkInAClosedMeshConservesEnergy) {
  const float R = 1;
  SphereScene s(R);
  for (float g : {0.0f, 0.6f}) {
    const WalkStats w = walk(s, R, walk_lobe(1.0f, 0.3f, g), 4000);
    // alpha is 0.999999, not 1: at most 256 bounces lose 2.6e-4.
    EXPECT_NEAR(w.mean, 1.0, 5 * w.se + 2.6e-4) << "g " << g << " se " << w.se;
    EXPECT_GT(w.exits, 3990) << g;
    RecordProperty("furnace_g" + std::to_string(int(g * 10)), std::to_string(w.mean) + " se " + std::to_string(w.se));
  }
}

// A thick slab, 1000 x 1000 x 200 mean free paths, as a box: a half-space for the walk.
struct SlabScene {
  Geometry g;
  SlabScene() { lt_test::add_lone_instance(g, lt_test::box_mesh(Vec3(-500, -500, -200), Vec3(500, 500, 0))); }
};

// The same medium walked the plain way (analog: free flights from sigma_t, HG directions, the
// weight times alpha per collision, Cycles' similarity switch after 9 bounces and its 256-bounce
// cap) in the half-space z < 0, from a cosine-distributed entry: the total reflectance the
// guided, channel-sampled walk must reproduce.
double analog_half_space(float albedo, float d, float g, int n, double* se) {
  float sigma_t, alpha;
  random_walk_remap(albedo, d, g, &sigma_t, &alpha);
  const float sigma_s = sigma_t * alpha;
  const float sigma_s_star = sigma_s * (1 - g), sigma_t_star = sigma_t - sigma_s + sigma_s_star;
  double sum = 0, sum2 = 0;
  Pcg32 rng(99, 1);
  auto u01 = [&] { return u32_to_unit(rng.next_u32()); };
  for (int i = 0; i < n; ++i) {
    Vec3 d_in = sample_cosine_hemisphere(Vec2{u01(), u01()});
    Vec3 dir(d_in.x, d_in.y, -d_in.z);
    double z = 0, w = 1, exit = 0;
    for (int b = 0; b < 256; ++b) {
      const bool similar = b > 9;
      const float st = similar ? sigma_t_star : sigma_t, gb = similar ? 0.0f : g;
      if (b > 0) {
        Vec3 nd;
        float pdf;
        PhaseHG{gb}.sample(-dir, Vec2{u01(), u01()}, &nd, &pdf);
        dir = nd;
      }
      const double t = -std::log(1 - double(u01())) / st;
      z += t * dir.z;
      if (z >= 0) {
        exit = w;
        break;
      }
      w *= (similar ? sigma_s_star / sigma_t_star : alpha);
    }
    sum += exit;
    sum2 += exit * exit;
  }
  const double mean = sum / n;
  *se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
  return mean;
}

// The walk's total reflectance in a half-space (Dwivedi guiding towards the entry plane, channel
// MIS, the similarity relation): the analog walk's, within both estimates' noise.
TEST(Subsurface, WalkInAHalfSpaceReflectsAsTheAnalogWalk) {
  SlabScene s;
  Ray r;
  r.o = Vec3(0.01f, 0.02f, 10);
  r.d = Vec3(0, 0, -1);
  Hit hit;
  ASSERT_TRUE(s.g.intersect(r, 31u, &hit));
  const SurfacePoint sp = s.g.surface(hit);
  for (float A : {0.3f, 0.8f})
    for (float g : {0.0f, 0.6f}) {
      const Lobe l = walk_lobe(A, 1.0f, g);
      double sum = 0, sum2 = 0;
      const int n = 4000;
      for (int i = 0; i < n; ++i) {
        Sampler sampler(11, 0, uint32_t(i));
        Spectrum beta = l.weight;
        SubsurfaceExit exit;
        double w = 0;
        if (subsurface_scatter(s.g, sp, Vec3(0, 0, 1), Vec3(0, 0, 1), false, l, 0.5f, sampler, &beta, &exit)) {
          w = beta.x;
          EXPECT_NEAR(exit.sp.p.z, 0.0f, 1e-3f);
          EXPECT_GT(exit.wo.z, 0.0f);
        }
        sum += w;
        sum2 += w * w;
      }
      const double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
      double ref_se;
      const double ref = analog_half_space(A, 1.0f, g, 40000, &ref_se);
      EXPECT_NEAR(mean, ref, 5 * std::sqrt(se * se + ref_se * ref_se))
          << "albedo " << A << " g " << g << " se " << se << " ref se " << ref_se;
      RecordProperty("half_space_A" + std::to_string(int(A * 10)) + "_g" + std::to_string(int(g * 10)),
                     std::to_string(mean) + " se " + std::to_string(se) + " analog " + std::to_string(ref) + " se " +
                         std::to_string(ref_se));
    }
}

}  // namespace
