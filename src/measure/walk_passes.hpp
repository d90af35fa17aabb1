// How many work units of the BSDF walks run at a time (UnitPasses, measure/replicates.hpp): a pass
// holds at least kPassChunks chunks (work for the threads; 4 per thread on smaller machines: each
// unit in a pass keeps its tally until the pass ends) and at most kPassBytes of unit tallies (large
// hemisphere maps: one unit at a time). Results do not depend on it.
#pragma once
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdint>

#include "microsim/measure/replicates.hpp"

namespace microsim {

constexpr std::uint64_t kPassChunks = 16;
constexpr double kPassBytes = 64.0 * 1024 * 1024;

// The bytes of a walk tally with second moments: sum and second moment (8 bytes each) of both
// sides and K + 1 slots (orders 1 .. K+, total), over the albedo, npix pixels and nplane bins.
inline double walk_tally_bytes(int K, int npix, int nplane) {
  return 16.0 * 2 * (K + 1) * (1.0 + npix + nplane);
}

// The passes of units whose tallies take unit_bytes each.
inline UnitPasses walk_passes(double unit_bytes) {
  const auto threads = static_cast<std::uint64_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  return {std::min(kPassChunks, 4 * threads), std::max<std::uint64_t>(1, static_cast<std::uint64_t>(kPassBytes / unit_bytes))};
}

}  // namespace microsim
