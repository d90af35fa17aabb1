#include "estimator_steps.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "microsim/measure/sampling.hpp"

namespace microsim {

CdfSamples::CdfSamples(const std::vector<double>& cdf, std::uint64_t seed, std::uint64_t base,
                       std::uint64_t n, UnitRange reps)
    : seed_(seed), base_(base), n_(n), reps_(reps), facet_(reps.size() * n) {
  const double total = cdf.back();
  const std::size_t nf = cdf.size();
  tbb::parallel_for(std::uint64_t(0), reps.size() * n, [&](std::uint64_t g) {
    const int q = static_cast<int>(reps.first + g / n);
    const std::uint64_t i = g % n;
    CounterRng rng(seed, ReplicatePlan::stream(base, q), i);
    const double u = (static_cast<double>(i) + rng.uniform()) / n * total;
    std::size_t j = std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin();
    j = std::min(j, nf - 1);
    while (j > 0 && cdf[j] == cdf[j - 1]) --j;  // never a zero-weight facet
    facet_[g] = static_cast<std::uint32_t>(j);
  });
}

}  // namespace microsim
