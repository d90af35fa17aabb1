// The estimates of a VNDF result (measure/vndf_result.hpp).
#include "microsim/measure/vndf_result.hpp"

namespace microsim {

DirectionBinning vndf_binning(const VndfOptions& o) {
  return DirectionBinning(o.theta_bins, o.phi_bins, kPi / 2);
}

Estimate VndfResult::dv(int b) const {
  Estimate p = binomial_estimate(bin_hits[b], hits);
  const double w = binning.solid_angle(b);
  return {p.mean / w, p.stderr_ / w, bin_hits[b]};
}

double VndfResult::dv_smith_numeric(int b) const {
  return front_projected[b] / front_projected_total / binning.solid_angle(b);
}

std::vector<double> VndfResult::smith_numeric_probabilities() const {
  std::vector<double> p(binning.size());
  for (int b = 0; b < binning.size(); ++b) p[b] = front_projected[b] / front_projected_total;
  return p;
}

}  // namespace microsim
