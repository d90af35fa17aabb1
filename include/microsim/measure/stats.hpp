// Small statistics shared by the estimators and their tests: two-sided z thresholds with a
// Sidak correction over many bins, and the chi-square upper tail for goodness-of-fit tests.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

namespace microsim {

// Two-sided z threshold with a Sidak correction: family-wise false-alarm rate `alpha` over
// `k` independent comparisons, i.e. Phi^-1(1 - a/2) with a = 1 - (1 - alpha)^(1/k).
// Solved by bisection on erfc (monotone).
inline double sidak_z(double alpha, int k) {
  if (k < 1) k = 1;
  const double per = -std::expm1(std::log1p(-alpha) / k);  // 1 - (1-alpha)^(1/k), no cancellation
  double lo = 0, hi = 40;
  for (int i = 0; i < 200; ++i) {
    const double z = 0.5 * (lo + hi);
    if (std::erfc(z / std::sqrt(2.0)) > per) lo = z; else hi = z;
  }
  return 0.5 * (lo + hi);
}

// Regularized upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a): power series of P for
// x < a + 1, Lentz continued fraction for Q otherwise (both converge fast in their range).
inline double gamma_q(double a, double x) {
  if (!(a > 0) || !(x >= 0)) return std::numeric_limits<double>::quiet_NaN();
  if (x == 0) return 1.0;
  const double log_prefix = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 100000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-16) break;
    }
    return std::max(0.0, 1.0 - sum * std::exp(log_prefix));
  }
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int n = 1; n < 100000; ++n) {
    const double an = -n * (n - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < 1e-16) break;
  }
  return std::exp(log_prefix) * h;
}

// P(X >= chi2) for X chi-square distributed with `dof` degrees of freedom.
inline double chi2_p_value(double chi2, int dof) {
  if (dof <= 0) return 1.0;
  return gamma_q(0.5 * dof, 0.5 * std::max(0.0, chi2));
}

// Quantile of the chi-square distribution: the x with P(X <= x) = p for `dof` degrees of
// freedom (0 < p < 1), by bisection on the regularized incomplete gamma (monotone in x).
inline double chi2_quantile(double p, int dof) {
  if (!(p > 0 && p < 1) || dof <= 0) return std::numeric_limits<double>::quiet_NaN();
  double lo = 0, hi = dof + 10.0 * std::sqrt(2.0 * dof) + 50;
  while (1 - gamma_q(0.5 * dof, 0.5 * hi) < p) hi *= 2;
  for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i) {
    const double x = 0.5 * (lo + hi);
    if (1 - gamma_q(0.5 * dof, 0.5 * x) < p) lo = x; else hi = x;
  }
  return 0.5 * (lo + hi);
}

// Two-sided interval of a sample-to-reference standard deviation ratio s / sigma from `dof`
// degrees of freedom at confidence 1 - alpha: (dof s^2 / sigma^2 is chi-square with dof).
struct RatioInterval {
  double lo = 0, hi = 0;
  bool contains(double ratio) const { return ratio >= lo && ratio <= hi; }
};
inline RatioInterval sd_ratio_interval(int dof, double alpha) {
  return {std::sqrt(chi2_quantile(0.5 * alpha, dof) / dof),
          std::sqrt(chi2_quantile(1 - 0.5 * alpha, dof) / dof)};
}

}  // namespace microsim
