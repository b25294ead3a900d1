#include "denoise/nfor.h"

#include <tbb/blocked_range.h>
#include <tbb/blocked_range2d.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <utility>

namespace lt {

namespace {

constexpr int kDims = 1 + kFeatureChannels;      // the regression's intercept and features
constexpr int kPairs = kDims * (kDims + 1) / 2;  // entries of the symmetric normal matrix
constexpr int kTile = 32;                        // pixels per task side (a row's sums stay in L1)
// Ridge added to the features' diagonal, relative to the weight sum: keeps the normal equations
// solvable where a feature is constant over the window (a flat wall's normal).
constexpr double kRidge = 1e-3;

// Eight floats (GCC's vector extension, which clang shares): loops the vectoriser leaves scalar
// (it will not if-convert a float-to-int conversion) written as vector operations, compiled for
// whatever the tile function's clone targets (AVX2 or twice SSE2).
typedef float f8 __attribute__((vector_size(32)));
typedef int32_t i8 __attribute__((vector_size(32)));

inline f8 load8(const float* p) {
  f8 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline f8 select8(i8 mask, f8 a, f8 b) { return f8((i8(a) & mask) | (i8(b) & ~mask)); }

// e^-x for x >= 0 (NL-means weights), per lane: 2^(-x log2 e) from the exponent bits and a
// degree-5 polynomial for the fraction (relative error below 2e-6; the same bits on every thread).
inline f8 exp_neg(f8 x) {
  const f8 t = select8(x < 80.0f, x, f8{} + 80.0f) * -1.44269504f;  // in [-115.4, 0]
  // floor(t): truncation rounds up where t (<= 0) is not whole (the mask is -1 there).
  const i8 ti = __builtin_convertvector(t, i8);
  const i8 fi = ti + (__builtin_convertvector(ti, f8) > t);
  const f8 f = t - __builtin_convertvector(fi, f8);  // in [0, 1)
  const f8 p = 1.0f + f * (0.693147f + f * (0.240227f + f * (0.0555041f + f * (0.00961813f + f * 0.00133336f))));
  return f8(i8(p) + fi * (1 << 23));  // a multiply: shifting a negative value is undefined
}

bool finite(const float* v, int n) {
  for (int k = 0; k < n; ++k)
    if (!std::isfinite(v[k])) return false;
  return true;
}

// One image-wide plane of floats (one per pixel), a part of a FreshVector (zero at first).
struct Plane {
  float* p = nullptr;
  float* data() const { return p; }
  float& operator[](size_t i) const { return p[i]; }
};

// The inputs as planes (one float per pixel each) so that the inner loops run along rows.
struct Planes {
  static constexpr int kCount = 2 * 3 + 2 * 3 + kFeatureChannels + 1;
  explicit Planes(size_t n) {
    memory.resize(kCount * n);
    Plane* all[kCount];
    int k = 0;
    for (int j = 0; j < 2; ++j)
      for (int c = 0; c < 3; ++c) all[k++] = &color[j][c], all[k++] = &var[j][c];
    for (Plane& f : feature) all[k++] = &f;
    all[k++] = &valid;
    for (int i = 0; i < kCount; ++i) all[i]->p = memory.data() + size_t(i) * n;
  }
  int w = 0, h = 0;
  FreshVector<float> memory;
  Plane color[2][3];  // each half's RGB
  Plane var[2][3];    // each half's variance, smoothed
  Plane feature[kFeatureChannels];
  Plane valid;  // 1 or 0
};

void prepare(const HalfImages& in, Planes& pl) {
  pl.w = in.width;
  pl.h = in.height;
  const int w = in.width, h = in.height;
  const size_t n = size_t(w) * h;
  // Sanitise: a pixel with any non-finite input is left out (valid 0, values 0), so it cannot spread.
  tbb::parallel_for(0, h, [&](int y) {
    for (size_t i = size_t(y) * w; i < size_t(y + 1) * w; ++i) {
      bool ok = in.valid[i] != 0;
      for (int j = 0; j < 2; ++j)
        ok = ok && finite(&in.color[j][3 * i], 3) && finite(&in.variance[j][3 * i], 3) &&
             finite(&in.feature[j][kFeatureChannels * i], kFeatureChannels);
      if (!ok) continue;
      pl.valid[i] = 1;
      for (int j = 0; j < 2; ++j)
        for (int c = 0; c < 3; ++c) pl.color[j][c][i] = in.color[j][3 * i + c];
      for (int k = 0; k < kFeatureChannels; ++k)
        pl.feature[k][i] = 0.5f * (in.feature[0][kFeatureChannels * i + k] + in.feature[1][kFeatureChannels * i + k]);
    }
  });
  // Each half's variance (from its own samples: few degrees of freedom) smoothed over its valid
  // 3x3 neighbours (Rousselle et al. 2012 smooth their dual-buffer variance likewise).
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      double sum[2][3] = {}, count = 0;
      for (int qy = std::max(0, y - 1); qy <= std::min(h - 1, y + 1); ++qy)
        for (int qx = std::max(0, x - 1); qx <= std::min(w - 1, x + 1); ++qx) {
          const size_t q = size_t(qy) * w + qx;
          if (pl.valid[q] == 0) continue;
          count += 1;
          for (int j = 0; j < 2; ++j)
            for (int c = 0; c < 3; ++c) sum[j][c] += std::max(0.0f, in.variance[j][3 * q + c]);  // finite: valid
        }
      const size_t i = size_t(y) * w + x;
      if (count > 0)
        for (int j = 0; j < 2; ++j)
          for (int c = 0; c < 3; ++c) pl.var[j][c][i] = float(sum[j][c] / count);
    }
  });
  // Distance in units of the image's mean distance (the other features are of order 1 already),
  // so that the ridge means the same in any scene's scale. Summed per row in row order.
  std::vector<double> row_sum(h, 0.0), row_count(h, 0.0);
  tbb::parallel_for(0, h, [&](int y) {
    for (size_t i = size_t(y) * w; i < size_t(y + 1) * w; ++i)
      if (pl.valid[i] != 0 && pl.feature[kFeatureChannels - 1][i] > 0) {
        row_sum[y] += pl.feature[kFeatureChannels - 1][i];
        row_count[y] += 1;
      }
  });
  double sum = 0, count = 0;
  for (int y = 0; y < h; ++y) {
    sum += row_sum[y];
    count += row_count[y];
  }
  const float scale = count > 0 && sum > 0 ? float(count / sum) : 1.0f;
  for (size_t i = 0; i < n; ++i) pl.feature[kFeatureChannels - 1][i] *= scale;
}

