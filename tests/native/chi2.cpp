#include "chi2.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numeric>
#include <vector>

namespace lt::test {

namespace {

// ---- regularised incomplete gamma Q(a, x) (series / Lentz continued fraction) -------------------
double gamma_p_series(double a, double x) {
  double sum = 1 / a, term = sum;
  for (int n = 1; n < 100000; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::abs(term) < std::abs(sum) * 1e-15) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

double gamma_q_fraction(double a, double x) {
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < 1e-15) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

double gamma_q(double a, double x) {
  if (x <= 0) return 1;
  return x < a + 1 ? 1 - gamma_p_series(a, x) : gamma_q_fraction(a, x);
}

// ---- bin geometry ------------------------------------------------------------------------------
struct Binning {
  int nt, np;
  double power;
  Frame frame;
  double theta(double v) const { return kPi * std::pow(v, power); }
  double dtheta_dv(double v) const { return power == 1 ? double(kPi) : kPi * power * std::pow(v, power - 1); }
  Vec3 direction(double v, double phi) const {
    double t = theta(v);
    double st = std::sin(t);
    return frame.to_world(Vec3(float(st * std::cos(phi)), float(st * std::sin(phi)), float(std::cos(t))));
  }
  // Returns the bin of a direction, or -1 if it is not a usable direction.
  int bin(const Vec3& d) const {
    Vec3 l = frame.to_local(d);
    double x = l.x, y = l.y, z = l.z;
    double r = std::sqrt(x * x + y * y);
    double t = std::atan2(r, z);  // accurate near both poles, unlike acos
    double v = std::pow(std::max(0.0, t / kPi), 1 / power);
    double phi = std::atan2(y, x);  // [-pi, pi]
    int it = std::min(nt - 1, std::max(0, int(v * nt)));
    int ip = std::min(np - 1, std::max(0, int((phi + kPi) / (2 * kPi) * np)));
    return it * np + ip;
  }
};

// Nested adaptive Simpson quadrature over a rectangle: the outer integral over x of the inner
// integral over y. Discontinuities (a light's outline, the horizon, a critical angle) cut through
// bins; 1D adaptive Simpson isolates a jump with two evaluations per halving, so both levels can
// recurse deep where needed, and the kink the jump leaves in the inner integral costs the outer
// level little. (A 2D quadtree needs work proportional to the jump's length over the cell size.)
class Integrator2D {
 public:
  Integrator2D(std::function<double(double, double)> f, int max_depth) : f_(std::move(f)), max_depth_(max_depth) {}

  // tol: absolute error target; rel: relative floor (the pdfs are float: below ~1e-6 of the
  // value, differences are rounding noise that no refinement removes).
  double integrate(double x0, double x1, double y0, double y1, double tol, double rel) {
    evaluations_ = 0;
    rel_ = rel;
    // The inner integrals' errors must stay below what the outer refinement can resolve.
    const double tol_inner = 0.1 * tol / (x1 - x0);
    auto inner = [&](double x) {
      auto g = [&](double y) {
        ++evaluations_;
        return f_(x, y);
      };
      return simpson(g, y0, y1, tol_inner);
    };
    return simpson(inner, x0, x1, tol);
  }
  long evaluations() const { return evaluations_; }

 private:
  template <class G>
  double simpson(G& g, double a, double b, double tol) {
    double fa = g(a), fm = g(0.5 * (a + b)), fb = g(b);
    double whole = (b - a) / 6 * (fa + 4 * fm + fb);
    return refine(g, a, b, fa, fm, fb, whole, std::max(tol, rel_ * std::abs(whole)), 0);
  }
  template <class G>
  double refine(G& g, double a, double b, double fa, double fm, double fb, double whole, double tol, int depth) {
    double m = 0.5 * (a + b);
    double flm = g(0.5 * (a + m)), frm = g(0.5 * (m + b));
    double left = (m - a) / 6 * (fa + 4 * flm + fm), right = (b - m) / 6 * (fm + 4 * frm + fb);
    double delta = left + right - whole;
    // At least two levels, so that a peak between the first few points of a bin is not missed;
    // a budget keeps a pathological pdf from stalling the test.
    bool converged = depth >= 2 && std::abs(delta) <= 15 * tol;
    if (converged || depth >= max_depth_ || evaluations_ > kBudget) return left + right + delta / 15;
    return refine(g, a, m, fa, flm, fm, left, 0.5 * tol, depth + 1) +
           refine(g, m, b, fm, frm, fb, right, 0.5 * tol, depth + 1);
  }

  static constexpr long kBudget = 200000;  // pdf evaluations per bin
  std::function<double(double, double)> f_;
  int max_depth_;
  long evaluations_ = 0;
  double rel_ = 0;
};

std::string fmt(const char* f, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, a);
  return buf;
}

}  // namespace

double chi2_survival(double chi2, int dof) {
  if (dof <= 0) return 1;
  return gamma_q(0.5 * dof, 0.5 * chi2);
}

double sidak_alpha(double alpha, int tests) { return 1 - std::pow(1 - alpha, 1.0 / std::max(1, tests)); }

Chi2Result chi2_test(const DirectionSampler& sample, const DirectionPdf& pdf, const Chi2Options& o) {
  Chi2Result r;
  Binning bins{o.theta_bins, o.phi_bins, std::max(1.0, o.theta_power), Frame(normalize(o.pole))};
  const int nbins = bins.nt * bins.np;
  // LANTERN_CHI2_SAMPLE_DIVISOR=<d> draws samples / d (at least 10^4): the sanitizer run
  // (scripts/run_sanitizers.sh) looks for memory errors and undefined behaviour in the same
  // code, not for the test's full statistical power, which the Release suite keeps.
  uint64_t samples = o.samples;
  if (const char* env = o.keep_samples ? nullptr : std::getenv("LANTERN_CHI2_SAMPLE_DIVISOR")) {
    const uint64_t d = std::max(1ul, std::strtoul(env, nullptr, 10));
    samples = std::max<uint64_t>(std::min<uint64_t>(samples, 10000), samples / d);
  }
  const double n = double(samples);

  // 1. Histogram of samples, and the claimed pdf against the pdf adapter.
  std::vector<double> observed(nbins, 0.0);
  // LANTERN_CHI2_SEED=<k> reruns every test with other fixed seeds (to look at the spread of
  // p-values); the default is the seed the test chose.
  uint32_t seed = o.seed;
  if (const char* env = std::getenv("LANTERN_CHI2_SEED")) seed += uint32_t(std::strtoul(env, nullptr, 10)) * 7919u;
  Sampler rng(seed, 0x9e3779b9u, 0);
  for (uint64_t k = 0; k < samples; ++k) {
    DirectionSample s;
    if (!sample(rng, &s)) {
      ++r.failures;
      continue;
    }
    int b = bins.bin(s.dir);
    double len = length(s.dir);
    if (b < 0 || !is_finite(s.dir) || std::abs(len - 1) > 1e-3) {
      ++r.pdf_mismatches;  // a broken direction counts as a broken sample
      r.max_pdf_rel_error = INFINITY;
      continue;
    }
    observed[b] += 1;
    double p = pdf(s.dir);
    double err = std::abs(p - s.pdf) / std::max(std::abs(p), std::abs(s.pdf));
    if (!(p > 0) || !std::isfinite(p) || !std::isfinite(s.pdf) || !std::isfinite(err)) err = INFINITY;
    if (!(err <= o.pdf_rel_tolerance)) ++r.pdf_mismatches;
    r.max_pdf_rel_error = std::max(r.max_pdf_rel_error, err);
  }

  // 2. Expected counts: the pdf integrated over each bin in (v, phi), theta = pi v^power.
  std::vector<double> expected(nbins, 0.0);
  Integrator2D integrator(
      [&](double v, double phi) {
        double p = pdf(bins.direction(v, phi));
        if (!std::isfinite(p) || p < 0) p = 0;
        return p * std::sin(bins.theta(v)) * bins.dtheta_dv(v);
      },
      o.max_depth);
  const double tol = 1e-3 / n;  // absolute: each bin's expected count good to ~1e-3, the sum to ~1
  double integral = 0;
  for (int it = 0; it < bins.nt; ++it)
    for (int ip = 0; ip < bins.np; ++ip) {
      double v0 = double(it) / bins.nt, v1 = double(it + 1) / bins.nt;
      double p0 = -kPi + 2 * kPi * ip / bins.np, p1 = -kPi + 2 * kPi * (ip + 1) / bins.np;
      double m = std::max(0.0, integrator.integrate(v0, v1, p0, p1, tol, 1e-5));
      expected[it * bins.np + ip] = m * n;
      integral += m;
    }
  r.pdf_integral = integral;
  r.integral_ok = integral <= 1 + o.integral_tolerance &&
                  (o.expected_integral < 0 || std::abs(integral - o.expected_integral) <= o.integral_tolerance);

  // 3. The failure bin, 4. pooling and Pearson's statistic.
  observed.push_back(double(r.failures));
  expected.push_back(std::max(0.0, 1 - integral) * n);
  std::vector<int> order(observed.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return expected[a] < expected[b]; });
  std::vector<std::pair<double, double>> cells;  // (observed, expected)
  double pool_o = 0, pool_e = 0;
  for (int i : order) {
    // A bin the pdf gives no mass must stay empty. (The failure bin is exempt: a sampler may fail
    // on a measure-zero set, e.g. a cosine sample exactly on the horizon.)
    if (expected[i] == 0 && i != nbins) {
      r.zero_pdf_samples += uint64_t(observed[i]);
      continue;
    }
    pool_o += observed[i];
    pool_e += expected[i];
    if (pool_e >= o.min_expected) {
      cells.push_back({pool_o, pool_e});
      pool_o = pool_e = 0;
    }
  }
  if (pool_e > 0) {
    if (cells.empty())
      cells.push_back({pool_o, pool_e});
    else {
      cells.back().first += pool_o;
      cells.back().second += pool_e;
    }
  }
  for (auto& c : cells) r.chi2 += (c.first - c.second) * (c.first - c.second) / c.second;
  r.dof = int(cells.size()) - 1;
  r.p_value = chi2_survival(r.chi2, r.dof);
  r.alpha = sidak_alpha(o.significance, o.test_count);
  const double allowed = o.boundary_fraction * n;
  r.chi2_ok = r.dof > 0 && double(r.zero_pdf_samples) <= allowed && r.p_value >= r.alpha;
  r.pdf_ok = double(r.pdf_mismatches) <= allowed;

  r.summary = o.name + ": chi2 " + fmt("%.1f", r.chi2) + " dof " + std::to_string(r.dof) + " p " +
              fmt("%.3g", r.p_value) + " (alpha " + fmt("%.3g", r.alpha) + "), integral " +
              fmt("%.6f", r.pdf_integral) + ", failures " + std::to_string(r.failures) + ", zero-pdf samples " +
              std::to_string(r.zero_pdf_samples) + ", pdf mismatches " + std::to_string(r.pdf_mismatches) +
              " (max rel err " + fmt("%.3g", r.max_pdf_rel_error) + ")";

  // Optional dump for debugging a failure: LANTERN_CHI2_DUMP=<dir> writes observed/expected grids.
  if (const char* dir = std::getenv("LANTERN_CHI2_DUMP")) {
    std::ofstream f(std::string(dir) + "/" + o.name + ".txt");
    f << "# theta_bin phi_bin observed expected\n";
    for (int b = 0; b < nbins; ++b)
      f << b / bins.np << ' ' << b % bins.np << ' ' << observed[b] << ' ' << expected[b] << '\n';
    f << "# failures " << observed[nbins] << ' ' << expected[nbins] << '\n';
  }
  return r;
}

}  // namespace lt::test
