// Small statistics shared by the estimators, the checks and their tests: the mean over K
// surfaces with its between-surface error, z-scores, the error floor of a proportion, two-sided
// z thresholds with a Sidak correction over many bins, the chi-square upper tail for
// goodness-of-fit tests, and Student's t (CDF, quantile, Sidak threshold) for means over K
// surfaces (K - 1 dof).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace microsim {

// Mean of K values and its standard error sd / sqrt(K), sd from the two-pass sum of squares
// about the mean (no cancellation); 0 for K < 2. The one place where an ensemble's mean and
// between-surface error are computed (measure tables and validate checks).
struct SampleMean {
  double mean = 0, stderr_ = 0;
  std::size_t n = 0;
};
inline SampleMean sample_mean(const std::vector<double>& x) {
  SampleMean m;
  m.n = x.size();
  if (x.empty()) return m;
  const double k = static_cast<double>(x.size());
  double sum = 0;
  for (double v : x) sum += v;
  m.mean = sum / k;
  double ss = 0;
  for (double v : x) ss += (v - m.mean) * (v - m.mean);
  m.stderr_ = x.size() > 1 ? std::sqrt(ss / (k - 1) / k) : 0.0;
  return m;
}

// Ray-count error of the mean of K independent estimates with errors se_k: sqrt(sum se_k^2) / K
// (K = se.size() unless given: estimates without an error count in K but add nothing).
inline double mean_of_errors(const std::vector<double>& se, std::size_t k = 0) {
  if (k == 0) k = se.size();
  double s2 = 0;
  for (double e : se) s2 += e * e;
  return k == 0 ? 0.0 : std::sqrt(s2) / static_cast<double>(k);
}

// z-score (measured - model) / stderr. A zero error gives 0 when measured equals the model (to
// 1e-12 relative) and an infinite z of the difference's sign otherwise (written as null in JSON).
inline double z_score(double measured, double model, double stderr_) {
  const double diff = measured - model;
  if (stderr_ > 0) return diff / stderr_;
  if (std::abs(diff) <= 1e-12 * std::max(1.0, std::abs(model))) return 0.0;
  return std::copysign(std::numeric_limits<double>::infinity(), diff);
}

// Relative deviation (measured - model) / |model| (0 when both are 0, infinite for model 0).
inline double rel_dev(double measured, double model) {
  if (model != 0) return (measured - model) / std::abs(model);
  return measured == 0 ? 0.0 : std::copysign(std::numeric_limits<double>::infinity(), measured);
}

// Error floor of a proportion measured from n samples: a proportion at 0 or 1 has no spread but
// is known only to the resolution of n samples, taken as the binomial error of the estimate
// (k + 1/2) / (n + 1) at k = n: sqrt(p (1 - p) / n) with p = (n + 1/2) / (n + 1), about
// 0.71 / n. Used wherever an error enters a z or a chi-square (measure and validate alike), so
// that a proportion at 0 or 1 compared with a model is not an infinite z.
inline double proportion_floor(std::uint64_t n) {
  if (n == 0) return 0.0;
  const double nd = static_cast<double>(n);
  const double p = (nd + 0.5) / (nd + 1.0);
  return std::sqrt(p * (1 - p) / nd);
}

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

// Regularized incomplete beta I_x(a, b) = B(x; a, b) / B(a, b), a, b > 0, x in [0, 1]:
// the continued fraction of I_x (modified Lentz), with I_x(a, b) = 1 - I_{1-x}(b, a) used
// where x > (a + 1) / (a + b + 2) so that the fraction converges fast.
inline double incomplete_beta(double a, double b, double x) {
  if (!(a > 0) || !(b > 0) || !(x >= 0 && x <= 1)) return std::numeric_limits<double>::quiet_NaN();
  if (x == 0 || x == 1) return x;
  if (x > (a + 1) / (a + b + 2)) return 1.0 - incomplete_beta(b, a, 1.0 - x);
  const double log_prefix = a * std::log(x) + b * std::log1p(-x) - std::log(a) + std::lgamma(a + b) -
                            std::lgamma(a) - std::lgamma(b);
  // I_x = prefix / (1 + d1 / (1 + d2 / (1 + ...))), d_{2m+1} = -(a+m)(a+b+m) x / ((a+2m)(a+2m+1)),
  // d_{2m} = m (b-m) x / ((a+2m-1)(a+2m)).
  const double tiny = 1e-300;
  double c = 1, d = 1 - (a + b) * x / (a + 1);
  if (std::abs(d) < tiny) d = tiny;
  d = 1 / d;
  double h = d;
  for (int m = 1; m < 100000; ++m) {
    const double even = m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m));
    d = 1 + even * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1 + even / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    h *= d * c;
    const double odd = -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1));
    d = 1 + odd * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1 + odd / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < 1e-16) break;
  }
  return std::exp(log_prefix) * h;
}

// Two-sided tail P(|T| >= |t|) of Student's t with `dof` degrees of freedom:
// I_{dof / (dof + t^2)}(dof / 2, 1 / 2).
inline double student_t_two_sided_p(double t, double dof) {
  if (!(dof > 0)) return std::numeric_limits<double>::quiet_NaN();
  if (std::isinf(t)) return 0.0;
  return incomplete_beta(0.5 * dof, 0.5, dof / (dof + t * t));
}

// CDF P(T <= t) of Student's t with `dof` degrees of freedom.
inline double student_t_cdf(double t, double dof) {
  const double half_tail = 0.5 * student_t_two_sided_p(t, dof);
  return t >= 0 ? 1.0 - half_tail : half_tail;
}

// Quantile: the t with P(T <= t) = p, p in (0, 1). Bisection on x = dof / (dof + t^2), where the
// two-sided tail I_x(dof/2, 1/2) is monotone, so that far tails (t ~ 1e8 for dof 1) are exact too.
inline double student_t_quantile(double p, double dof) {
  if (!(p > 0 && p < 1) || !(dof > 0)) return std::numeric_limits<double>::quiet_NaN();
  if (p == 0.5) return 0.0;
  const double tail = 2 * std::min(p, 1 - p);  // two-sided tail of |t|
  double lo = 0, hi = 1;                       // I_x is 0 at x = 0 and 1 at x = 1
  for (int i = 0; i < 1100 && hi > lo; ++i) {
    const double x = 0.5 * (lo + hi);
    if (x == lo || x == hi) break;
    if (incomplete_beta(0.5 * dof, 0.5, x) < tail) lo = x; else hi = x;
  }
  const double x = 0.5 * (lo + hi);
  const double t = std::sqrt(dof * (1 - x) / x);
  return p > 0.5 ? t : -t;
}

// Two-sided Student t threshold with a Sidak correction: |t| above it has probability `alpha`
// that any of `k` independent null comparisons, each with `dof` degrees of freedom, crosses it.
// Tends to sidak_z as dof grows.
inline double sidak_t(double alpha, int k, double dof) {
  if (k < 1) k = 1;
  const double per = -std::expm1(std::log1p(-alpha) / k);
  return student_t_quantile(1 - 0.5 * per, dof);
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