// The reconstruction's sums per pixel, over the whole image: for each half j, the weighted fits
// that reach the pixel (RGB) and their weights, zero at first. Tiles add into them in a fixed
// order (denoise()).
struct Sums {
  explicit Sums(size_t n) {
    memory.resize(8 * n);
    for (int j = 0; j < 2; ++j) {
      for (int c = 0; c < 3; ++c) value[j][c].p = memory.data() + size_t(4 * j + c) * n;
      weight[j].p = memory.data() + size_t(4 * j + 3) * n;
    }
  }
  FreshVector<float> memory;
  Plane value[2][3], weight[2];
};

// A task's buffers, reused across its tiles; per-pixel arrays are tile-local (ty * kTile + tx).
struct Scratch {
  std::vector<float> term[2], vsum[2], psum[2];          // an offset's distance terms and patch sums
  std::vector<float> weight[2];                          // per offset and pixel: the NL-means weight of guide g
  std::vector<float> acc[2][kPairs], rhs[2][kDims * 3];  // a row's normal equations per half
  // A row's gathered offsets: design rows (features' differences), each half's weighted design
  // rows (the weight, the weight times each difference) and colours; [offset][dimension][lane].
  std::vector<float> gx, gw[2], gy[2];
  std::vector<float> coef[2][kDims * 3];  // each half's fit per pixel: coefficient d, channel c at d*3+c
  std::vector<float> inv_wsum[2];         // per guide g and pixel: its weights' sum, then 1 / it
};

// The packed index of the symmetric normal matrix's entry (a, b), a <= b (the order in which the
// tile accumulates them).
constexpr int packed(int a, int b) { return a * kDims - a * (a - 1) / 2 + (b - a); }

