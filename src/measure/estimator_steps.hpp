// Steps shared by the estimators of a whole surface (g2_measure.cpp, vndf_measure.cpp) and of an
// ensemble scene traced part by part (ensemble_estimators.cpp): option checks, random
// streams, the replicate plan, the exchange of tallies with other processes (measure/shards.hpp)
// and the totals, written once so that both routes stay the same estimator.
#pragma once
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "microsim/measure/g2_measure.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/shards.hpp"
#include "microsim/measure/vndf_measure.hpp"

namespace microsim {

// --- G2 ---------------------------------------------------------------------------------------

// Checks o, i (above the horizon) and the sample count (UsageError naming the option), then a
// result with the unit directions, the macro area and the empty normal bins of the options.
G2Result start_g2(const Vec3& o, const Vec3& i, const G2Options& opt, double macro_area);

// The random stream of the unordered pair {o, i}: swapping the directions draws the same points.
std::uint64_t pair_stream(const Vec3& o, const Vec3& i, std::uint64_t salt);

// The replicates of opt.rays area samples (sets r.replicates and r.samples).
ReplicatePlan plan_g2(G2Result& r, const G2Options& opt);

// The per-replicate counts of the replicates `reps` are in r.bins[*].*_r and r.counters (the
// others zero): completes them from the other processes (opt.split), then sums the totals.
void finish_g2(G2Result& r, const G2Options& opt, UnitRange reps);

// --- VNDF -------------------------------------------------------------------------------------

// Checks v (above the horizon) and the ray count, then a result with the unit direction, the
// macro area and the normal binning of the options.
VndfResult start_vndf(const Vec3& v, const VndfOptions& o, double macro_area);

// `counts` (nbins + 1, the last one below the horizon) and r.counters hold the rays `share`:
// completes them from the other processes (o.split), then fills the bin counts and totals.
void finish_vndf(VndfResult& r, const VndfOptions& o, UnitRange share, std::vector<std::uint64_t> counts);

// --- Stratified samples along a CDF -----------------------------------------------------------

// Per replicate q of `reps`, n stratified samples along the CDF of nonnegative facet weights
// (cdf[j] = w_0 + ... + w_j): sample i draws u = (i + U) cdf.back() / n with U the first draw
// of CounterRng(seed, ReplicatePlan::stream(base, q), i) and lands on the first facet with
// cdf[j] > u (never on a zero weight). Within a replicate the facet index is nondecreasing in
// the sample index, so the samples of a range of facets are one contiguous run.
class CdfSamples {
 public:
  CdfSamples(const std::vector<double>& cdf, std::uint64_t seed, std::uint64_t base, std::uint64_t n,
             UnitRange reps);
  // Calls fn(i, facet) for the samples i of replicate q (in reps) on facets [lo, hi).
  template <class Fn>
  void for_each(int q, std::uint32_t lo, std::uint32_t hi, Fn&& fn) const {
    const auto first = facet_.begin() + static_cast<std::ptrdiff_t>((static_cast<std::uint64_t>(q) - reps_.first) * n_);
    const auto last = first + static_cast<std::ptrdiff_t>(n_);
    for (auto it = std::lower_bound(first, last, lo), end = std::lower_bound(first, last, hi); it != end; ++it)
      fn(static_cast<std::uint64_t>(it - first), *it);
  }
  // The generator of sample i of replicate q after the draw that placed it on its facet.
  CounterRng rng(int q, std::uint64_t i) const {
    CounterRng r(seed_, ReplicatePlan::stream(base_, q), i);
    r.uniform();
    return r;
  }

 private:
  std::uint64_t seed_, base_, n_;
  UnitRange reps_;
  std::vector<std::uint32_t> facet_;  // (q - reps.first) n + i
};

}  // namespace microsim
