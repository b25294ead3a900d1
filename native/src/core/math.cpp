#include "core/math.h"

#include "core/error.h"

namespace lt {

Transform compose(const Transform& a, const Transform& b) {
  Transform r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      float v = 0;
      for (int k = 0; k < 3; ++k) v += a.m[i * 4 + k] * b.m[k * 4 + j];
      r.m[i * 4 + j] = v + (j == 3 ? a.m[i * 4 + 3] : 0.0f);
    }
  }
  return r;
}

Transform affine_inverse(const Transform& t) {
  const float* m = t.m;
  float det = t.determinant();
  if (!(std::abs(det) > 0) || !std::isfinite(det)) throw InvalidArgument("transform is singular (determinant 0)");
  double inv_det = 1.0 / double(det);
  // Inverse of the 3x3 linear part by cofactors.
  double a[9] = {double(m[5]) * m[10] - double(m[6]) * m[9], double(m[2]) * m[9] - double(m[1]) * m[10],
                 double(m[1]) * m[6] - double(m[2]) * m[5],  double(m[6]) * m[8] - double(m[4]) * m[10],
                 double(m[0]) * m[10] - double(m[2]) * m[8], double(m[2]) * m[4] - double(m[0]) * m[6],
                 double(m[4]) * m[9] - double(m[5]) * m[8],  double(m[1]) * m[8] - double(m[0]) * m[9],
                 double(m[0]) * m[5] - double(m[1]) * m[4]};
  Transform r;
  for (int i = 0; i < 3; ++i) {
    double tr = 0;
    for (int j = 0; j < 3; ++j) {
      double v = a[i * 3 + j] * inv_det;
      r.m[i * 4 + j] = float(v);
      tr -= v * m[j * 4 + 3];
    }
    r.m[i * 4 + 3] = float(tr);
  }
  return r;
}

}  // namespace lt