// Row a of a row's normal equations, lanes [i0, i0 + 8): the pairs (a, b), b >= a, and the
// right-hand sides (a, c) summed over the n gathered offsets (gw, gx, gy: Scratch's), in registers.
template <int A>
__attribute__((always_inline)) inline void accumulate_row(int n, const float* gw, const float* gx, const float* gy,
                                                          int i0, std::vector<float>* acc, std::vector<float>* rhs) {
  constexpr int kB = kDims - A;
  f8 pair[kB] = {}, right[3] = {};
  for (int q = 0; q < n; ++q) {
    const f8 wa = load8(gw + (size_t(q) * kDims + A) * kTile + i0);
    for (int b = 0; b < kB; ++b) {
      if (A + b == 0)
        pair[b] += wa;
      else
        pair[b] += wa * load8(gx + (size_t(q) * kFeatureChannels + A + b - 1) * kTile + i0);
    }
    for (int c = 0; c < 3; ++c) right[c] += wa * load8(gy + (size_t(q) * 3 + c) * kTile + i0);
  }
  for (int b = 0; b < kB; ++b) std::memcpy(acc[packed(A, A + b)].data() + i0, &pair[b], sizeof(f8));
  for (int c = 0; c < 3; ++c) std::memcpy(rhs[A * 3 + c].data() + i0, &right[c], sizeof(f8));
}

template <int... A>
__attribute__((always_inline)) inline void accumulate_rows(int n, const float* gw, const float* gx, const float* gy,
                                                           int i0, std::vector<float>* acc, std::vector<float>* rhs,
                                                           std::integer_sequence<int, A...>) {
  (accumulate_row<A>(n, gw, gx, gy, i0, acc, rhs), ...);
}

// Each lane's first-order fit for a row of kTile pixels: (A + ridge) b = r by Cholesky in double,
// vectorised across the lanes (a lane that fails takes the zeroth-order fit). Inputs: the packed
// normal matrices and right-hand sides (r[d * 3 + c]); output b[d * 3 + c], coefficient d of
// channel c, and has[i] = 0 where a lane has no valid neighbour (no fit at all).
// Inlined into the tile function's clones; every loop runs across the lanes, innermost.
__attribute__((always_inline)) inline void solve_row(const float* const* a_in, const float* const* r_in,
                                                     float* const* out, float* has) {
  alignas(32) double l[kPairs][kTile], inv[kDims][kTile], y[kDims][kTile], b[kDims][kTile], ok[kTile], wsum[kTile];
  auto L = [&](int i, int j) -> double* { return l[packed(j, i)]; };  // lower factor L(i, j), j <= i
  for (int i = 0; i < kTile; ++i) {
    wsum[i] = a_in[0][i];
    ok[i] = wsum[i] > 0 ? 1.0 : 0.0;
  }
  for (int j = 0; j < kDims; ++j) {
    double* ljj = L(j, j);
    // Ridge on the features' diagonal, relative to the weight sum.
    for (int i = 0; i < kTile; ++i) ljj[i] = double(a_in[packed(j, j)][i]) + (j > 0 ? kRidge * wsum[i] : 0.0);
    for (int k = 0; k < j; ++k) {
      const double* ljk = L(j, k);
      for (int i = 0; i < kTile; ++i) ljj[i] -= ljk[i] * ljk[i];
    }
    for (int i = 0; i < kTile; ++i) {
      const double d = ljj[i];
      ok[i] = d > 0 ? ok[i] : 0.0;
      ljj[i] = std::sqrt(d > 0 ? d : 1.0);
      inv[j][i] = 1.0 / ljj[i];
    }
    for (int m = j + 1; m < kDims; ++m) {
      double* lmj = L(m, j);
      for (int i = 0; i < kTile; ++i) lmj[i] = a_in[packed(j, m)][i];
      for (int k = 0; k < j; ++k) {
        const double *lmk = L(m, k), *ljk = L(j, k);
        for (int i = 0; i < kTile; ++i) lmj[i] -= lmk[i] * ljk[i];
      }
      for (int i = 0; i < kTile; ++i) lmj[i] *= inv[j][i];
    }
  }
  for (int c = 0; c < 3; ++c) {
    for (int m = 0; m < kDims; ++m) {
      for (int i = 0; i < kTile; ++i) y[m][i] = r_in[m * 3 + c][i];
      for (int k = 0; k < m; ++k) {
        const double* lmk = L(m, k);
        for (int i = 0; i < kTile; ++i) y[m][i] -= lmk[i] * y[k][i];
      }
      for (int i = 0; i < kTile; ++i) y[m][i] *= inv[m][i];
    }
    for (int m = kDims - 1; m >= 0; --m) {
      for (int i = 0; i < kTile; ++i) b[m][i] = y[m][i];
      for (int k = m + 1; k < kDims; ++k) {
        const double* lkm = L(k, m);
        for (int i = 0; i < kTile; ++i) b[m][i] -= lkm[i] * b[k][i];
      }
      for (int i = 0; i < kTile; ++i) b[m][i] *= inv[m][i];
    }
    // A fit whose value at the pixel is negative (a non-negative image) or not finite fails (a
    // NaN fails every comparison).
    for (int i = 0; i < kTile; ++i) ok[i] = b[0][i] >= 0 ? ok[i] : 0.0;
    for (int m = 0; m < kDims; ++m)
      for (int i = 0; i < kTile; ++i) ok[i] = std::abs(b[m][i]) <= DBL_MAX ? ok[i] : 0.0;
    for (int m = 0; m < kDims; ++m)
      for (int i = 0; i < kTile; ++i) out[m * 3 + c][i] = float(b[m][i]);
  }
  for (int i = 0; i < kTile; ++i) {
    has[i] = wsum[i] > 0 ? 1.0f : 0.0f;
    if (ok[i] != 0 || !(wsum[i] > 0)) continue;
    for (int m = 0; m < kDims * 3; ++m) out[m][i] = m < 3 ? float(r_in[m][i] / wsum[i]) : 0.0f;
  }
}

