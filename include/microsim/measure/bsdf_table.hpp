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
  // An isotropic table (one phi_i) measured at this many incidence azimuths, spread uniformly
  // from phi_i (phi_i + 2 pi k / N, k = 0 .. N-1), each with rays / N walks (the remainder to the
  // first ones): the table then holds the surface's azimuthal mean, not one azimuth's lobe
  // (docs/theory/exports.md). 1: phi_i alone. Ignored when phi_i has several entries.
  int table_azimuths = 1;
  // What is read of the turned runs (table_azimuths > 1): everything (their albedos and errors:
  // measure albedo), or only a renderer table's averages (measure/table_run_sums.hpp): the
  // reflected total's f per pixel (table_f: .bsdf, .binary; no Mueller sums walked), or the
  // Mueller bins (.pbsdf). The table's entries are the same bit for bit.
  enum class TurnedRuns { Everything, TableF, TableMueller };
  TurnedRuns turned_runs = TurnedRuns::Everything;
  // Fraction of the whole table done (called from the calling thread).
  std::function<void(double)> progress;
};

struct BsdfTable {
  std::vector<double> theta_i, phi_i;  // radians
  std::vector<BsdfResult> results;     // incidence (p, t) at index p * theta_i.size() + t
  double seconds = 0;
  // Azimuth-averaged isotropic tables (table_azimuths N > 1): results holds the runs at the
  // nominal phi_i[0]; turns[k] = 2 pi k / N (turns[0] = 0) and turned[t][k - 1] the run of
  // theta_i[t] at phi_i[0] + turns[k]. Empty otherwise.
  std::vector<double> turns;
  std::vector<std::vector<BsdfResult>> turned;

  int incidences() const { return static_cast<int>(results.size()); }
  const BsdfResult& at(int p, int t) const { return results[static_cast<std::size_t>(p) * theta_i.size() + t]; }
  // Incidence azimuths the table's entries average (1 unless azimuth-averaged).
  int azimuths() const { return turns.empty() ? 1 : static_cast<int>(turns.size()); }
  // Walks of incidence (p, t), over all its azimuths.
  std::uint64_t paths(int p, int t) const;
};

// Throws UsageError for empty angle lists or a theta outside [0, 90) degrees.
BsdfTable measure_bsdf_table(const Tracer& tracer, const BsdfTableOptions& options);

// The measured f (slot k of side s) at direction wo, bilinear between the pixel centres of the
// equal-area hemisphere map (in its square coordinates; edge pixels held constant to the border).
// Pixels are cos-weighted pixel averages, so this is the histogram's piecewise-bilinear
// reconstruction; its error is the pixel size, not the Monte Carlo error.
// `lambda`: a spectral run's wavelength index (BsdfResult::tally), -1 the measured tallies.
double interpolate_f(const BsdfResult& r, int side, int slot, const Vec3& wo, int lambda = -1);

// The table's f at incidence (p, t) toward wo (in the frame of the nominal incidence, azimuth
// phi_i[p]): interpolate_f of the nominal run, or for an azimuth-averaged table the mean over
// its N azimuths of each run's f at wo turned by that run's azimuth offset (the run at
// phi_i + turns[k] sees the outgoing direction of wo at Rz(turns[k]) wo), weighted by walks.
double table_f(const BsdfTable& table, int p, int t, int side, int slot, const Vec3& wo, int lambda = -1);

// Rz(angle) v: v turned about the normal by `angle` (radians, counterclockwise seen from +z).
Vec3 turn_about_normal(const Vec3& v, double angle);

}  // namespace microsim
