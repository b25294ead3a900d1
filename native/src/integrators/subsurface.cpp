// Subsurface scattering (subsurface.h). Formulas from Cycles 3.4's kernel/integrator/
// subsurface_random_walk.h (Chiang, Kutz and Burley 2016, "Practical and Controllable Subsurface
// Scattering for Production Path Tracing"; Wrenninge, Villemin and Hery's anisotropic remap;
// Dwivedi guiding after Krivanek and d'Eon 2014, Meng et al. 2016, d'Eon and Krivanek 2020),
// subsurface_disk.h (King et al. 2013, "BSSRDF Importance Sampling") and closure/bssrdf.h
// (Christensen and Burley 2015's profile).
#include "integrators/subsurface.h"

#include <utility>

#include "media/phase.h"

namespace lt {

namespace {

constexpr int kMaxBounces = 256;             // Cycles' BSSRDF_MAX_BOUNCES
constexpr float kThroughputEpsilon = 1e-6f;  // VOLUME_THROUGHPUT_EPSILON
constexpr int kSimilarityLevel = 9;          // SUBSURFACE_RANDOM_WALK_SIMILARITY_LEVEL
constexpr int kMaxDiskHits = 4;              // BSSRDF_MAX_HITS
constexpr float kBurleyTruncate = 16.0f;     // BURLEY_TRUNCATE
constexpr float kBurleyTruncateCdf = 0.9963790093708328f;

Spectrum exp_neg(const Spectrum& x) { return Spectrum(std::exp(-x.x), std::exp(-x.y), std::exp(-x.z)); }

// The walk's distance pdf per channel: a collision (sigma_t T) or passing to the surface (T).
Spectrum distance_pdf(const Spectrum& sigma_t, float t, bool hit) {
  const Spectrum T = exp_neg(sigma_t * t);
  return hit ? T : sigma_t * T;
}

// Dwivedi's guiding (Meng et al. 2016, eqs. 9 and 10; d'Eon and Krivanek 2020, eq. 67).
float dwivedi_eval(float v, float phase_log, float cos_theta) { return 1 / ((v - cos_theta) * phase_log); }
float dwivedi_sample(float v, float phase_log, float u) { return v - (v + 1) * std::exp(-u * phase_log); }
float dwivedi_length(float alpha) {
  return 1 / std::sqrt(1 - std::pow(alpha, 2.44294f - 0.0215813f * alpha + 0.578637f / alpha));
}

Vec3 direction_from_cosine(const Vec3& axis, float cos_theta, float u) {
  const float sin_theta = std::sqrt(std::max(0.0f, 1 - cos_theta * cos_theta));
  const float phi = 2 * kPi * u;
  return Frame(axis).to_world(Vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta));
}

// volume_sample_channel: a channel by |throughput x alpha| (Chiang et al. 2016).
int sample_channel(const Spectrum& alpha, const Spectrum& throughput, float u, Spectrum* pdf) {
  const Spectrum w = abs(throughput * alpha);
  const float sum = w.x + w.y + w.z;
  *pdf = sum > 0 ? w / sum : Spectrum(1.0f / 3);
  float c = 0;
  for (int k = 0; k < 3; ++k) {
    c += (*pdf)[k];
    if (u < c) return k;
  }
  return 2;
}

bool random_walk(const Geometry& geometry, const SurfacePoint& sp, const Vec3& N, const Vec3& ng, const Lobe& l,
                 float time, Sampler& sampler, Spectrum* beta, SubsurfaceExit* exit) {
  // A diffuse direction into the surface.
  const Vec3 local = sample_cosine_hemisphere(sampler.next_2d());
  Vec3 D = Frame(-N).to_world(local);
  if (!(dot(-ng, D) > 0)) return false;

  Spectrum sigma_t, alpha, throughput;
  for (int k = 0; k < 3; ++k) {
    random_walk_remap(l.sss_albedo[k], l.sss_radius[k], l.sss_anisotropy, &sigma_t[k], &alpha[k]);
    // The closure weight holds the albedo, which the scattering adds again (safe_divide_color).
    throughput[k] = l.sss_albedo[k] != 0 ? (*beta)[k] / l.sss_albedo[k] : 0.0f;
    // Low albedos give a diffusion length of 1 and an infinite guiding phase: alpha at least 0.2,
    // the throughput scaled to make up for it.
    constexpr float kMinAlpha = 0.2f;
    if (alpha[k] < kMinAlpha) {
      throughput[k] *= alpha[k] / kMinAlpha;
      alpha[k] = kMinAlpha;
    }
  }
  // The highest albedo's diffusion length guides every channel (Cycles' choice).
  const float dl = dwivedi_length(max_component(alpha));
  if (!(dl > 1) || !std::isfinite(dl)) return false;
  const float phase_log = std::log((dl + 1) / (dl - 1));

  const float g0 = l.sss_anisotropy;
  const float guided_fraction0 = 1 - std::max(0.5f, std::pow(std::abs(g0), 0.125f));
  const Spectrum sigma_s0 = sigma_t * alpha;
  // Past kSimilarityLevel bounces: isotropic with the similarity relation's reduced coefficients.
  const Spectrum sigma_s_star = sigma_s0 * (1 - g0);
  const Spectrum sigma_t_star = sigma_t - sigma_s0 + sigma_s_star;

  Ray ray;
  ray.o = spawn_origin(sp, D);
  ray.time = time;
  const Vec3 P = sp.p;
  Vec3 pos = ray.o;
  bool hit = false, have_opposite = false;
  float opposite_distance = 0;
  Hit h;
  for (int bounce = 0; bounce < kMaxBounces; ++bounce) {
    const bool similar = bounce > kSimilarityLevel;
    const float g = similar ? 0.0f : g0;
    const float guided_fraction = similar ? 0.75f : guided_fraction0;
    const Spectrum st = similar ? sigma_t_star : sigma_t;
    const Spectrum ss = similar ? sigma_s_star : sigma_s0;

    Spectrum channel_pdf;
    const int channel = sample_channel(alpha, throughput, sampler.next_1d(), &channel_pdf);
    float sample_sigma_t = st[channel];
    const float u_t = sampler.next_1d();

    float backward_fraction = 0, forward_factor = 0, backward_factor = 0;
    float forward_stretch = 1, backward_stretch = 1;
    if (bounce > 0) {
      const bool guided = sampler.next_1d() < guided_fraction;
      bool backward = false;
      if (have_opposite) {
        // Towards a nearby opposite interface with a probability that grows as the walk nears it.
        const float x = clamp(dot(pos - P, -N), 0.0f, opposite_distance);
        backward_fraction = 1 / (1 + std::exp((opposite_distance - 2 * x) / dl));
        backward = sampler.next_1d() < backward_fraction;
      }
      const Vec2 u = sampler.next_2d();
      float cos_theta, hg_pdf;
      Vec3 nd;
      if (guided) {
        cos_theta = dwivedi_sample(dl, phase_log, u.x);
        if (backward) cos_theta = -cos_theta;  // the backward distribution mirrored along N
        nd = direction_from_cosine(N, cos_theta, u.y);
        hg_pdf = hg_phase(dot(-D, nd), g);
      } else {
        if (!PhaseHG{g}.sample(-D, u, &nd, &hg_pdf)) return false;
        cos_theta = dot(nd, N);
      }
      D = nd;
      // The guided pdfs relative to the phase function's (which cancels with the estimator's).
      forward_factor = 0.5f * kInvPi * dwivedi_eval(dl, phase_log, cos_theta) / hg_pdf;
      backward_factor = 0.5f * kInvPi * dwivedi_eval(dl, phase_log, -cos_theta) / hg_pdf;
      forward_stretch = 1 - cos_theta / dl;
      backward_stretch = 1 + cos_theta / dl;
      if (guided) sample_sigma_t *= backward ? backward_stretch : forward_stretch;
    }

    float t = -std::log(1 - u_t) / sample_sigma_t;
    ray.o = pos;
    ray.d = D;
    ray.tmin = 0;
    // The first segment also looks for the opposite side within 10 mean free paths.
    ray.tmax = bounce == 0 ? std::max(t, 10 / std::min(st.x, std::min(st.y, st.z))) : t;
    hit = geometry.intersect_instance(ray, sp.instance, &h);
    float t_hit = hit ? h.t : ray.tmax;
    if (bounce == 0) {
      if (hit) {
        have_opposite = true;
        opposite_distance = dot(pos + D * t_hit - P, -N);
      }
      hit = hit && t_hit < t;
    }
    if (hit) t = t_hit;
    pos = pos + D * t;

    const Spectrum T = exp_neg(st * t);
    Spectrum pdf = hit ? T : st * T;
    if (bounce > 0) {
      // MIS (balance) over classic, forward- and backward-guided sampling, then over channels.
      Spectrum guided_pdf = distance_pdf(st * forward_stretch, t, hit);
      if (have_opposite)
        guided_pdf = lerp(backward_fraction, guided_pdf * forward_factor,
                          distance_pdf(st * backward_stretch, t, hit) * backward_factor);
      else
        guided_pdf *= forward_factor;
      pdf = lerp(guided_fraction, pdf, guided_pdf);
    }
    throughput *= (hit ? T : ss * T) / dot(channel_pdf, pdf);
    if (hit || !(max_component(throughput) >= kThroughputEpsilon)) break;
  }
  if (!hit || !is_finite(throughput)) return false;
  *beta = throughput;
  exit->sp = geometry.surface(h);
  exit->wo = D;
  return true;
}

// Christensen-Burley's profile (closure/bssrdf.h): normalised by 2 pi r, truncated at 16 d.
float burley_eval(float d, float r) {
  if (r >= kBurleyTruncate * d) return 0;
  const float e3 = std::exp(-r / (3 * d));
  return (e3 * e3 * e3 + e3) / (4 * d);
}
float burley_pdf(float d, float r) { return r == 0 ? 0.0f : burley_eval(d, r) / kBurleyTruncateCdf; }
// The scaled radius at cdf xi: Newton's method from Cycles' fitted first guess.
float burley_root(float xi) {
  float r = xi <= 0.9f ? std::exp(xi * xi * 2.4f) - 1 : 15.0f;
  for (int i = 0; i < 10; ++i) {
    const float e3 = std::exp(-r / 3), e = e3 * e3 * e3;
    const float f = 1 - 0.25f * e - 0.75f * e3 - xi, df = 0.25f * e + 0.25f * e3;
    if (std::abs(f) < 1e-6f || df == 0) break;
    r = std::max(0.0f, r - f / df);
  }
  return r;
}
float channels(const Spectrum& radius) { return float((radius.x > 0) + (radius.y > 0) + (radius.z > 0)); }

bool disk(const Geometry& geometry, const SurfacePoint& sp, const Vec3& ng, bool backfacing, const Lobe& l, float time,
          Sampler& sampler, Spectrum* beta, SubsurfaceExit* exit) {
  Vec2 u = sampler.next_2d();
  const Spectrum& radius = l.sss_radius;
  // One of three projection axes (the normal half the time), MIS-weighted below.
  const Frame f(ng);
  Vec3 axis[3] = {f.n, f.s, f.t};
  float pick[3] = {0.5f, 0.25f, 0.25f};
  if (u.y < 0.5f) {
    u.y *= 2;
  } else if (u.y < 0.75f) {
    std::swap(axis[0], axis[1]);
    std::swap(pick[0], pick[1]);
    u.y = (u.y - 0.5f) * 4;
  } else {
    std::swap(axis[0], axis[2]);
    std::swap(pick[0], pick[2]);
    u.y = (u.y - 0.75f) * 4;
  }
  // A channel, then a radius from its profile (bssrdf_sample).
  float xi = u.x * channels(radius), d = 0, sum = 0;
  for (int k = 0; k < 3; ++k) {
    if (!(radius[k] > 0)) continue;
    if (xi < sum + 1) {
      xi -= sum;
      d = radius[k];
      break;
    }
    sum += 1;
  }
  if (!(d > 0)) return false;
  const float disk_r = burley_root(xi * kBurleyTruncateCdf) * d;
  const float rm = kBurleyTruncate * d;
  const float height = std::sqrt(std::max(0.0f, rm * rm - disk_r * disk_r));
  const float phi = 2 * kPi * u.y;
  Ray ray;
  ray.o = sp.p + axis[0] * height + axis[1] * (disk_r * std::cos(phi)) + axis[2] * (disk_r * std::sin(phi));
  ray.d = -axis[0];
  ray.tmax = 2 * height;
  ray.time = time;
  // Every hit along the probe; at most kMaxDiskHits of them, a uniform random subset (reservoir).
  Hit hits[kMaxDiskHits];
  int count = 0;
  geometry.local_hits(ray, sp.instance, [&](const Hit& hh) {
    if (count < kMaxDiskHits) {
      hits[count] = hh;
    } else {
      const int j = int(sampler.next_1d() * float(count + 1));
      if (j < kMaxDiskHits) hits[j] = hh;
    }
    ++count;
    return true;
  });
  if (count == 0) return false;
  const int n = std::min(count, kMaxDiskHits);
  for (int i = 1; i < n; ++i)  // nearest first, as Cycles sorts them
    for (int j = i; j > 0 && hits[j].t < hits[j - 1].t; --j) std::swap(hits[j], hits[j - 1]);
  float pdf_disk = 0;
  for (int k = 0; k < 3; ++k) pdf_disk += burley_pdf(radius[k], disk_r);
  pdf_disk /= channels(radius);
  if (!(pdf_disk > 0)) return false;
  Spectrum weights[kMaxDiskHits];
  SurfacePoint points[kMaxDiskHits];
  Vec3 normals[kMaxDiskHits];
  float total = 0;
  for (int i = 0; i < n; ++i) {
    points[i] = geometry.surface(hits[i]);
    normals[i] = backfacing ? -points[i].ng : points[i].ng;
    const float p0 = pick[0] * std::abs(dot(axis[0], normals[i]));
    const float p1 = pick[1] * std::abs(dot(axis[1], normals[i]));
    const float p2 = pick[2] * std::abs(dot(axis[2], normals[i]));
    float w = p0 / (p0 * p0 + p1 * p1 + p2 * p2);  // power heuristic over the axes, p0 cancelled
    if (count > kMaxDiskHits) w *= float(count) / kMaxDiskHits;
    const float r = length(points[i].p - sp.p);
    Spectrum e;
    for (int k = 0; k < 3; ++k) e[k] = burley_pdf(radius[k], r);
    weights[i] = e * (w / pdf_disk);
    if (!is_finite(weights[i])) weights[i] = Spectrum(0.0f);
    total += average(abs(weights[i]));
  }
  if (!(total > 0)) return false;
  // One hit by its weight (importance resampling).
  const float pick_u = sampler.next_1d() * total;
  float c = 0;
  for (int i = 0; i < n; ++i) {
    const float sw = average(abs(weights[i]));
    if (pick_u < c + sw || (i == n - 1 && sw > 0)) {
      *beta *= weights[i] * (total / sw);
      exit->sp = points[i];
      exit->wo = normals[i];
      return true;
    }
    c += sw;
  }
  return false;
}

}  // namespace

