#include "denoise/nfor.h"

#include <tbb/blocked_range.h>
#include <tbb/blocked_range2d.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace lt {

namespace {

constexpr int kDims = 1 + kFeatureChannels;      // the regression's intercept and features
constexpr int kPairs = kDims * (kDims + 1) / 2;  // entries of the symmetric normal matrix
constexpr int kTile = 32;                        // output pixels per task side (accumulators stay in L2)
// Ridge added to the features' diagonal, relative to the weight sum: keeps the normal equations
// solvable where a feature is constant over the window (a flat wall's normal).
constexpr double kRidge = 1e-3;

// e^-x for x >= 0 (NL-means weights), vectorisable: 2^(-x log2 e) from the exponent bits and a
// degree-5 polynomial for the fraction (relative error below 2e-6; the same bits on every thread).
inline float exp_neg(float x) {
  const float t = std::min(x, 80.0f) * -1.44269504f;  // in [-115.4, 0]
  const float fl = std::floor(t), f = t - fl;         // f in [0, 1)
  const float p = 1.0f + f * (0.693147f + f * (0.240227f + f * (0.0555041f + f * (0.00961813f + f * 0.00133336f))));
  int32_t bits;
  std::memcpy(&bits, &p, 4);
  bits += int32_t(fl) * (1 << 23);  // a multiply: shifting a negative value is undefined
  float r;
  std::memcpy(&r, &bits, 4);
  return r;
}

bool finite(const float* v, int n) {
  for (int k = 0; k < n; ++k)
    if (!std::isfinite(v[k])) return false;
  return true;
}

// The inputs as planes (one float per pixel each) so that the inner loops run along rows.
struct Planes {
  int w = 0, h = 0;
  std::vector<float> color[2][3];  // each half's RGB
  std::vector<float> var[2][3];    // each half's variance, smoothed
  std::vector<float> feature[kFeatureChannels];
  std::vector<float> valid;  // 1 or 0
};

Planes prepare(const HalfImages& in) {
  Planes pl;
  pl.w = in.width;
  pl.h = in.height;
  const int w = in.width, h = in.height;
  const size_t n = size_t(w) * h;
  for (int j = 0; j < 2; ++j)
    for (int c = 0; c < 3; ++c) {
      pl.color[j][c].assign(n, 0.0f);
      pl.var[j][c].assign(n, 0.0f);
    }
  for (auto& f : pl.feature) f.assign(n, 0.0f);
  pl.valid.assign(n, 0.0f);
  std::vector<float> raw_var[2][3];
  for (int j = 0; j < 2; ++j)
    for (int c = 0; c < 3; ++c) raw_var[j][c].assign(n, 0.0f);
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
        for (int c = 0; c < 3; ++c) {
          pl.color[j][c][i] = in.color[j][3 * i + c];
          raw_var[j][c][i] = std::max(0.0f, in.variance[j][3 * i + c]);
        }
      for (int k = 0; k < kFeatureChannels; ++k)
        pl.feature[k][i] = 0.5f * (in.feature[0][kFeatureChannels * i + k] + in.feature[1][kFeatureChannels * i + k]);
    }
  });
  // The variance from one pixel's two halves has 1 degree of freedom per channel: smoothed over its
  // valid 3x3 neighbours (Rousselle et al. 2012 smooth their dual-buffer variance likewise).
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      double sum[2][3] = {}, count = 0;
      for (int qy = std::max(0, y - 1); qy <= std::min(h - 1, y + 1); ++qy)
        for (int qx = std::max(0, x - 1); qx <= std::min(w - 1, x + 1); ++qx) {
          const size_t q = size_t(qy) * w + qx;
          if (pl.valid[q] == 0) continue;
          count += 1;
          for (int j = 0; j < 2; ++j)
            for (int c = 0; c < 3; ++c) sum[j][c] += raw_var[j][c][q];
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
  for (float& d : pl.feature[kFeatureChannels - 1]) d *= scale;
  return pl;
}

// A task's buffers, reused across its tiles.
struct Scratch {
  std::vector<float> term[2], hsum[2], weight[2], x[kDims];
  std::vector<float> acc[2][kPairs], rhs[2][kDims * 3];
};

