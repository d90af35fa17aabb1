// Direction bins on the sphere (or hemisphere): uniform in theta and phi.
#pragma once
#include <vector>

#include "microsim/common.hpp"

namespace microsim {

class DirectionBinning {
 public:
  // theta in [0, theta_max] (pi for the whole sphere), phi in [0, 2 pi).
  DirectionBinning(int n_theta, int n_phi, double theta_max);
  int n_theta() const { return n_theta_; }
  int n_phi() const { return n_phi_; }
  int size() const { return n_theta_ * n_phi_; }  // the constructor keeps this below 2^31
  // Bin index, or -1 when theta > theta_max or the direction is not finite.
  int bin_of(const Vec3& unit_dir) const;
  int index(int it, int ip) const { return it * n_phi_ + ip; }
  double theta_lo(int it) const { return it * d_theta_; }
  double theta_hi(int it) const { return (it + 1) * d_theta_; }
  double phi_lo(int ip) const { return ip * d_phi_; }
  double phi_hi(int ip) const { return (ip + 1) * d_phi_; }
  // Exact solid angle of a bin: (cos theta_lo - cos theta_hi) * d_phi.
  double solid_angle(int bin) const;
  double solid_angle_of_ring(int it) const { return solid_angle(index(it, 0)) * n_phi_; }
  // Average of f over the bin's solid angle (Gauss-Legendre in cos theta and phi).
  template <class F>
  double bin_average(int bin, F&& f) const;

 private:
  int n_theta_, n_phi_;
  double theta_max_, d_theta_, d_phi_;
};

// 8-point Gauss-Legendre nodes and weights on [-1, 1].
extern const double kGauss8Nodes[8];
extern const double kGauss8Weights[8];

template <class F>
double DirectionBinning::bin_average(int bin, F&& f) const {
  int it = bin / n_phi_, ip = bin % n_phi_;
  double c0 = std::cos(theta_lo(it)), c1 = std::cos(theta_hi(it));
  double p0 = phi_lo(ip), p1 = phi_hi(ip);
  double sum = 0;
  for (int a = 0; a < 8; ++a) {
    double c = 0.5 * (c0 + c1) + 0.5 * (c0 - c1) * kGauss8Nodes[a];
    double s = std::sqrt(std::max(0.0, 1 - c * c));
    for (int b = 0; b < 8; ++b) {
      double p = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * kGauss8Nodes[b];
      sum += 0.25 * kGauss8Weights[a] * kGauss8Weights[b] *
             f(Vec3(s * std::cos(p), s * std::sin(p), c));
    }
  }
  return sum;
}

}  // namespace microsim
