// A faster twin of detail::beckmann_visible_slope_quantile (ndf.hpp) for the Smith random walk, which
// inverts the visible-slope CDF at every scattering event. The same function to ~1e-14:
//   * mu = +inf (the plain Gaussian slope, density exp(-x^2)/sqrt(pi)): x = Phi^-1(u) / sqrt(2) with
//     Phi^-1 from Wichura's algorithm AS 241 (PPND16, relative error ~1e-16; no iteration, no erfc).
//   * finite mu: a start from a table of x over (theta' = acot(mu), z = Phi^-1(u)), bilinear
//     (error ~1e-3), then Halley's iteration on the closed-form CDF (cubic convergence: the error is at
//     rounding after two steps) inside the bracket [lo, hi] the iteration keeps;
//     outside the table, or when the iteration does not settle in a few steps, the exact function.
// The tests compare both with the exact function over mu and u (tests/test_beckmann_slope_sampler.cpp).
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "microsim/models/ndf.hpp"

namespace microsim::models::detail {

// The standard normal quantile Phi^-1(p), p in (0, 1): Wichura, "Algorithm AS 241: The percentage points
// of the normal distribution", Applied Statistics 37 (1988) 477-484, PPND16.
inline double normal_quantile_as241(double p) {
  if (!(p > 0.0)) return -kInf;
  if (!(p < 1.0)) return kInf;
  const double q = p - 0.5;
  if (std::abs(q) <= 0.425) {
    const double r = 0.180625 - q * q;
    return q *
           (((((((r * 2509.0809287301226727 + 33430.575583588128105) * r + 67265.770927008700853) * r +
                45921.953931549871457) * r + 13731.693765509461125) * r + 1971.5909503065514427) * r +
             133.14166789178437745) * r + 3.387132872796366608) /
           (((((((r * 5226.495278852545925 + 28729.085735721942674) * r + 39307.89580009271061) * r +
                21213.794301586595867) * r + 5394.1960214247511077) * r + 687.1870074920579083) * r +
             42.313330701600911252) * r + 1.0);
  }
  double r = q < 0.0 ? p : 1.0 - p;
  r = std::sqrt(-std::log(r));
  double x;
  if (r <= 5.0) {
    r -= 1.6;
    x = (((((((r * 7.7454501427834140764e-4 + 0.0227238449892691845833) * r + 0.24178072517745061177) * r +
              1.27045825245236838258) * r + 3.64784832476320460504) * r + 5.7694972214606914055) * r +
           4.6303378461565452959) * r + 1.42343711074968357734) /
        (((((((r * 1.05075007164441684324e-9 + 5.475938084995344946e-4) * r + 0.0151986665636164571966) * r +
              0.14810397642748007459) * r + 0.68976733498510000455) * r + 1.6763848301838038494) * r +
           2.05319162663775882187) * r + 1.0);
  } else {
    r -= 5.0;
    x = (((((((r * 2.01033439929228813265e-7 + 2.71155556874348757815e-5) * r + 0.0012426609473880784386) * r +
              0.026532189526576123093) * r + 0.29656057182850489123) * r + 1.7848265399172913358) * r +
           5.4637849111641143699) * r + 6.6579046435011037772) /
        (((((((r * 2.04426310338993978564e-15 + 1.4215117583164458887e-7) * r + 1.8463183175100546818e-5) * r +
              7.868691311456132591e-4) * r + 0.0148753612908506148525) * r + 0.13692988092273580531) * r +
           0.59983220655588793769) * r + 1.0);
  }
  return q < 0.0 ? -x : x;
}

// The table of starts: x(theta', z) at kRows x kCols nodes, theta' = acot(mu) in [kTheta0, kTheta1] (mu from
// +36 to -3.2: the views the walk samples from; beyond, the exact function), z in [-kZ, kZ].
class BeckmannSlopeStarts {
 public:
  static constexpr int kRows = 96, kCols = 96;
  static constexpr double kTheta0 = 0.028, kTheta1 = 2.84, kZ = 7.5;

  static const BeckmannSlopeStarts& instance() {
    static const BeckmannSlopeStarts t;
    return t;
  }
  // The bilinear start at (theta', z); false outside the table.
  bool start(double theta, double z, double* x) const {
    const double a = (theta - kTheta0) / dtheta_, b = (z + kZ) / dz_;
    if (!(a >= 0.0 && a < kRows - 1 && b >= 0.0 && b < kCols - 1)) return false;
    const int i = static_cast<int>(a), j = static_cast<int>(b);
    const double fa = a - i, fb = b - j;
    const double* r0 = &x_[static_cast<std::size_t>(i) * kCols + j];
    const double* r1 = r0 + kCols;
    *x = (1.0 - fa) * ((1.0 - fb) * r0[0] + fb * r0[1]) + fa * ((1.0 - fb) * r1[0] + fb * r1[1]);
    return true;
  }

