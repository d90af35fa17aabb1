// The BSDF random walk on an ensemble scene (measure/ensemble_estimators.hpp).
#include "microsim/measure/ensemble_estimators.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <string>

#include "ensemble_parts.hpp"
#include "estimator_steps.hpp"
#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/models/vgroove_multiple.hpp"

namespace microsim {

BsdfTally trace_bsdf(const SceneEnsemble& e, const BsdfOptions& o, const Vec3& wi,
                     const HemisphereMap& map, const InPlaneBins& plane, std::uint64_t stream) {
  require_equal_parts(e, "trace_bsdf");
  const std::size_t K = e.parts();
  const Strata strata((o.rays + K - 1) / K);
  const int orders = o.orders, npix = map.size(), nplane = plane.size();
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, K, 16), BsdfTally(),
      [&](const tbb::blocked_range<std::size_t>& range, BsdfTally acc) {
        if (acc.albedo.empty()) acc = BsdfTally(orders, npix, nplane);
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          const SceneEnsemble::Part& p = e.part(k);
          const std::unique_ptr<Scene> scene = e.build(k);
          const Vec3 wl = p.frame.to_local(wi);
          const RayWindow w = scene->ray_window(wl);
          for (std::uint64_t i = 0; i < strata.total(); ++i) {
            CounterRng rng(o.seed, stream + (static_cast<std::uint64_t>(k) << 32), i);
            ++acc.paths;
            const Vec2 ab = strata.point(i, rng);
            WalkEnd end = walk_bsdf_path(scene->tracer(), w.origin0 + ab.x() * w.e1 + ab.y() * w.e2, -wl,
                                         o.material, rng, o.max_events, false, acc.counters, acc.events);
            end.direction = p.frame.to_world(end.direction);
            record_walk_end(acc, end, 1.0, map, plane);
          }
        }
        return acc;
      },
      [](BsdfTally a, const BsdfTally& b) {
        a += b;
        return a;
      });
}

}  // namespace microsim