// Solves (A + ridge) b = r for the intercept b_0 per colour channel (Cholesky, double); false if
// A is not positive definite.
bool solve_intercept(const double* a_packed, const double* r, double ridge, double* out) {
  double a[kDims][kDims], l[kDims][kDims] = {};
  for (int i = 0, k = 0; i < kDims; ++i)
    for (int j = i; j < kDims; ++j, ++k) a[i][j] = a[j][i] = a_packed[k];
  for (int i = 1; i < kDims; ++i) a[i][i] += ridge;
  for (int j = 0; j < kDims; ++j) {
    double d = a[j][j];
    for (int k = 0; k < j; ++k) d -= l[j][k] * l[j][k];
    if (!(d > 0)) return false;
    l[j][j] = std::sqrt(d);
    for (int i = j + 1; i < kDims; ++i) {
      double s = a[i][j];
      for (int k = 0; k < j; ++k) s -= l[i][k] * l[j][k];
      l[i][j] = s / l[j][j];
    }
  }
  for (int c = 0; c < 3; ++c) {
    double y[kDims], b[kDims];
    for (int i = 0; i < kDims; ++i) {
      double s = r[i * 3 + c];
      for (int k = 0; k < i; ++k) s -= l[i][k] * y[k];
      y[i] = s / l[i][i];
    }
    for (int i = kDims - 1; i >= 0; --i) {
      double s = y[i];
      for (int k = i + 1; k < kDims; ++k) s -= l[k][i] * b[k];
      b[i] = s / l[i][i];
    }
    out[c] = b[0];
  }
  return std::isfinite(out[0]) && std::isfinite(out[1]) && std::isfinite(out[2]);
}