// Denoises the tile [x0, x1) x [y0, y1): fits each pixel's regressions and adds each fit, evaluated
// at every neighbour of its window, into sums (which reach the window's radius beyond the tile).
// Also compiled for AVX2 + FMA, used where the CPU has them (the same bits on every thread).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void denoise_tile(const Planes& pl, const DenoiseParams& p, int x0, int x1, int y0, int y1, Scratch& s, Sums& sums) {
  const int w = pl.w, h = pl.h, f = p.patch, r = p.window;
  const int tw = x1 - x0, th = y1 - y0, ew = tw + 2 * f, eh = th + 2 * f;
  const size_t tn = size_t(kTile) * th;  // tile-local arrays: rows of kTile (the lanes past tw unused)
  const int side = 2 * r + 1, offsets = side * side;
  const float k2 = p.k * p.k;
  for (int g = 0; g < 2; ++g) {
    s.term[g].resize(size_t(ew) * eh);
    s.vsum[g].resize(size_t(ew) * th);
    s.psum[g].resize(tn);
    s.weight[g].resize(size_t(offsets) * tn);
    for (auto& a : s.acc[g]) a.resize(kTile);
    for (auto& a : s.rhs[g]) a.resize(kTile);
    for (auto& a : s.coef[g]) a.resize(tn);
    s.inv_wsum[g].assign(tn, 0.0f);
  }
  const float* valid = pl.valid.data();
  const float inv_patch = 1.0f / float((2 * f + 1) * (2 * f + 1));
  for (int oi = 0; oi < offsets; ++oi) {
    const int dy = oi / side - r, dx = oi % side - r;
    // NL-means per-pixel distances of the offset on each guide half g, over the tile and its
    // patch margin (Rousselle et al. 2012, eq. 5: variance-cancelled, normalised by the noise):
    //   d_c(p, q) = ((u_p - u_q)^2 - (v_p + min(v_p, v_q))) / (eps + k^2 (v_p + v_q)).
    for (int ey = 0; ey < eh; ++ey) {
      const int y = y0 - f + ey, qy = y + dy;
      float* t0 = &s.term[0][size_t(ey) * ew];
      float* t1 = &s.term[1][size_t(ey) * ew];
      std::fill(t0, t0 + ew, 0.0f);
      std::fill(t1, t1 + ew, 0.0f);
      if (y < 0 || y >= h || qy < 0 || qy >= h) continue;
      const int lo = std::max({x0 - f, 0, -dx}), hi = std::min({x1 + f, w, w - dx});
      // Extended index e = x - (x0 - f) over [lo, hi); image indices row + e and qrow + e (>= 0).
      const ptrdiff_t row = ptrdiff_t(y) * w + x0 - f, qrow = row + ptrdiff_t(dy) * w + dx;
      const int elo = lo - (x0 - f), ehi = hi - (x0 - f);
      for (int g = 0; g < 2; ++g) {
        float* t = g ? t1 : t0;
        for (int c = 0; c < 3; ++c) {
          const float* u = pl.color[g][c].data();
          const float* v = pl.var[g][c].data();
          for (int e = elo; e < ehi; ++e) {
            const float up = u[row + e], uq = u[qrow + e], vp = v[row + e], vq = v[qrow + e];
            const float d = up - uq;
            t[e] += (d * d - (vp + std::min(vp, vq))) / (1e-10f + k2 * (vp + vq));
          }
        }
        for (int e = elo; e < ehi; ++e) t[e] *= valid[row + e] * valid[qrow + e] * (1.0f / 3.0f);
      }
    }
    // The patch's sum: a box filter, columns then rows (contiguous loops).
    for (int g = 0; g < 2; ++g) {
      float* vs = s.vsum[g].data();
      std::copy(s.term[g].begin(), s.term[g].begin() + size_t(ew) * th, vs);
      for (int j = 1; j <= 2 * f; ++j) {
        const float* t = &s.term[g][size_t(j) * ew];
        for (size_t e = 0; e < size_t(ew) * th; ++e) vs[e] += t[e];
      }
      for (int ty = 0; ty < th; ++ty) {
        float* o = &s.psum[g][size_t(ty) * kTile];
        const float* v = &vs[size_t(ty) * ew];
        std::copy(v, v + tw, o);
        for (int j = 1; j <= 2 * f; ++j)
          for (int i = 0; i < tw; ++i) o[i] += v[i + j];
      }
    }
    for (int g = 0; g < 2; ++g) {
      float* weight = &s.weight[g][size_t(oi) * tn];
      for (int ty = 0; ty < th; ++ty) {
        const int qy = y0 + ty + dy;
        float* wt = weight + size_t(ty) * kTile;
        const int ilo = std::max(x0, -dx) - x0, ihi = std::min(x1, w - dx) - x0;
        // Neighbours outside the image and lanes past the tile: weight 0.
        if (qy < 0 || qy >= h) {
          std::fill(wt, wt + kTile, 0.0f);
          continue;
        }
        const float* ps = &s.psum[g][size_t(ty) * kTile];
        for (int i = 0; i < kTile; i += 8) {  // every lane, then those outside set to 0
          const f8 d = load8(ps + i) * inv_patch, e = exp_neg(select8(d > 0.0f, d, f8{}));
          std::memcpy(wt + i, &e, sizeof e);
        }
        std::fill(wt, wt + std::min(ilo, kTile), 0.0f);
        std::fill(wt + std::max(ihi, 0), wt + kTile, 0.0f);
        float* sum = &s.inv_wsum[g][size_t(ty) * kTile];  // the reconstruction's divisor, below
        for (int i = 0; i < kTile; ++i) sum[i] += wt[i];
      }
    }
  }
  // Half j's normal equations with the weights of guide 1 - j (cross-filtering), a row of pixels
  // at a time, kTile lanes wide (lanes outside the image or the tile have weight 0). The design
  // row: 1 and the features' differences from the pixel's. First each offset's design rows,
  // weights and colours are gathered (s.gx, s.gw, s.gy), then each sum runs over the offsets in
  // registers, eight lanes at a time (accumulate_row): in the offsets' order, as adding them into
  // arrays offset by offset would, without the arrays' loads and stores.
  const size_t gx_size = size_t(offsets) * kFeatureChannels * kTile, gw_size = size_t(offsets) * kDims * kTile,
               gy_size = size_t(offsets) * 3 * kTile;
  s.gx.resize(gx_size);
  for (int j = 0; j < 2; ++j) {
    s.gw[j].resize(gw_size);
    s.gy[j].resize(gy_size);
  }
  for (int ty = 0; ty < th; ++ty) {
    const int y = y0 + ty;
    const size_t o = size_t(ty) * kTile;
    int active = 0;  // offsets whose neighbours are in the image, gathered at 0, 1, ...
    for (int oi = 0; oi < offsets; ++oi) {
      const int dy = oi / side - r, dx = oi % side - r, qy = y + dy;
      if (qy < 0 || qy >= h) continue;
      const int ilo = std::max(x0, -dx) - x0, ihi = std::min(x1, w - dx) - x0;
      if (ilo >= ihi) continue;
      const ptrdiff_t row = ptrdiff_t(y) * w + x0, qrow = ptrdiff_t(qy) * w + dx + x0;
      const bool partial = ilo > 0 || ihi < kTile;  // lanes outside: zero (else all are written)
      const int n = active++;
      float* xr = &s.gx[size_t(n) * kFeatureChannels * kTile];
      for (int k = 0; k < kFeatureChannels; ++k) {
        const float* fe = pl.feature[k].data();
        float* xk = xr + k * kTile;
        if (partial) std::fill(xk, xk + kTile, 0.0f);
        for (int i = ilo; i < ihi; ++i) xk[i] = fe[qrow + i] - fe[row + i];
      }
      for (int j = 0; j < 2; ++j) {
        const float* wsrc = &s.weight[1 - j][size_t(oi) * tn + o];
        float* wa = &s.gw[j][size_t(n) * kDims * kTile];
        if (partial) std::fill(wa, wa + kTile, 0.0f);
        for (int i = ilo; i < ihi; ++i) wa[i] = wsrc[i] * valid[qrow + i];
        float* yr = &s.gy[j][size_t(n) * 3 * kTile];
        for (int c = 0; c < 3; ++c) {
          const float* yq = pl.color[j][c].data() + qrow;
          if (partial) std::fill(yr + c * kTile, yr + (c + 1) * kTile, 0.0f);
          for (int i = ilo; i < ihi; ++i) yr[c * kTile + i] = yq[i];
        }
        for (int k = 0; k < kFeatureChannels; ++k)
          for (int i = 0; i < kTile; ++i) wa[(1 + k) * kTile + i] = wa[i] * xr[k * kTile + i];
      }
    }
    for (int j = 0; j < 2; ++j)
      for (int i0 = 0; i0 < kTile; i0 += 8)
        accumulate_rows(active, s.gw[j].data(), s.gx.data(), s.gy[j].data(), i0, s.acc[j], s.rhs[j],
                        std::make_integer_sequence<int, kDims>());
    // The row's fits per half (solve_row: where a fit fails, the zeroth-order one). A pixel without
    // any valid neighbour has no fit: its weights are set to 0 for the reconstruction.
    alignas(32) float has[kTile];
    for (int j = 0; j < 2; ++j) {
      const float* a[kPairs];
      const float* rv[kDims * 3];
      float* b[kDims * 3];
      for (int q = 0; q < kPairs; ++q) a[q] = s.acc[j][q].data();
      for (int q = 0; q < kDims * 3; ++q) rv[q] = s.rhs[j][q].data(), b[q] = &s.coef[j][q][o];
      solve_row(a, rv, b, has);
      for (int i = 0; i < tw; ++i)
        if (has[i] == 0)
          for (int oi = 0; oi < offsets; ++oi) s.weight[1 - j][size_t(oi) * tn + o + i] = 0;
    }
  }
  // Collaborative reconstruction (NFOR, sec. 4.2): every pixel's fit, evaluated at each neighbour
  // q of its window, adds into q's sums with the pixel's NL-means weight for q over the pixel's
  // weight sum. At an invalid q (features not known) the fit's value at the pixel. Dividing by
  // the sender's sum as well as (at the end) by the receiver's is one step of symmetrising the
  // filter towards a doubly stochastic one (Milanfar 2013, "Symmetrizing Smoothing Filters"),
  // which keeps the light where it was: with the receiver's sum alone, a dark pixel (low noise,
  // few similar neighbours, a small sum) took more from its bright neighbours than they gave up,
  // and the Cornell box came out 0.1 % (+5 standard errors) brighter at 256 samples.
  for (int g = 0; g < 2; ++g)
    for (float& v : s.inv_wsum[g]) v = v > 0 ? 1.0f / v : 0.0f;
  alignas(32) float fit[kTile], xr[kFeatureChannels][kTile], ws[kTile];
  for (int oi = 0; oi < offsets; ++oi) {
    const int dy = oi / side - r, dx = oi % side - r;
    for (int ty = 0; ty < th; ++ty) {
      const int y = y0 + ty, qy = y + dy;
      if (qy < 0 || qy >= h) continue;
      const int ilo = std::max(x0, -dx) - x0, ihi = std::min(x1, w - dx) - x0;
      if (ilo >= ihi) continue;
      const ptrdiff_t row = ptrdiff_t(y) * w + x0, qrow = ptrdiff_t(qy) * w + dx + x0;
      const bool partial = ilo > 0 || ihi < kTile;  // lanes outside: zero (else all are written)
      const size_t o = size_t(ty) * kTile;
      for (int k = 0; k < kFeatureChannels; ++k) {
        const float* fe = pl.feature[k].data();
        if (partial) std::fill(xr[k], xr[k] + kTile, 0.0f);
        for (int i = ilo; i < ihi; ++i) xr[k][i] = (fe[qrow + i] - fe[row + i]) * valid[qrow + i];
      }
      for (int j = 0; j < 2; ++j) {
        const float* w0 = &s.weight[1 - j][size_t(oi) * tn + o];
        const float* inv = &s.inv_wsum[1 - j][o];
        for (int i = 0; i < kTile; ++i) ws[i] = w0[i] * inv[i];
        const float* wt = ws;
        float* sw = sums.weight[j].data() + qrow;
        for (int i = ilo; i < ihi; ++i) sw[i] += wt[i];
        for (int c = 0; c < 3; ++c) {
          const float* b[kDims];
          for (int d = 0; d < kDims; ++d) b[d] = &s.coef[j][d * 3 + c][o];
          for (int i = 0; i < kTile; ++i) {
            float v = b[0][i];
            for (int k = 0; k < kFeatureChannels; ++k) v += b[1 + k][i] * xr[k][i];
            fit[i] = v;
          }
          float* sv = sums.value[j][c].data() + qrow;
          for (int i = ilo; i < ihi; ++i) sv[i] += wt[i] * fit[i];
        }
      }
    }
  }
}

}  // namespace

