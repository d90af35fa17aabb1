// The four Smith joint masking-shadowing forms [Heitz14, Sec. 5] written in terms of the two Smith
// Lambda values, so that they can be evaluated with any Lambda: the closed forms of an NDF, or
// Lambda computed from a surface's own facets (docs/theory/masking.md,
// "Smith from the facets' own Lambda"). models/ndf.hpp has the same forms for an Ndf; tests/test_g2.cpp checks that both
// agree. Also the Smith Lambda of a non-centered (vertically sheared) slope distribution
// [Heitz14, Sec. 3.4].
//
// Header-only, Eigen only. Conventions as in models/ndf.hpp (n = +z, directions away from the
// surface, radians).
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include "microsim/models/ndf.hpp"

namespace microsim::models {

// Values of the four forms for directions o, i that both face the facet (the chi+(o.m)
// chi+(i.m) factor is the caller's). lambda_o, lambda_i >= 0; phi = azimuth difference in
// [0, pi] (models::azimuth_difference).
struct G2Forms {
  double separable = 0;                    // [Heitz14, eq. 20]
  double height_correlated = 0;            // [Heitz14, eq. 21]
  double direction_correlated = 0;         // [Heitz14, eq. 22]
  double height_direction_correlated = 0;  // [Heitz14, eq. 23]
};

inline G2Forms g2_forms_from_lambda(double lambda_o, double lambda_i, double phi) {
  G2Forms f;
  if (std::isinf(lambda_o) || std::isinf(lambda_i)) return f;  // a direction at/below horizon
  // (lambda slightly below 0 is accepted: g2_forms_from_g1 differentiates at G1 = 1.)
  const double go = 1.0 / (1.0 + lambda_o), gi = 1.0 / (1.0 + lambda_i);  // [Heitz14, eq. 10]
  const double l = van_ginneken_lambda(phi);  // [Heitz14, Sec. 5]: 4.41 phi / (4.41 phi + 1)
  f.separable = go * gi;                                   // [Heitz14, eq. 20]
  f.height_correlated = 1.0 / (1.0 + lambda_o + lambda_i);  // [Heitz14, eq. 21]
  f.direction_correlated = l * go * gi + (1.0 - l) * std::min(go, gi);  // [Heitz14, eq. 22]
  f.height_direction_correlated =
      1.0 / (1.0 + std::max(lambda_o, lambda_i) + l * std::min(lambda_o, lambda_i));  // eq. (23)
  return f;
}

// The same four forms built from given masking values G1(o) and G1(i) instead of Lambda, through
// [Heitz14, eq. 10] inverted, Lambda = 1/G1 - 1. With the measured G1 of a set of facets this isolates
// what the forms assume about the correlation of the two visibilities from the masking
// magnitude itself. g1 <= 0 gives 0 (fully masked).
inline G2Forms g2_forms_from_g1(double g1_o, double g1_i, double phi) {
  if (!(g1_o > 0) || !(g1_i > 0)) return G2Forms{};
  return g2_forms_from_lambda(1.0 / g1_o - 1.0, 1.0 / g1_i - 1.0, phi);
}

// [Heitz14, Sec. 3.4] "Vertical Shearing and Non-Centered Distributions": a surface whose slopes are
// centered on (mean_slope_x, mean_slope_y) (slopes -m_x/m_z, -m_y/m_z as in [Heitz14, App. A]) masks
// like the centered one with every slope offset, the view's included:
//   a = (cot(theta_o) - (cos(phi_o) xbar + sin(phi_o) ybar)) / alpha_o,
// i.e. (v_z - xbar v_x - ybar v_y) / |(alpha_x v_x, alpha_y v_y)|: the centered a of the
// unsheared view (v_x, v_y, v_z - xbar v_x - ybar v_y). +inf when the view is at or below the
// mesosurface. (Lambda is then normalized by the mesosurface's projected area: the masking
// G1 = 1 / (1 + Lambda) relates visible projected area to A_meso (v . n_meso), [Heitz14, Sec. 3.4].)
inline double Lambda_offset_slopes(const Ndf& ndf, const Vec3& v, double mean_slope_x,
                                   double mean_slope_y) {
  const Vec3 unsheared(v.x(), v.y(), v.z() - mean_slope_x * v.x() - mean_slope_y * v.y());
  return ndf.Lambda(unsheared);
}

}  // namespace microsim::models
