// Calibrated standard errors from independent randomized replicates (docs/theory/error-bars.md,
// "Every estimate carries its standard error"): the rays of a measurement are split into R replicates, each a
// full stratified, Morton-ordered pass with its own random stream (CounterRng keyed by the
// replicate index), so the R replicate estimates are independent and identically distributed.
// The reported value is the mean of the replicate means and its error the standard error of
// that mean, sqrt(var_r / R); stratification lowers the variance of each replicate, and the
// error still measures it (a binomial formula would only bound it, or miss it entirely where a
// quantity is nearly deterministic).
#pragma once
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>
#include <type_traits>
#include <utility>

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

// The estimators' driver: plan -> work units -> per-unit tallies -> deterministic reduction.
//
// A replicate's n paths are cut into chunks of `chunk` paths (chunk c: paths [c chunk, (c + 1)
// chunk)), and its chunks into at most `max_groups` groups of consecutive chunks (group g:
// chunks [C g / G, C (g + 1) / G), C chunks, G groups). A work unit is one group of one
// replicate, unit number rep * G + g. Each chunk's paths are summed, in order, in a tally of its
// own (made by make()), and a group's chunk tallies are added by halving (the left half's sum
// plus the right half's, recursively: tbb::parallel_deterministic_reduce's order), so a unit's
// tally is the same for any number of threads. The units are handed over in unit order.
inline std::uint64_t chunks_per_replicate(std::uint64_t n, std::uint64_t chunk) {
  return (n + chunk - 1) / chunk;
}
struct UnitPlan {
  int replicates = 1;
  std::uint64_t per_replicate = 0;  // paths of one replicate
  std::uint64_t chunk = 1;          // paths of one chunk
  std::uint64_t max_groups = ~std::uint64_t(0);
  std::uint64_t chunks() const { return chunks_per_replicate(per_replicate, chunk); }
  std::uint64_t groups() const { return std::min(chunks(), max_groups); }
  std::uint64_t units() const { return static_cast<std::uint64_t>(replicates) * groups(); }
  // The units of replicates [reps.first, reps.end) (the share of a process that splits replicates).
  UnitRange units_of(UnitRange reps) const {
    const std::uint64_t R = static_cast<std::uint64_t>(replicates), G = groups();
    return {std::min(reps.first, R) * G, std::min(reps.end, R) * G};
  }
};
// The walk family's rule (BSDF walks, polarized and spectral tallies, the Smith walk model):
// 2^13 paths a chunk, at most 64 units a replicate.
constexpr std::uint64_t kPathChunk = std::uint64_t(1) << 13;
constexpr std::uint64_t kMaxPathUnits = 64;
inline UnitPlan path_plan(int replicates, std::uint64_t per_replicate) {
  return {replicates, per_replicate, kPathChunk, kMaxPathUnits};
}
// How many units run at a time: a pass takes units until it holds at least `min_chunks` chunks
// (the threads' work) or `max_units` units (the memory of their tallies). Results do not depend
// on it.
struct UnitPasses {
  std::uint64_t min_chunks = ~std::uint64_t(0);
  std::uint64_t max_units = ~std::uint64_t(0);
};

namespace replicate_detail {
template <class T, class = void>
struct addable : std::false_type {};
template <class T>
struct addable<T, std::void_t<decltype(std::declval<T&>() += std::declval<const T&>())>> : std::true_type {};
}  // namespace replicate_detail

// The tally of unit u: its chunks summed by halving (see above).
template <class Part, class Make, class Body>
Part run_unit(const UnitPlan& plan, std::uint64_t u, Make& make, Body& body) {
  const std::uint64_t G = plan.groups(), C = plan.chunks(), n = plan.per_replicate;
  const int rep = static_cast<int>(u / G);
  const std::uint64_t g = u % G, c0 = C * g / G, c1 = C * (g + 1) / G;
  auto chunks = [&](std::uint64_t a, std::uint64_t b, Part& part) {
    for (std::uint64_t c = a; c < b; ++c)
      for (std::uint64_t j = c * plan.chunk, end = std::min(n, (c + 1) * plan.chunk); j < end; ++j)
        body(rep, j, part);
  };
  if constexpr (replicate_detail::addable<Part>::value) {
    // Every leaf of parallel_deterministic_reduce starts from the identity (Part(), unused):
    // each chunk's tally is made afresh.
    if (c1 - c0 > 1)
      return tbb::parallel_deterministic_reduce(
          tbb::blocked_range<std::uint64_t>(c0, c1, 1), Part(),
          [&](const tbb::blocked_range<std::uint64_t>& r, const Part&) {
            Part part = make();
            chunks(r.begin(), r.end(), part);
            return part;
          },
          [](Part a, const Part& b) {
            a += b;
            return a;
          });
  }
  Part part = make();
  chunks(c0, c1, part);
  return part;
}

// Runs the units in `share` (unit numbers; UnitPlan::units_of turns a share of replicates into
// one) a pass at a time, body(rep, j, part) for path j of replicate rep, and hands each unit's
// tally to done(rep, group, std::move(part)) on the calling thread, in unit order. Part is
// default-constructible (an empty tally) and, where a unit has several chunks, has +=. After each
// pass, progress(fraction of the share's units done).
template <class Part, class Make, class Body, class Done>
void run_units(const UnitPlan& plan, Make&& make, Body&& body, Done&& done,
               UnitRange share = {0, ~std::uint64_t(0)}, UnitPasses passes = {},
               const std::function<void(double)>& progress = nullptr) {
  const std::uint64_t G = plan.groups(), C = plan.chunks();
  const std::uint64_t first = std::min(share.first, plan.units()), last = std::min(share.end, plan.units());
  for (std::uint64_t u = first; u < last;) {
    std::uint64_t u1 = u, chunks = 0;
    while (u1 < last && chunks < passes.min_chunks && u1 - u < passes.max_units) {
      const std::uint64_t g = u1 % G;
      chunks += C * (g + 1) / G - C * g / G;
      ++u1;
    }
    std::vector<Part> parts(u1 - u);
    tbb::parallel_for(u, u1, [&](std::uint64_t w) { parts[w - u] = run_unit<Part>(plan, w, make, body); });
    for (std::uint64_t w = u; w < u1; ++w) done(static_cast<int>(w / G), w % G, std::move(parts[w - u]));
    u = u1;
    if (progress) progress(static_cast<double>(u - first) / static_cast<double>(last - first));
  }
}

// Every chunk its own unit (max_groups unlimited), all in one pass: the tallies of the chunks in
// (replicate, chunk) order, chunks_per_replicate(n, chunk) per replicate. Only the replicates in
// `reps` are traced (measure/shards.hpp: the share of this process); the parts of the others are
// left as make() returns them.
template <class Part, class Make, class Body>
std::vector<Part> run_replicate_chunks(int R, std::uint64_t n, std::uint64_t chunk, Make&& make,
                                       Body&& body,
                                       UnitRange reps = {0, ~std::uint64_t(0)}) {
  const UnitPlan plan{R, n, chunk};
  std::vector<Part> parts(plan.units());
  const UnitRange mine = plan.units_of(reps);
  run_units<Part>(plan, make, body, [&](int rep, std::uint64_t c, Part&& p) {
    parts[static_cast<std::size_t>(rep) * plan.groups() + c] = std::move(p);
  }, mine);
  for (std::uint64_t u = 0; u < parts.size(); ++u)
    if (!mine.contains(u)) parts[u] = make();
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