// Denoises the tile [x0, x1) x [y0, y1) into out (RGB of the whole image).
void denoise_tile(const Planes& pl, const DenoiseParams& p, int x0, int x1, int y0, int y1, Scratch& s, float* out) {
  const int w = pl.w, h = pl.h, f = p.patch, r = p.window;
  const int tw = x1 - x0, th = y1 - y0, ew = tw + 2 * f, eh = th + 2 * f;
  const size_t tn = size_t(tw) * th;
  const float k2 = p.k * p.k;
  for (int g = 0; g < 2; ++g) {
    s.term[g].assign(size_t(ew) * eh, 0.0f);
    s.hsum[g].assign(size_t(tw) * eh, 0.0f);
    s.weight[g].assign(tn, 0.0f);
    for (auto& a : s.acc[g]) a.assign(tn, 0.0f);
    for (auto& a : s.rhs[g]) a.assign(tn, 0.0f);
  }
  for (auto& a : s.x) a.assign(tn, 0.0f);
  const float* valid = pl.valid.data();
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
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
        const ptrdiff_t row = ptrdiff_t(y) * w, qrow = ptrdiff_t(qy) * w + dx;  // qrow + x >= 0
        for (int g = 0; g < 2; ++g) {
          float* t = g ? t1 : t0;
          for (int c = 0; c < 3; ++c) {
            const float* u = pl.color[g][c].data();
            const float* v = pl.var[g][c].data();
            for (int x = lo; x < hi; ++x) {
              const float up = u[row + x], uq = u[qrow + x], vp = v[row + x], vq = v[qrow + x];
              const float d = up - uq;
              t[x - (x0 - f)] += (d * d - (vp + std::min(vp, vq))) / (1e-10f + k2 * (vp + vq));
            }
          }
          for (int x = lo; x < hi; ++x) t[x - (x0 - f)] *= valid[row + x] * valid[qrow + x] * (1.0f / 3.0f);
        }
      }
      // The patch's mean distance: a box filter, rows then columns.
      const float inv_patch = 1.0f / float((2 * f + 1) * (2 * f + 1));
      for (int g = 0; g < 2; ++g) {
        for (int ey = 0; ey < eh; ++ey) {
          const float* t = &s.term[g][size_t(ey) * ew];
          float* o = &s.hsum[g][size_t(ey) * tw];
          for (int x = 0; x < tw; ++x) {
            float sum = 0;
            for (int j = 0; j <= 2 * f; ++j) sum += t[x + j];
            o[x] = sum;
          }
        }
      }
      for (int ty = 0; ty < th; ++ty) {
        const int y = y0 + ty, qy = y + dy;
        if (qy < 0 || qy >= h) continue;
        const int lo = std::max(x0, -dx), hi = std::min(x1, w - dx);
        if (lo >= hi) continue;
        // Tile-local index i = x - x0 over [lo, hi); image index row + x0 + i (qrow + x0 + i >= 0).
        const ptrdiff_t row = ptrdiff_t(y) * w + x0, qrow = ptrdiff_t(qy) * w + dx + x0;
        const size_t o = size_t(ty) * tw;
        const int ilo = lo - x0, ihi = hi - x0;
        for (int g = 0; g < 2; ++g) {
          float* wt = &s.weight[g][o];
          const float* hs = &s.hsum[g][o];
          for (int i = ilo; i < ihi; ++i) {
            float sum = 0;
            for (int j = 0; j <= 2 * f; ++j) sum += hs[size_t(j) * tw + i];
            wt[i] = valid[qrow + i] * exp_neg(std::max(0.0f, sum * inv_patch));
          }
        }
        // The regression's design row: 1 and the features' differences from the centre's.
        for (int k = 0; k < kFeatureChannels; ++k) {
          const float* fe = pl.feature[k].data();
          float* xk = &s.x[1 + k][o];
          for (int i = ilo; i < ihi; ++i) xk[i] = fe[qrow + i] - fe[row + i];
        }
        // Half j is filtered with the weights of guide 1 - j (cross-filtering).
        for (int j = 0; j < 2; ++j) {
          const float* wt = &s.weight[1 - j][o];
          for (int a = 0, pair = 0; a < kDims; ++a) {
            for (int b = a; b < kDims; ++b, ++pair) {
              float* acc = &s.acc[j][pair][o];
              if (a == 0 && b == 0) {
                for (int i = ilo; i < ihi; ++i) acc[i] += wt[i];
              } else if (a == 0) {
                const float* xb = &s.x[b][o];
                for (int i = ilo; i < ihi; ++i) acc[i] += wt[i] * xb[i];
              } else {
                const float *xa = &s.x[a][o], *xb = &s.x[b][o];
                for (int i = ilo; i < ihi; ++i) acc[i] += wt[i] * xa[i] * xb[i];
              }
            }
            for (int c = 0; c < 3; ++c) {
              float* rhs = &s.rhs[j][a * 3 + c][o];
              const float* yq = pl.color[j][c].data();
              if (a == 0) {
                for (int i = ilo; i < ihi; ++i) rhs[i] += wt[i] * yq[qrow + i];
              } else {
                const float* xa = &s.x[a][o];
                for (int i = ilo; i < ihi; ++i) rhs[i] += wt[i] * xa[i] * yq[qrow + i];
              }
            }
          }
        }
      }
    }
  // Per pixel: each half's intercept (the regression's value at the pixel), then their mean.
  for (int ty = 0; ty < th; ++ty)
    for (int tx = 0; tx < tw; ++tx) {
      const size_t t = size_t(ty) * tw + tx, i = size_t(y0 + ty) * w + (x0 + tx);
      double result[3] = {0, 0, 0};
      for (int j = 0; j < 2; ++j) {
        double a[kPairs], rv[kDims * 3], b[3];
        for (int q = 0; q < kPairs; ++q) a[q] = s.acc[j][q][t];
        for (int q = 0; q < kDims * 3; ++q) rv[q] = s.rhs[j][q][t];
        const double wsum = a[0];
        if (!(wsum > 0)) continue;  // no valid neighbour at all: 0
        // The first-order fit; where it fails or extrapolates below zero (a non-negative image),
        // the zeroth-order one: the NL-means weighted mean.
        if (!solve_intercept(a, rv, kRidge * wsum, b) || b[0] < 0 || b[1] < 0 || b[2] < 0)
          for (int c = 0; c < 3; ++c) b[c] = rv[c] / wsum;
        for (int c = 0; c < 3; ++c) result[c] += 0.5 * b[c];
      }
      for (int c = 0; c < 3; ++c) out[3 * i + c] = std::isfinite(float(result[c])) ? float(result[c]) : 0.0f;
    }
}

}  // namespace

std::vector<float> denoise(const HalfImages& in, const DenoiseParams& params) {
  const Planes pl = prepare(in);
  std::vector<float> out(3 * size_t(in.width) * in.height, 0.0f);
  tbb::enumerable_thread_specific<Scratch> scratch;
  const int tiles_x = (in.width + kTile - 1) / kTile, tiles_y = (in.height + kTile - 1) / kTile;
  tbb::parallel_for(tbb::blocked_range2d<int>(0, tiles_y, 1, 0, tiles_x, 1), [&](const tbb::blocked_range2d<int>& r) {
    Scratch& s = scratch.local();
    for (int ty = r.rows().begin(); ty < r.rows().end(); ++ty)
      for (int tx = r.cols().begin(); tx < r.cols().end(); ++tx)
        denoise_tile(pl, params, tx * kTile, std::min(in.width, (tx + 1) * kTile), ty * kTile,
                     std::min(in.height, (ty + 1) * kTile), s, out.data());
  });
  return out;
}

}  // namespace lt