 private:
  BeckmannSlopeStarts() : x_(static_cast<std::size_t>(kRows) * kCols) {
    dtheta_ = (kTheta1 - kTheta0) / (kRows - 1);
    dz_ = 2.0 * kZ / (kCols - 1);
    for (int i = 0; i < kRows; ++i) {
      const double theta = kTheta0 + i * dtheta_, mu = std::cos(theta) / std::sin(theta);
      for (int j = 0; j < kCols; ++j) {
        const double z = -kZ + j * dz_;
        const double u = 0.5 * std::erfc(-z / std::sqrt(2.0));
        x_[static_cast<std::size_t>(i) * kCols + j] = beckmann_visible_slope_quantile(mu, std::max(u, 1e-300));
      }
    }
  }
  std::vector<double> x_;
  double dtheta_ = 0.0, dz_ = 0.0;
};

// detail::beckmann_visible_slope_quantile(mu, u) to ~1e-14, faster (see the top of this file). `norm`: the
// CDF's normalization mu erfc(-mu)/2 + exp(-mu^2)/(2 sqrt(pi)) where the caller knows it (= mu (1 + Lambda)
// of the view; NaN: computed here). *cdf_evaluations (optional): the CDF evaluations of Halley's iteration,
// -1 where the exact function gave the result.
inline double fast_beckmann_visible_slope_quantile(double mu, double u,
                                                   double norm = std::numeric_limits<double>::quiet_NaN(),
                                                   int* cdf_evaluations = nullptr) {
  int evaluations = 0;
  auto exact = [&]() {
    if (cdf_evaluations) *cdf_evaluations = -1;
    return beckmann_visible_slope_quantile(mu, u);
  };
  auto converged = [&](double x) {
    if (cdf_evaluations) *cdf_evaluations = evaluations;
    return x;
  };
  if (std::isinf(mu) && mu > 0.0) return converged(normal_quantile_as241(u) / std::sqrt(2.0));
  const double z = normal_quantile_as241(u);
  double x;
  const double theta = std::atan2(1.0, mu);  // acot(mu) in (0, pi)
  if (!BeckmannSlopeStarts::instance().start(theta, z, &x)) return exact();
  // C(x) = [mu erfc(-x)/2 + exp(-x^2)/(2 sqrt(pi))] / N, C' = (mu - x) exp(-x^2) / (sqrt(pi) N),
  // C'' = (-1 - 2 x (mu - x)) exp(-x^2) / (sqrt(pi) N); N = C's numerator at x = mu.
  if (!(norm > 0.0 && std::isfinite(norm))) norm = mu * 0.5 * std::erfc(-mu) + std::exp(-mu * mu) / (2.0 * kSqrtPi);
  if (!(norm > 0.0)) return exact();
  // A start at or beyond mu (the density's end, where it vanishes) gives Halley no slope: the exact function.
  if (!(x < mu)) return exact();
  double lo = -kInf, hi = mu;
  for (int it = 0; it < 10; ++it) {
    ++evaluations;
    const double e = std::exp(-x * x);
    const double f = (mu * 0.5 * std::erfc(-x) + e / (2.0 * kSqrtPi)) / norm - u;
    if (f == 0.0) return converged(x);
    if (f < 0.0) lo = x; else hi = x;
    const double d1 = (mu - x) * e / (kSqrtPi * norm);
    if (!(d1 > 0.0)) return exact();
    const double d2 = (-1.0 - 2.0 * x * (mu - x)) * e / (kSqrtPi * norm);
    const double den = 2.0 * d1 * d1 - f * d2;
    double xn = den != 0.0 ? x - 2.0 * f * d1 / den : x - f / d1;
    // Halley left the bracket: bisect (and do not stop on that step). The bracket is closed: at rounding the
    // step is 0 and x itself is an end of the bracket.
    if (!(xn >= lo && xn <= hi)) {
      if (!(std::isfinite(lo))) return exact();
      x = 0.5 * (lo + hi);
      continue;
    }
    const double step = std::abs(xn - x);
    x = xn;
    // cubic convergence: a step s from x lands within ~K s^3 of the root, K ~ (f''/f')^2 = (2 x + 1 / (mu - x))^2:
    // at rounding for s <= 1e-6 min(1, mu - x); from a start ~1e-3 off that is the second step
    if (step <= 1e-6 * std::min(1.0, mu - x)) return converged(x);
  }
  return exact();
}

}  // namespace microsim::models::detail
