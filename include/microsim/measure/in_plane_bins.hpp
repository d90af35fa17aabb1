// The in-plane bins of the BSDF tallies (measure/bsdf_measure.hpp): a narrow band around the plane
// of incidence. Defined in src/measure/bsdf_measure.cpp.
#pragma once
#include <functional>

#include "microsim/common.hpp"

namespace microsim {

// A narrow band around the plane of incidence, cut into bins of signed polar angle.
// A direction d (either hemisphere; the lower one measured from -n) is written
// d = cos(beta) (sin(psi) s + cos(psi) n') + sin(beta) p, with n' = +-z toward d's side, s the
// horizontal unit vector toward azimuth phi_i + pi (the specular side: psi > 0) and p = n x s.
// Bin b: psi in [-90 + b w, -90 + (b + 1) w] degrees, w = 180 / n_bins, |beta| <= w / 2.
// Exact: int_bin |cos theta| d omega = (delta + sin(delta) cos(delta)) (sin psi1 - sin psi0),
// delta = w / 2 (|cos theta| = cos(beta) cos(psi), d omega = cos(beta) d beta d psi).
class InPlaneBins {
 public:
  InPlaneBins(double phi_i, int n_bins);
  int size() const { return n_; }
  // -1 outside the band. Exactly bin_of_exact(d): a direction clearly outside the band (by more
  // than band_margin in sin(beta), far beyond the rounding of normalising d) is decided without
  // normalising it; the others (inside the band: a few percent of directions) by bin_of_exact.
  int bin_of(const Vec3& d) const { return bin_of(d, kBandMargin); }
  int bin_of(const Vec3& d, double band_margin) const;
  int bin_of_exact(const Vec3& d) const;
  static constexpr double kBandMargin = 1e-12;
  double psi_lo(int b) const { return -0.5 * kPi + b * width_; }
  double psi_hi(int b) const { return -0.5 * kPi + (b + 1) * width_; }
  double psi_center(int b) const { return -0.5 * kPi + (b + 0.5) * width_; }
  double half_width() const { return delta_; }
  double cos_integral(int b) const;
  // Direction at (psi, beta) on the upper (above = true) or lower side.
  Vec3 direction(double psi, double beta, bool above) const;
  // Average of f over the bin weighted by |cos theta| (6 x 6 Gauss-Legendre in (psi, beta)).
  double cos_weighted_average(int b, bool above, const std::function<double(const Vec3&)>& f) const;

 private:
  int n_;
  double width_, delta_;
  double sin_delta_;  // sin(delta_), compared with every direction binned
  Vec3 s_, p_;
};

}  // namespace microsim
