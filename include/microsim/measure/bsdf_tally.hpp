// The mergeable sums of a BSDF measurement per side, scattering order and outgoing bin
// (measure/bsdf_measure.hpp), and the keys of its order slots. Defined in
// src/measure/bsdf_measure.cpp.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/trace/trace_counters.hpp"

namespace microsim {

struct SpectralTally;

// Mergeable sums. Index conventions: side s (0 reflected, 1 transmitted), slot k (0 .. K-1 for
// orders 1 .. K+, K for the total). The first moments are sums over paths of the weight that
// left in the cell. The second moments depend on how the paths were drawn:
//  * replicates == 0 (i.i.d. paths, the Smith walk): sums over paths of the squared weight;
//  * replicates = R >= 1 (R stratified replicates of paths / R paths, the explicit surface):
//    the sums of squared deviations of the R replicate means from their mean (add_replicate).
struct BsdfTally {
  int orders = 4, pixels = 0, plane_bins = 0;
  int replicates = 0;
  std::vector<double> albedo, albedo2;  // [s][k]
  std::vector<double> pix, pix2;        // [s][k][pixel]
  std::vector<double> plane, plane2;    // [s][k][bin]
  double both2 = 0;                     // second moment of reflected + transmitted (total)
  std::uint64_t paths = 0;              // rays (walks) started
  std::uint64_t lost = 0;               // ended without leaving (tracer loss, wrong-side hit)
  std::uint64_t unterminated = 0;       // more than max_events scattering events
  std::uint64_t events = 0;             // scattering events, all paths
  TraceCounters counters;

  // The counts, declared once (tally_fields.hpp): summed, exchanged between processes.
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f("paths", &BsdfTally::paths);
    f("lost", &BsdfTally::lost);
    f("unterminated", &BsdfTally::unterminated);
    f("events", &BsdfTally::events);
    f("counters", &BsdfTally::counters);
  }
  // The weight sums, each with its second moment (per path; between replicates, Welford's sum
  // of squared deviations of the replicate means): f(name, sum, second moment). both2 apart.
  template <class F>
  static constexpr void for_each_moment(F&& f) {
    f("albedo", &BsdfTally::albedo, &BsdfTally::albedo2);
    f("pix", &BsdfTally::pix, &BsdfTally::pix2);
    f("plane", &BsdfTally::plane, &BsdfTally::plane2);
  }

  BsdfTally() = default;
  BsdfTally(int K, int npix, int nplane);
  // A replicate's tally of first moments only (albedo2, pix2, plane2 empty): add_replicate reads a
  // replicate's first moments and counts alone, so per-path second moments of a replicate that only
  // enters add_replicate are never read (the Smith walk's replicates: half the memory to zero and add).
  static BsdfTally first_moments(int K, int npix, int nplane);
  bool has_second_moments() const { return albedo2.size() == albedo.size(); }
  int slots() const { return orders + 1; }
  std::size_t a_index(int s, int k) const { return static_cast<std::size_t>(s) * slots() + k; }
  std::size_t p_index(int s, int k, int px) const {
    return (static_cast<std::size_t>(s) * slots() + k) * pixels + px;
  }
  std::size_t b_index(int s, int k, int b) const {
    return (static_cast<std::size_t>(s) * slots() + k) * plane_bins + b;
  }
  // A path that left on side s after `order` >= 1 events, with weight w, pixel px (or -1) and
  // in-plane bin b (or -1).
  void add_exit(int s, int order, double w, int px, int b);
  BsdfTally& operator+=(const BsdfTally& o);
  // Adds one replicate's per-path tally (replicates == 0) as replicate number `replicates`.
  void add_replicate(const BsdfTally& rep);
  // The same for wavelength l of a spectral replicate (the counts are the path's, shared).
  void add_replicate(const SpectralTally& rep, int l);
  // Mean per path of the first moment `sum` (times `scale`) with its standard error.
  Estimate estimate(double sum, double sum2, double scale = 1.0) const;
};

// Mean and standard error of the per-path contribution X (0 or the path's weight) times `scale`.
Estimate tally_estimate(double sum, double sum2, std::uint64_t n, double scale = 1.0);

// Key of slot k: "order_1", ..., "order_<K>plus", "total".
std::string order_key(int k, int orders);

}  // namespace microsim