void random_walk_remap(float albedo, float d, float g, float* sigma_t, float* alpha) {
  // Wrenninge et al.'s fit of the single-scattering albedo for anisotropy g (Cycles'
  // subsurface_random_walk_remap; Chiang et al.'s formula at g = 0): six polynomials of degree 7.
  auto poly = [g](const float(&c)[8]) {
    float r = 0;
    for (int k = 7; k >= 0; --k) r = r * g + c[k];
    return r;
  };
  static constexpr float kA[8] = {1.8260523782f,   -1.28451056436f, -1.79904629312f, 9.19393289202f,
                                  -22.8215585862f, 32.0234874259f,  -23.6264803333f, 7.21067002658f};
  static constexpr float kB[8] = {0.0f,           31.1491581433f,  -201.847017512f, 841.576016723f, -2018.09288505f,
                                  2731.71560286f, -1935.41424244f, 559.009054474f};
  static constexpr float kC[8] = {1.09686102424f, -0.394704063468f, 1.05258115941f, -8.83963712726f,
                                  28.8643230661f, -46.8802913581f,  38.5402837518f, -12.7181042538f};
  static constexpr float kD[8] = {0.496310210422f, 0.360146581622f, -2.15139309747f, 17.8896899217f,
                                  -55.2984010333f, 82.065982243f,   -58.5106008578f, 15.8478295021f};
  static constexpr float kE[8] = {0.0f,           76.7316253952f,  -594.356773233f, 2448.8834203f, -5576.68528998f,
                                  7116.60171912f, -4763.54467887f, 1303.5318055f};
  static constexpr float kF[8] = {2.40602999408f, -2.51814844609f, 9.18494908356f, -79.2191708682f,
                                  259.082868209f, -403.613804597f, 302.85712436f,  -87.4370473567f};
  const float A = poly(kA), B = 4.98511194385f + 0.127355959438f * std::exp(poly(kB)), C = poly(kC);
  const float D = poly(kD), E = 4.23190299701f + 0.00310603949088f * std::exp(poly(kE)), F = poly(kF);
  const float blend = std::pow(albedo, 0.25f);
  const float a = (1 - blend) * A * std::pow(std::atan(B * albedo), C) + blend * D * std::pow(std::atan(E * albedo), F);
  *alpha = clamp(std::isfinite(a) ? a : 0.0f, 0.0f, 0.999999f);
  *sigma_t = 1 / std::max(d, 1e-16f) / (1 - g);
}

Lobe subsurface_exit_lobe(const Lobe& l) {
  Lobe e;
  e.weight = Spectrum(1.0f);
  if (l.sss_fresnel) {
    e.type = LobeType::PrincipledDiffuse;
    e.diffuse_part = DiffusePart::LambertExit;
  }
  return e;
}

bool subsurface_scatter(const Geometry& geometry, const SurfacePoint& sp, const Vec3& n, const Vec3& ng,
                        bool backfacing, const Lobe& l, float time, Sampler& sampler, Spectrum* beta,
                        SubsurfaceExit* exit) {
  if (l.sss_method == SubsurfaceMethod::Burley) return disk(geometry, sp, ng, backfacing, l, time, sampler, beta, exit);
  return random_walk(geometry, sp, n, ng, l, time, sampler, beta, exit);
}

}  // namespace lt
