// Steps shared by the estimators of an ensemble scene traced part by part (ensemble_g1.cpp,
// ensemble_g2_vndf.cpp): the stratified samples of each replicate along the CDF of the
// ensemble's facet weights, whose runs on a part's facets are contiguous.
#pragma once
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/shards.hpp"

namespace microsim {

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
  // The samples [first, end) of replicate q (in reps) on facets [lo, hi), and the facet of its
  // sample i.
  UnitRange run(int q, std::uint32_t lo, std::uint32_t hi) const {
    const auto first = facet_.begin() + static_cast<std::ptrdiff_t>((static_cast<std::uint64_t>(q) - reps_.first) * n_);
    const auto last = first + static_cast<std::ptrdiff_t>(n_);
    return {static_cast<std::uint64_t>(std::lower_bound(first, last, lo) - first),
            static_cast<std::uint64_t>(std::lower_bound(first, last, hi) - first)};
  }
  std::uint32_t facet(int q, std::uint64_t i) const {
    return facet_[(static_cast<std::uint64_t>(q) - reps_.first) * n_ + i];
  }
  // Calls fn(i, facet) for the samples i of replicate q (in reps) on facets [lo, hi).
  template <class Fn>
  void for_each(int q, std::uint32_t lo, std::uint32_t hi, Fn&& fn) const {
    const UnitRange r = run(q, lo, hi);
    for (std::uint64_t i = r.first; i < r.end; ++i) fn(i, facet(q, i));
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
