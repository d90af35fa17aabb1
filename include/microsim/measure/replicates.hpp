// Calibrated standard errors from independent randomized replicates (docs/theory/error-bars.md,
// "Every estimate carries its standard error"): the rays of a measurement are split into R replicates, each a
// full stratified, Morton-ordered pass with its own random stream (CounterRng keyed by the
// replicate index), so the R replicate estimates are independent and identically distributed.
// The reported value is the mean of the replicate means and its error the standard error of
// that mean, sqrt(var_r / R); stratification lowers the variance of each replicate, and the
// error still measures it (a binomial formula would only bound it, or miss it entirely where a
// quantity is nearly deterministic).
#pragma once
#include <tbb/parallel_for.h>

#include <cstdint>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/measure/shards.hpp"

namespace microsim {

constexpr int kDefaultReplicates = 32;

// How `rays` requested rays are split: R replicates of ceil(rays / R) rays each (the total is
// rays rounded up to a multiple of R). R is lowered to `rays` for tiny requests.
struct ReplicatePlan {
  int replicates = 1;
  Strata strata{1};
  ReplicatePlan(std::uint64_t rays, int requested);
  std::uint64_t per_replicate() const { return strata.total(); }
  std::uint64_t total() const { return per_replicate() * static_cast<std::uint64_t>(replicates); }
  // Random stream of replicate `rep` for a measurement stream `base`.
  static std::uint64_t stream(std::uint64_t base, int rep) {
    return mix64(base ^ mix64(0x7E91CA7Eull + static_cast<std::uint64_t>(rep)));
  }
};

// Runs body(rep, j, part) for every replicate rep < R and ray j < n of it, in parallel chunks
// of at most `chunk` rays inside one replicate, each chunk filling its own part (made by
// make()). The parts come back in (replicate, chunk) order, so merging them in that order gives
// integer tallies identical for any thread count. chunks_per_replicate(n, chunk) parts belong
// to each replicate. Only the replicates in `reps` are traced (measure/shards.hpp: the share of
// this process); the parts of the others are left as make() returns them.
inline std::uint64_t chunks_per_replicate(std::uint64_t n, std::uint64_t chunk) {
  return (n + chunk - 1) / chunk;
}
template <class Part, class Make, class Body>
std::vector<Part> run_replicate_chunks(int R, std::uint64_t n, std::uint64_t chunk, Make&& make,
                                       Body&& body,
                                       UnitRange reps = {0, ~std::uint64_t(0)}) {
  const std::uint64_t nc = chunks_per_replicate(n, chunk);
  std::vector<Part> parts(static_cast<std::size_t>(R) * nc);
  tbb::parallel_for(std::uint64_t(0), static_cast<std::uint64_t>(R) * nc, [&](std::uint64_t c) {
    const int rep = static_cast<int>(c / nc);
    const std::uint64_t first = (c % nc) * chunk, end = std::min(n, first + chunk);
    parts[c] = make();
    if (!reps.contains(static_cast<std::uint64_t>(rep))) return;
    for (std::uint64_t j = first; j < end; ++j) body(rep, j, parts[c]);
  });
  return parts;
}

// Mean of the replicate values x_r and the standard error of that mean, sqrt(var / R)
// (0 when R < 2: no error can be estimated from one replicate).
Estimate replicate_mean(const std::vector<double>& x);
// Same for integer tallies scaled by `scale` (e.g. 1 / rays per replicate).
Estimate replicate_mean(const std::vector<std::uint64_t>& counts, double scale);
// A ratio of totals sum y_r / sum x_r (e.g. visible / samples of one normal bin, whose sample
// count varies between replicates) with the linearized replicate error
// sqrt(sum_r (y_r - q x_r)^2 / (R (R - 1))) / mean(x_r): the first-order jackknife, equal to
// the error of the replicate means when every x_r is the same.
Estimate replicate_ratio(const std::vector<std::uint64_t>& y, const std::vector<std::uint64_t>& x);
// Delete-one-replicate jackknife of a smooth function of totals: theta_r is the statistic
// recomputed without replicate r, theta_all with all of them; the error is
// sqrt((R - 1) / R sum_r (theta_r - mean theta_r)^2).
Estimate jackknife(double theta_all, const std::vector<double>& theta_without);

}  // namespace microsim
