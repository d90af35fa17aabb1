// What a G1 measurement is asked and what it returns (measure/g1_measure.hpp measures it; the
// one estimator, g1_estimator, fills it): the options, the result per view with its normal bins,
// and the deterministic facet sums both use.
#pragma once
#include <algorithm>
#include <cstdint>
#include <functional>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "microsim/measure/binning.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/trace/trace_counters.hpp"

namespace microsim {

class TallySplit;  // measure/shards.hpp

struct G1Options {
  std::uint64_t rays = 1000000;  // per estimator and direction
  std::uint64_t seed = 1;
  int normal_theta_bins = 18;  // normal bins over the whole sphere (10 degree rings)
  int normal_phi_bins = 8;     // 45 degree sectors
  // Independent randomized replicates the rays are split into (measure/replicates.hpp): the
  // standard errors are those of the replicate means.
  int replicates = 32;
  // Called from the calling thread with the fraction of work done (progress display).
  std::function<void(double)> progress;
  // Other processes sharing the replicates (measure/shards.hpp); nullptr: all computed here.
  TallySplit* split = nullptr;
  // A heightfield's fast routes (measure_g1 on a Tracer): rays decoded by its grid walk, draws
  // set up ahead. false: every ray traced on the surface's Scene, the exact route they must
  // equal ray for ray (the tests compare the two).
  bool grid_fast_paths = true;
};

struct G1NormalBin {
  Vec3 mean_normal = Vec3::Zero();  // projected-area-weighted mean unit normal
  double area = 0;                  // sum_f A_f in the bin
  double front_projected = 0;       // sum_f A_f max(0, v.m_f)
  double vcavity_weighted = 0;      // sum_f A_f max(0, v.m_f) G1_vcavity(v, m_f) [Heitz14, eq. 24]
  std::uint64_t raycast_hits = 0;   // estimator (a)
  std::uint64_t samples = 0;        // estimator (b)
  std::uint64_t visible = 0;
  // The same counts per replicate (size G1Result::replicates).
  std::vector<std::uint64_t> raycast_hits_r, samples_r, visible_r;
};

struct G1Result {
  Vec3 v;
  // v.n < 0: the explicit measurement of the undersurface (measured on undersurface(s) at
  // mirror_z(v)); bins are labelled by the undersurface normal -m_f, in the original frame.
  bool undersurface = false;
  double theta = 0, phi = 0;
  std::uint64_t raycast_rays = 0, sample_rays = 0;
  std::uint64_t raycast_hits = 0, sample_visible = 0;
  // Independent replicates (each a full stratified pass of raycast_rays / replicates rays and
  // as many area samples) and the totals per replicate.
  int replicates = 1;
  std::vector<std::uint64_t> raycast_hits_r, sample_visible_r;
  double window_area_perp = 0;     // area of the ray window perpendicular to v
  double front_projected = 0;      // sum_f A_f max(0, v.m_f)
  double total_area = 0;
  double macro_area = 1;           // A
  double total_area_macro() const { return macro_area; }
  double lambda_numeric = 0;       // Lambda from the surface's facets
  TraceCounters counters;
  std::vector<G1NormalBin> bins;
  DirectionBinning binning{1, 1, kPi};
  double seconds = 0;        // wall time of the whole measurement
  double facet_seconds = 0;  // of which the exact facet sums,
  double raycast_seconds = 0;  // estimator (a),
  double sample_seconds = 0;   // estimator (b)
  // Processor time (user + system, all threads of the process) of (a) and (b): the rate on a
  // shared machine, where wall time depends on the other processes.
  double raycast_cpu_seconds = 0, sample_cpu_seconds = 0;

  // Derived quantities with standard errors (of the replicate means, measure/replicates.hpp).
  Estimate g1_area_sampling() const;  // (b), averaged over front-facing projected area
  Estimate g1_raycast() const;        // (a), averaged
  Estimate visible_area_ratio() const;
  Estimate bin_g1_area_sampling(int b) const;
  Estimate bin_g1_raycast(int b) const;
};

DirectionBinning g1_normal_binning(const G1Options& options);
// Deterministic parallel sums over the facets: body(k, acc) adds facet k's terms into
// acc[0 .. width); the result does not depend on the thread count.
template <class Body>
std::vector<double> sum_over_facets(std::size_t num_facets, std::size_t width, Body&& body) {
  using Sums = std::vector<double>;
  Sums sums = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, num_facets,
                                      std::max<std::size_t>(1 << 15, num_facets / 64)),
      Sums{},
      [&](const tbb::blocked_range<std::size_t>& range, Sums acc) {
        if (acc.empty()) acc.assign(width, 0.0);
        for (std::size_t k = range.begin(); k != range.end(); ++k) body(k, acc.data());
        return acc;
      },
      [](Sums a, const Sums& b) {
        if (a.empty()) return b;
        for (std::size_t k = 0; k < b.size(); ++k) a[k] += b[k];
        return a;
      });
  if (sums.empty()) sums.assign(width, 0.0);
  return sums;
}

}  // namespace microsim
