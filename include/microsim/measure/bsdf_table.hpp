// BSDF tables: the random-walk BSDF (measure/bsdf_measure.hpp) at every incidence of a grid of
// zenith angles theta_i and azimuths phi_i, sharing one scene (Tracer). The tables that
// renderers load (io/rgl_bsdf.hpp, io/merl.hpp) are built from this.
//
// Incidence k runs the single-incidence estimator with the same options and seed; each incidence
// draws from its own counter stream (keyed by its angles), so incidences are independent and a
// table's entry equals the single-incidence run at that angle.
#pragma once
#include <functional>
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"

namespace microsim {

struct BsdfTableOptions {
  BsdfOptions base;             // material, orders, rays, seed, resolution, model walks
  std::vector<double> theta_i;  // radians, each in [0, pi/2)
  std::vector<double> phi_i;    // radians
  // Fraction of the whole table done (called from the calling thread).
  std::function<void(double)> progress;
};

struct BsdfTable {
  std::vector<double> theta_i, phi_i;  // radians
  std::vector<BsdfResult> results;     // incidence (p, t) at index p * theta_i.size() + t
  double seconds = 0;

  int incidences() const { return static_cast<int>(results.size()); }
  const BsdfResult& at(int p, int t) const { return results[static_cast<std::size_t>(p) * theta_i.size() + t]; }
};

// Throws UsageError for empty angle lists or a theta outside [0, 90) degrees.
BsdfTable measure_bsdf_table(const Tracer& tracer, const BsdfTableOptions& options);

// The measured f (slot k of side s) at direction wo, bilinear between the pixel centres of the
// equal-area hemisphere map (in its square coordinates; edge pixels held constant to the border).
// Pixels are cos-weighted pixel averages, so this is the histogram's piecewise-bilinear
// reconstruction; its error is the pixel size, not the Monte Carlo error.
// `lambda`: a spectral run's wavelength index (BsdfResult::tally), -1 the measured tallies.
double interpolate_f(const BsdfResult& r, int side, int slot, const Vec3& wo, int lambda = -1);

}  // namespace microsim
