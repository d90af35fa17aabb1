// Quadratures of the cosine-weighted hemispherical average E_avg = 2 int_0^1 E(mu) mu dmu on
// measured nodes mu_j, with the error of each (measure/albedo_measure.hpp measures E there).
//
// E_avg = sum_j W_j E(mu_j):
//  * gauss-legendre: the N-point Gauss-Legendre rule in mu on [0, 1], W_j = w_j mu_j (w_j the
//    rule's weights on [-1, 1]); exact when E is a polynomial of degree <= 2N - 2;
//  * trapezoid (given nodes): E linear in mu between the nodes and constant from the outermost
//    nodes to mu = 0 and mu = 1, integrated exactly against 2 mu.
// Statistical error: sqrt(sum_j W_j^2 se_j^2) (independent nodes). Quadrature error: the
// difference |Q - Q_low| from a lower-order rule on a subset of the same measured values
// (every other node; gauss-legendre: the interpolating polynomial of those nodes integrated
// exactly; trapezoid: the piecewise-linear rule on them, the outermost nodes kept). It is the
// error of the lower rule, so an overestimate of the higher rule's; its own noise,
// sqrt(sum_j (W_j - W'_j)^2 se_j^2), is reported beside it.
#pragma once
#include <string>
#include <vector>

#include "microsim/common.hpp"

namespace microsim {

// The Gauss-Legendre nodes a quadrature may have (the request's and the command line's range).
constexpr int kMinMuNodes = 2, kMaxMuNodes = 64;

// A quadrature of 2 int_0^1 E(mu) mu dmu on measured nodes, with a lower-order rule on a subset
// of them for the error estimate. Nodes increase in mu.
struct MuQuadrature {
  std::string rule;                 // "gauss-legendre" or "trapezoid"
  std::vector<double> mu;           // nodes
  std::vector<double> weight;       // W_j: E_avg = sum_j W_j E(mu_j)
  std::vector<double> low_weight;   // W'_j of the lower-order rule (0 on nodes it does not use)
  bool has_low_rule = false;        // false when the subset is every node (too few nodes)
  std::string description() const;  // the rule and its lower-order partner, in words
};
// The N-point Gauss-Legendre rule in mu on [0, 1] (N in [kMinMuNodes, kMaxMuNodes]).
MuQuadrature gauss_legendre_mu(int nodes);
// The piecewise-linear rule on the given nodes (sorted here; at least one, each in (0, 1]).
MuQuadrature trapezoid_mu(std::vector<double> mu);

// E_avg of values at the nodes, with its statistical and quadrature errors.
struct AlbedoAverage {
  double value = 0.0;
  double stderr_ = 0.0;            // sqrt(sum W_j^2 se_j^2)
  double quadrature_error = 0.0;   // |Q - Q_low|; NaN without a lower-order rule
  double quadrature_error_noise = 0.0;  // sqrt(sum (W_j - W'_j)^2 se_j^2); NaN likewise
  double low_rule_value = 0.0;
};
AlbedoAverage average_albedo(const MuQuadrature& q, const std::vector<Estimate>& e);

}  // namespace microsim
