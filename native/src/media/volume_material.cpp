#include "media/volume_material.h"

#include <cmath>

namespace lt {

namespace {

// Cycles 3.4.1's blackbody colour as its Principled Volume uses it (unclamped: below ~1900 K green
// and blue are negative), fitted to its output (Cycles evaluates a piecewise fit of the same forms:
// a/T + bT + c for red and green, a cubic in T for blue). Measured in Blender 3.4.1: where positive
// from the Blackbody node rendered at 9 temperatures per interval (the fit reproduces the renders
// to 3e-7); the negative parts (green from 800 to 965 K, blue from 800 to 1902 K, and the constant
// below 800 K) from a Principled Volume of density 0 and Blackbody Intensity 1 seen through 2 m
// (pixel = 2 sigma_SB 1e-6 / pi T^4 colour), 9 temperatures per interval, fitted to 2e-7.
// Rows: lower bound of the interval, red, green, blue coefficients.
struct BlackbodySegment {
  float t0;
  double r[3], g[3], b[4];
};
constexpr BlackbodySegment kBlackbody[] = {
    {800.0f,
     {1619.19903, -0.00205009798, 5.02993936},
     {-488.995226, 0.000604336763, -0.0755912304},
     {5.97040390e-11, -4.86014480e-08, -9.70365381e-05, -0.00408739648}},
    {965.0f,
     {2488.47045, -0.00111329559, 3.22618662},
     {-755.997694, 0.000316727221, 0.47831133},
     {2.40298135e-11, 5.55455283e-08, -0.000198551245, 0.0289486395}},
    {1167.0f,
     {3341.49112, -0.00048651745, 1.76477832},
     {-1023.63943, 0.000120223939, 0.936660412},
     {-1.40867985e-11, 1.89847396e-07, -0.000356592289, 0.0910594796}},
    {1449.0f,
     {4094.63896, -0.00012743972, 0.725707083},
     {-1265.7146, 4.8729131e-06, 1.27054576},
     {-3.61425278e-11, 2.84804506e-07, -0.000493182737, 0.15670798}},
    {1902.0f,
     {4670.27874, 2.91252119e-05, 0.126705153},
     {-1425.29448, -4.01152186e-05, 1.43972776},
     {-1.970765e-11, 1.75359979e-07, -0.000250544636, -0.0222764052}},
    {3315.0f,
     {4595.09867, 2.87496623e-05, 0.150341915},
     {-1175.54958, -2.16379066e-05, 1.30408003},
     {-1.62037271e-13, -1.64210578e-08, 0.000386213688, -0.738073268}},
    {6365.0f,
     {3787.17459, 9.35900865e-06, 0.399074875},
     {-500.791766, -4.59824786e-06, 1.09098495},
     {6.72648203e-13, -2.73078239e-08, 0.000424097712, -0.752334381}},
};

}  // namespace

Spectrum blackbody_rec709_unclamped(float kelvin) {
  if (!(kelvin >= 800.0f)) return Spectrum(5.41329241f, -0.203193843f, -0.0822535306f);  // below 800 K (and NaN)
  if (kelvin >= 12000.0f) return Spectrum(0.826293707f, 0.994506836f, 1.56630695f);
  int i = int(sizeof(kBlackbody) / sizeof(kBlackbody[0])) - 1;
  while (i > 0 && kelvin < kBlackbody[i].t0) --i;
  const BlackbodySegment& s = kBlackbody[i];
  const double t = kelvin;
  double r = s.r[0] / t + s.r[1] * t + s.r[2];
  double g = s.g[0] / t + s.g[1] * t + s.g[2];
  double b = ((s.b[0] * t + s.b[1]) * t + s.b[2]) * t + s.b[3];
  return Spectrum(float(r), float(g), float(b));
}

Spectrum blackbody_rec709(float kelvin) { return vmax(Spectrum(0.0f), blackbody_rec709_unclamped(kelvin)); }

Spectrum principled_volume_emission(float strength, const Spectrum& color, float blackbody_intensity,
                                    const Spectrum& blackbody_tint, float temperature) {
  Spectrum e(0.0f);
  if (strength > 0) e += vmax(Spectrum(0.0f), color) * strength;
  if (blackbody_intensity > 0) {
    double T = std::max(0.0f, temperature);
    double T4 = (T * T) * (T * T);
    double intensity =
        5.670373e-8 * 1e-6 / double(kPi) * ((1 - double(blackbody_intensity)) + blackbody_intensity * T4);
    e += vmax(Spectrum(0.0f), blackbody_tint) * blackbody_rec709_unclamped(float(T)) * float(intensity);
  }
  return e;
}

VolumeMix sum_volume_components(const VolumeCoefficients* c, int n) {
  VolumeMix m;
  float g[64], w[64];
  int lobes = 0;
  for (int i = 0; i < n; ++i) {
    m.sigma_a += c[i].sigma_a;
    m.sigma_s += c[i].sigma_s;
    m.emission += c[i].emission;
    float wi = (c[i].sigma_s.x + c[i].sigma_s.y + c[i].sigma_s.z) / 3;
    if (wi > 0 && lobes < 64) {
      g[lobes] = c[i].g;
      w[lobes++] = wi;
    }
  }
  m.phase = lobes > 0 ? Phase::mixture(g, w, lobes) : Phase::hg(n > 0 ? c[0].g : 0.0f);
  return m;
}

}  // namespace lt
