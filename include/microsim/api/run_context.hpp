// What a measurement's record needs to know of the run beyond its request: the threads and MPI
// ranks it ran on, the shards or ranks it shares its tallies with, and where its progress and
// warnings go.
#pragma once
#include <functional>
#include <string>

#include "microsim/common.hpp"

namespace microsim {

class TallySplit;

struct RunContext {
  int threads = 0;  // the TBB limit set by the caller; 0: all cores
  int ranks = 0;    // MPI processes sharing the work (> 0 under MPI; written to the record)
  // Tallies shared with other processes (shards, MPI ranks, a merge's replay); null: alone.
  TallySplit* split = nullptr;
  // Called with the fraction of the run done (0 to 1); may be empty.
  std::function<void(double)> progress;
  // Called with each warning of the run (e.g. a generated heightmap that is not periodic); may be
  // empty.
  std::function<void(const std::string&)> warning;
};

// The fields every record starts with: command, microsim_version, schema_version, threads (and
// ranks under MPI).
Json record_header(const std::string& command, const RunContext& ctx);

}  // namespace microsim
