// Work units over the parts of a surface (a whole surface is one part, an ensemble scene has
// many: trace/scene_ensemble.hpp), run in passes: the scenes of a pass's parts are built at its
// start, in parallel (a part's Embree scene lives while the pass traces it), then the pass's
// units run in parallel. Many small parts (the grooves of a V-cavity) are then built and traced
// side by side, and one large part is cut into units that share its scene. Shared by the G2 and
// VNDF estimators (g2_estimator.cpp, vndf_estimator.cpp), whose tallies are integer counts: the
// order the units run in does not change their sums.
#pragma once
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <memory>
#include <vector>

#include "microsim/trace/scene.hpp"

namespace microsim {

// units: the number of work units, sorted by part (part_of(u) nondecreasing). A pass holds at
// most max_units units. build(k): part k's scene; run(u, scene): unit u on its part's scene;
// after_pass(units done), on the calling thread.
template <class PartOf, class Build, class Run, class AfterPass>
void run_part_passes(std::size_t units, std::size_t max_units, PartOf&& part_of, Build&& build, Run&& run,
                     AfterPass&& after_pass) {
  for (std::size_t u0 = 0; u0 < units;) {
    const std::size_t u1 = std::min(units, u0 + max_units);
    const std::size_t k0 = part_of(u0), k1 = part_of(u1 - 1) + 1;
    std::vector<std::unique_ptr<Scene>> scenes(k1 - k0);
    tbb::parallel_for(k0, k1, [&](std::size_t k) { scenes[k - k0] = build(k); });
    tbb::parallel_for(u0, u1, [&](std::size_t u) { run(u, *scenes[part_of(u) - k0]); });
    after_pass(u1);
    u0 = u1;
  }
}

}  // namespace microsim
