// Cycles 3.4.1's single-scattering GGX reflection closures, written out again in double precision
// from its kernel (intern/cycles/kernel/closure/bsdf_microfacet.h: bsdf_microfacet_ggx_eval_reflect;
// bsdf_util.h: fresnel_dielectric_cos, interpolate_fresnel_color; svm/closure.h: the Principled
// BSDF's specular layer), independently of Lantern's bsdf.cpp, so tests can hold Lantern's lobes
// to them: pointwise, and through the directional albedo by quadrature.
//
// Directions are local (+Z the normal), o the outgoing (towards the viewer) and i the incoming
// direction, both above the surface. cspec0 <= 1 (Cycles saturates it); ior from Specular.
#pragma once

#include <cmath>

#include "scene_builders.h"

namespace cycles_ref {

using lt_test::kPi;

struct D3 {
  double x, y, z;
};
inline double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline D3 normalize(D3 a) {
  double l = std::sqrt(dot(a, a));
  return {a.x / l, a.y / l, a.z / l};
}

// fresnel_dielectric_cos
inline double fresnel_dielectric_cos(double cosi, double eta) {
  double c = std::abs(cosi), g = eta * eta - 1 + c * c;
  if (g <= 0) return 1;
  g = std::sqrt(g);
  double a = (g - c) / (g + c), b = (c * (g + c) - 1) / (c * (g - c) + 1);
  return 0.5 * a * a * (1 + b * b);
}

// The Principled BSDF's specular IOR: bsdf->ior = 2 / (1 - sqrt(0.08 specular)) - 1.
inline double principled_ior(double specular) { return 2 / (1 - std::sqrt(0.08 * specular)) - 1; }

// interpolate_fresnel_color(L, H, ior, F0 = fresnel_dielectric_cos(1, ior), cspec0), one channel.
inline double principled_fresnel(double cos_lh, double ior, double cspec0) {
  double f0 = fresnel_dielectric_cos(1, ior);
  double fh = (fresnel_dielectric_cos(cos_lh, ior) - f0) / (1 - f0);
  return cspec0 * (1 - fh) + fh;
}

inline double ggx_G1(double cos_n, double alpha2) {
  return 2 / (1 + std::sqrt(1 + alpha2 * (1 - cos_n * cos_n) / (cos_n * cos_n)));
}
inline double ggx_D(double cos_m, double alpha2) {
  double c2 = cos_m * cos_m, t2 = (1 - c2) / c2;
  return alpha2 / (kPi * c2 * c2 * (alpha2 + t2) * (alpha2 + t2));
}

// A closure: Glossy BSDF (fresnel = false: F = 1) or the Principled specular layer.
struct Closure {
  double alpha;          // roughness^2
  bool fresnel = false;  // Principled v1 Fresnel
  double ior = 1.5, cspec0 = 1;
  double weight = 1;  // the closure's weight (Glossy BSDF: its colour)
  double F(double cos_lh) const { return weight * (fresnel ? principled_fresnel(cos_lh, ior, cspec0) : 1.0); }
};

// The BSDF value f(o, i), without the cosine: weight F G1(o) G1(i) D / (4 cos_o cos_i).
inline double eval(const Closure& c, D3 o, D3 i) {
  if (!(o.z > 0 && i.z > 0)) return 0;
  D3 m = normalize({o.x + i.x, o.y + i.y, o.z + i.z});
  double a2 = c.alpha * c.alpha;
  return c.F(dot(i, m)) * ggx_G1(o.z, a2) * ggx_G1(i.z, a2) * ggx_D(m.z, a2) / (4 * o.z * i.z);
}

// Directional albedo E(o) = integral of f(o, i) cos_i over i, by the midpoint rule over microfacet
// normals: with i = reflect(o, m), d_i = 4 (o.m) d_m, and m parameterised so that D(m) cos_m d_m =
// du dphi / (2 pi) with tan^2 = alpha^2 u / (1 - u) and u = 1 - v^2 (smooth in v near grazing m):
// E = integral over v, phi of F G1(o) G1(i) (o.m) / (cos_o cos_m) 2 v dv dphi / (2 pi).
// F = cspec0 (1 - FH) + FH is linear in cspec0: returns the albedos for cspec0 = 0 and 1, so that
// E(cspec0) = E0 + cspec0 (E1 - E0) (E0 = E1 without Fresnel).
// The midpoint rule above: calls visit(i, om, w) for every reflected direction i of the n x n
// grid (half the azimuths: every integrand here is even in phi), w its weight without Fresnel
// (om = o.m, Fresnel's argument), the weights summing to the albedo at F = 1.
template <class Visit>
void for_each_reflection(const D3& o, double alpha, int n, Visit visit) {
  const double a2 = alpha * alpha;
  for (int a = 0; a < n; ++a) {
    const double v = (a + 0.5) / n, u = 1 - v * v;
    const double t2 = a2 * u / (v * v), cos_m = 1 / std::sqrt(1 + t2), sin_m = std::sqrt(t2) * cos_m;
    for (int b = 0; b < n; ++b) {
      const double phi = kPi * (b + 0.5) / n;
      const D3 m{sin_m * std::cos(phi), sin_m * std::sin(phi), cos_m};
      const double om = dot(o, m);
      if (om <= 0) continue;
      const D3 i{2 * om * m.x - o.x, 2 * om * m.y - o.y, 2 * om * m.z - o.z};
      if (i.z <= 0) continue;
      visit(i, om, ggx_G1(o.z, a2) * ggx_G1(i.z, a2) * om / (o.z * cos_m) * 2 * v / (double(n) * n));
    }
  }
}

struct Albedo {
  double e0, e1;
  double operator()(double cspec0) const { return e0 + cspec0 * (e1 - e0); }
};
inline Albedo albedo(const Closure& c, double theta_o, int n = 600) {
  Closure black = c, white = c;
  black.cspec0 = 0;
  white.cspec0 = 1;
  double s0 = 0, s1 = 0;
  for_each_reflection({std::sin(theta_o), 0, std::cos(theta_o)}, c.alpha, n, [&](const D3&, double om, double w) {
    s0 += black.F(om) * w;
    s1 += white.F(om) * w;
  });
  return {s0, s1};
}

}  // namespace cycles_ref
