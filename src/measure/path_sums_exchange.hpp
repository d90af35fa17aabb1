// Per-unit BSDF path sums (BsdfTally with replicates == 0: sums over paths and, when `second`,
// sums of squared weights) completed from other processes (measure/shards.hpp): one row per
// unit, the counts as BsdfTally declares them, then the first moments, then the second ones.
// Used by the Smith walk model's batches and an ensemble's units of parts (bsdf_measure.cpp,
// ensemble_bsdf.cpp) and, first moments only, by the whole surface's replicates.
#pragma once
#include <vector>

#include "microsim/measure/bsdf_tally.hpp"
#include "microsim/measure/shards.hpp"

namespace microsim {

// units[u] for u in `share` holds this process's sums (the others any tally of the same shape);
// on return every unit holds its sums, as the process that computed it had them.
void exchange_paths(TallySplit& split, const char* kind, UnitRange share, bool second,
                    std::vector<BsdfTally>& units);

}  // namespace microsim
