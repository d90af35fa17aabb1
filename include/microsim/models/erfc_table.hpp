// erfc(x) and exp(-x^2) together, without calling either, for the Smith walk's Beckmann Lambda and slope CDF
// (models/smith_random_walk.hpp, beckmann_slope_sampler.hpp), which evaluate both at every event.
//   * A table holds erfc and exp(-x^2) at the nodes x_k = k h (h = 1/256, |x_k| <= 6), computed once by
//     std::erfc and std::exp.
//   * From the nearest node (s = x - x_k, |s| <= h/2):
//       exp(-x^2) = exp(-x_k^2) exp(t),  t = -(2 x_k + s) s  (|t| <= 0.024: Taylor to t^7, error < 3e-18);
//       erfc(x) = erfc(x_k) - 2/sqrt(pi) exp(-x_k^2) int_0^s exp(-2 x_k r - r^2) dr,
//     the integrand's Taylor coefficients c_n from (n + 1) c_{n+1} = -2 x_k c_n - 2 c_{n-1}, c_0 = 1,
//     c_1 = -2 x_k (it solves f' = -(2 x_k + 2 r) f; c_n = (-1)^n H_n(x_k) / n!), |c_n s^n| <~ (2 |x_k| s)^n / n!,
//     to n = 8 (error < 1e-19 of the integral). The correction is at most 2 |x_k| s ~ 3% of erfc(x_k) for
//     x_k > 0 (no cancellation): both values to a few ulp of their own size.
//   * |x| > 6 (or not finite): std::erfc and std::exp.
// The tests compare both with std::erfc and std::exp to 1e-14 relative over the range and beyond
// (tests/test_erfc_table.cpp).
#pragma once

#include <cmath>
#include <vector>

namespace microsim::models::detail {

struct ErfcGauss {
  double erfc;   // erfc(x)
  double gauss;  // exp(-x^2)
};

class ErfcGaussTable {
 public:
  static constexpr int kPerUnit = 256;  // nodes per unit of x
  static constexpr double kReach = 6.0;
  static constexpr int kHalf = static_cast<int>(kReach) * kPerUnit;  // nodes -kHalf .. kHalf

  static const ErfcGaussTable& instance() {
    static const ErfcGaussTable t;
    return t;
  }

  ErfcGauss operator()(double x) const {
    if (!(std::abs(x) <= kReach)) return {std::erfc(x), std::exp(-x * x)};
    const double y = x * kPerUnit;
    const int k = static_cast<int>(y + (y >= 0.0 ? 0.5 : -0.5));  // the nearest node
    const double xk = k * (1.0 / kPerUnit), s = x - xk;
    const ErfcGauss& n = nodes_[static_cast<std::size_t>(k + kHalf)];
    const double t = -(2.0 * xk + s) * s;
    // exp(t), Taylor to t^7 (Horner)
    const double et =
        1.0 + t * (1.0 + t * (0.5 + t * (1.0 / 6 + t * (1.0 / 24 + t * (1.0 / 120 + t * (1.0 / 720 + t * (1.0 / 5040)))))));
    // int_0^s exp(-2 x_k r - r^2) dr = sum_n c_n s^(n+1) / (n + 1)
    const double a = -2.0 * xk;
    double cm = 1.0, c = a * s;  // c_n s^n for n = 0, 1
    double sum = cm + c * 0.5;
    for (int m = 1; m < 8; ++m) {
      const double next = (a * s * c - 2.0 * s * s * cm) * kInverse[m + 1];  // c_{m+1} s^(m+1)
      cm = c;
      c = next;
      sum += c * kInverse[m + 2];
    }
    constexpr double k2OverSqrtPi = 1.12837916709551257390;
    return {n.erfc - k2OverSqrtPi * n.gauss * s * sum, n.gauss * et};
  }

 private:
  static constexpr double kInverse[12] = {0.0,         1.0,         1.0 / 2, 1.0 / 3, 1.0 / 4,  1.0 / 5,
                                          1.0 / 6,     1.0 / 7,     1.0 / 8, 1.0 / 9, 1.0 / 10, 1.0 / 11};
  ErfcGaussTable() : nodes_(static_cast<std::size_t>(2 * kHalf + 1)) {
    for (int k = -kHalf; k <= kHalf; ++k) {
      const double x = k * (1.0 / kPerUnit);
      nodes_[static_cast<std::size_t>(k + kHalf)] = {std::erfc(x), std::exp(-x * x)};
    }
  }
  std::vector<ErfcGauss> nodes_;
};

// erfc(x) and exp(-x^2) of ErfcGaussTable (see the top of this file).
inline ErfcGauss erfc_gauss(double x) { return ErfcGaussTable::instance()(x); }

}  // namespace microsim::models::detail
