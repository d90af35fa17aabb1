// What the ray estimators' requests (measure g1, g2, vndf) share: their estimator options from the
// request and the run, the start of their records and the definition of their standard errors.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "microsim/api/run_context.hpp"
#include "microsim/api/surface_input.hpp"

namespace microsim {

// An estimator's options (G1Options, G2Options, VndfOptions) with the rays, the seed and the
// shards/MPI split of the run.
template <class Options>
Options estimator_options(long long rays, std::uint64_t seed, const RunContext& ctx) {
  Options o;
  o.split = ctx.split;
  o.rays = static_cast<std::uint64_t>(rays);
  o.seed = seed;
  return o;
}

// The record's first fields: record_header, then "file" (a name, or the list of an ensemble).
Json estimator_record(const std::string& command, const std::vector<SurfaceInput>& surfaces, const RunContext& ctx);

// The "stderr" definition of the replicated estimators (g1, g2): of one surface's replicates, or
// between the surfaces of an ensemble.
const char* replicate_stderr_definition(bool ensemble);

// ParameterError unless rays is in [1, kMaxRays] and replicates in [2, kMaxReplicates].
void require_rays_and_replicates(long long rays, int replicates);

}  // namespace microsim
