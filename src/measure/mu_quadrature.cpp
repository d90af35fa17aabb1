#include "microsim/measure/mu_quadrature.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "microsim/models/ndf.hpp"

namespace microsim {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Every other node (0, 2, 4, ...), and the last one when `keep_last`.
std::vector<std::size_t> every_other(std::size_t n, bool keep_last) {
  std::vector<std::size_t> s;
  for (std::size_t j = 0; j < n; j += 2) s.push_back(j);
  if (keep_last && s.back() != n - 1) s.push_back(n - 1);
  return s;
}

// Weights of 2 int_0^1 E mu dmu for E linear between the nodes `mu` (increasing) and constant
// beyond the outermost ones: segment [a, b] gives E_a (b - a)(b + 2a)/3 + E_b (b - a)(2b + a)/3;
// [0, mu_0] gives E_0 mu_0^2 and [mu_last, 1] gives E_last (1 - mu_last^2).
std::vector<double> piecewise_linear_weights(const std::vector<double>& mu) {
  const std::size_t n = mu.size();
  std::vector<double> w(n, 0.0);
  w[0] += mu[0] * mu[0];
  w[n - 1] += 1.0 - mu[n - 1] * mu[n - 1];
  for (std::size_t j = 0; j + 1 < n; ++j) {
    const double a = mu[j], b = mu[j + 1];
    w[j] += (b - a) * (b + 2 * a) / 3.0;
    w[j + 1] += (b - a) * (2 * b + a) / 3.0;
  }
  return w;
}

// Lagrange basis polynomial i of the nodes `x` at t.
double lagrange(const std::vector<double>& x, std::size_t i, double t) {
  double p = 1.0;
  for (std::size_t m = 0; m < x.size(); ++m)
    if (m != i) p *= (t - x[m]) / (x[i] - x[m]);
  return p;
}

}  // namespace

std::string MuQuadrature::description() const {
  const std::string n = std::to_string(mu.size());
  if (rule == "gauss-legendre")
    return n + "-point Gauss-Legendre rule in mu on [0, 1] (W_j = w_j mu_j); quadrature error: "
               "|Q - Q_low|, Q_low the interpolating polynomial of every other node integrated exactly";
  return "piecewise-linear E(mu) between the " + n +
         " nodes, constant beyond the outermost ones, integrated exactly against 2 mu; quadrature error: "
         "|Q - Q_low|, Q_low the same rule on every other node (outermost nodes kept)";
}

MuQuadrature gauss_legendre_mu(int nodes) {
  if (nodes < kMinMuNodes || nodes > kMaxMuNodes)
    throw ParameterError("{mu_nodes} must be in [" + std::to_string(kMinMuNodes) + ", " +
                         std::to_string(kMaxMuNodes) + "] (got " + std::to_string(nodes) + ")");
  MuQuadrature q;
  q.rule = "gauss-legendre";
  const auto rule = models::detail::gauss_legendre(nodes);  // increasing x on [-1, 1]
  for (const auto& [x, w] : rule) {
    q.mu.push_back(0.5 * (1.0 + x));
    q.weight.push_back(w * 0.5 * (1.0 + x));  // 2 * (w / 2) * mu
  }
  // The interpolating polynomial of the subset has degree < N: the N-point rule integrates it
  // (times 2 mu) exactly, so W'_i = sum_j W_j L_i(mu_j).
  const std::vector<std::size_t> sub = every_other(q.mu.size(), false);
  std::vector<double> x;
  for (std::size_t i : sub) x.push_back(q.mu[i]);
  q.low_weight.assign(q.mu.size(), 0.0);
  for (std::size_t i = 0; i < sub.size(); ++i)
    for (std::size_t j = 0; j < q.mu.size(); ++j) q.low_weight[sub[i]] += q.weight[j] * lagrange(x, i, q.mu[j]);
  q.has_low_rule = true;
  return q;
}

MuQuadrature trapezoid_mu(std::vector<double> mu) {
  if (mu.empty()) throw ParameterError("{theta_i}: no incidence angle given");
  for (double m : mu)
    if (!(m > 0.0 && m <= 1.0)) throw ParameterError("{theta_i} must be in [0, 90) degrees");
  std::sort(mu.begin(), mu.end());
  MuQuadrature q;
  q.rule = "trapezoid";
  q.mu = mu;
  q.weight = piecewise_linear_weights(mu);
  const std::vector<std::size_t> sub = every_other(mu.size(), true);
  q.low_weight.assign(mu.size(), 0.0);
  q.has_low_rule = sub.size() < mu.size();
  std::vector<double> x;
  for (std::size_t i : sub) x.push_back(mu[i]);
  const std::vector<double> w = piecewise_linear_weights(x);
  for (std::size_t i = 0; i < sub.size(); ++i) q.low_weight[sub[i]] = w[i];
  return q;
}

AlbedoAverage average_albedo(const MuQuadrature& q, const std::vector<Estimate>& e) {
  AlbedoAverage a;
  double var = 0, low = 0, var_diff = 0;
  for (std::size_t j = 0; j < q.mu.size(); ++j) {
    const double se2 = e[j].stderr_ * e[j].stderr_;
    a.value += q.weight[j] * e[j].mean;
    var += q.weight[j] * q.weight[j] * se2;
    low += q.low_weight[j] * e[j].mean;
    var_diff += (q.weight[j] - q.low_weight[j]) * (q.weight[j] - q.low_weight[j]) * se2;
  }
  a.stderr_ = std::sqrt(var);
  if (q.has_low_rule) {
    a.low_rule_value = low;
    a.quadrature_error = std::abs(a.value - low);
    a.quadrature_error_noise = std::sqrt(var_diff);
  } else {
    a.low_rule_value = a.quadrature_error = a.quadrature_error_noise = kNaN;
  }
  return a;
}

}  // namespace microsim