std::vector<float> denoise(const HalfImages& in, const DenoiseParams& params) {
  const int w = in.width, h = in.height;
  const size_t n = size_t(w) * h;
  Planes pl(n);
  prepare(in, pl);
  DenoiseParams p = params;
  // A tile's sums reach the window's radius beyond it: tiles two apart never share a pixel.
  p.window = std::min(p.window, kTile - 1);
  Sums sums(n);
  tbb::enumerable_thread_specific<Scratch> scratch;
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  // Four rounds, one per tile parity (tx % 2, ty % 2): within a round no two tiles add into the
  // same pixel, and every pixel's sums are added in the same order for any thread count.
  for (int round = 0; round < 4; ++round) {
    const int px = round % 2, py = round / 2;
    const int nx = (tiles_x - px + 1) / 2, ny = (tiles_y - py + 1) / 2;
    if (nx <= 0 || ny <= 0) continue;
    tbb::parallel_for(tbb::blocked_range2d<int>(0, ny, 1, 0, nx, 1), [&](const tbb::blocked_range2d<int>& r) {
      Scratch& s = scratch.local();
      for (int iy = r.rows().begin(); iy < r.rows().end(); ++iy)
        for (int ix = r.cols().begin(); ix < r.cols().end(); ++ix) {
          const int tx = 2 * ix + px, ty = 2 * iy + py;
          denoise_tile(pl, p, tx * kTile, std::min(w, (tx + 1) * kTile), ty * kTile, std::min(h, (ty + 1) * kTile), s,
                       sums);
        }
    });
  }
  // Each half's reconstruction, then their mean (one half alone where the other has no weight).
  std::vector<float> out(3 * n, 0.0f);
  tbb::parallel_for(0, h, [&](int y) {
    for (size_t i = size_t(y) * w; i < size_t(y + 1) * w; ++i)
      for (int c = 0; c < 3; ++c) {
        double sum = 0, halves = 0;
        for (int j = 0; j < 2; ++j)
          if (sums.weight[j][i] > 0) {
            sum += double(sums.value[j][c][i]) / sums.weight[j][i];
            halves += 1;
          }
        const float v = halves > 0 ? float(sum / halves) : 0.0f;
        out[3 * i + c] = std::isfinite(v) ? std::max(0.0f, v) : 0.0f;
      }
  });
  return out;
}

}  // namespace lt
