#include "microsim/measure/binning.hpp"

namespace microsim {

const double kGauss8Nodes[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                                -0.1834346424956498, 0.1834346424956498,  0.5255324099163290,
                                0.7966664774136267,  0.9602898564975363};
const double kGauss8Weights[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                                  0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                                  0.2223810344533745, 0.1012285362903763};

DirectionBinning::DirectionBinning(int n_theta, int n_phi, double theta_max)
    : n_theta_(n_theta), n_phi_(n_phi), theta_max_(theta_max),
      d_theta_(theta_max / n_theta), d_phi_(2 * kPi / n_phi) {
  // Counts that overflow n_theta * n_phi (or no bins at all) are a caller's error.
  if (n_theta < 1 || n_phi < 1 || static_cast<long long>(n_theta) * n_phi > (1LL << 30) ||
      !(theta_max > 0 && theta_max <= kPi))
    throw UsageError("direction binning: need 1 <= bins, n_theta x n_phi <= 2^30, theta_max in (0, pi]");
}

int DirectionBinning::bin_of(const Vec3& d) const {
  if (!d.allFinite()) return -1;  // a NaN normal (degenerate input) has no bin
  double t = theta_of(d);
  if (!(t <= theta_max_)) return -1;
  int it = std::min(n_theta_ - 1, static_cast<int>(t / d_theta_));
  int ip = std::min(n_phi_ - 1, static_cast<int>(phi_of(d) / d_phi_));
  return index(it, ip);
}

double DirectionBinning::solid_angle(int bin) const {
  int it = bin / n_phi_;
  return (std::cos(theta_lo(it)) - std::cos(theta_hi(it))) * d_phi_;
}

}  // namespace microsim
