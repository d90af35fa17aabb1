// The BSDF random walk on an ensemble scene (measure/ensemble_estimators.hpp), on the estimators'
// driver (measure/replicates.hpp: run_units) and split over processes like the whole surface's
// walk (measure/shards.hpp).
#include "microsim/measure/ensemble_estimators.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "ensemble_parts.hpp"
#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/halving_sum.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "path_sums_exchange.hpp"
#include "walk_passes.hpp"

namespace microsim {

namespace {

// A work unit walks the paths of a block of at most kPartsPerUnit consecutive parts, part after
// part, into one tally from zero; the blocks are the leaves of the halving split of the parts
// and the units' tallies are added in that tree's order (measure/halving_sum.hpp): the sums of
// one tbb::parallel_deterministic_reduce over the parts with grain kPartsPerUnit, bit for bit,
// for any number of threads or processes.
constexpr std::uint64_t kPartsPerUnit = 16;
// What the paths of one part share: its scene (built once, at the start of the pass that walks
// the part), the incidence in its frame and its ray window.
struct PartWalk {
  std::unique_ptr<Scene> scene;
  Vec3 wl;
  RayWindow window;
};

// The walks of an ensemble: on every one of its K parts n stratified paths along -wi; path i of
// part k draws from CounterRng(seed, stream + (k << 32), i), its exit turned back to the world
// frame before binning.
struct EnsembleWalk {
  const SceneEnsemble& e;
  const BsdfOptions& o;
  Vec3 wi;
  const HemisphereMap& map;
  const InPlaneBins& plane;
  std::uint64_t stream;
  Strata strata;
  HalvingTree blocks;

  EnsembleWalk(const SceneEnsemble& ens, const BsdfOptions& opt, const Vec3& l, const HemisphereMap& m,
               const InPlaneBins& b, std::uint64_t s)
      : e(ens), o(opt), wi(l), map(m), plane(b), stream(s), strata((opt.rays + ens.parts() - 1) / ens.parts()),
        blocks(ens.parts(), kPartsPerUnit) {}

  // Unit u is block u; its paths j = (part - first) n + i, the blocks shorter than the longest
  // without paths at the end. One chunk a unit: its paths summed in order.
  UnitPlan plan() const {
    const std::uint64_t paths = blocks.largest_leaf() * strata.total();
    return {static_cast<int>(blocks.leaves().size()), paths, paths, 1};
  }
  BsdfTally make() const { return BsdfTally(o.orders, map.size(), plane.size()); }
  PartWalk part_walk(std::size_t k) const {
    PartWalk p{e.build(k), e.part(k).frame.to_local(wi), {}};
    p.window = p.scene->ray_window(p.wl);
    return p;
  }
  // Path j of `block` into acc; parts[k - first] is part k's walk.
  void walk(const UnitRange& block, std::uint64_t j, const PartWalk* parts, std::uint64_t first, BsdfTally& acc) const {
    const std::uint64_t n = strata.total(), k = block.first + j / n, i = j % n;
    if (k >= block.end) return;
    const PartWalk& p = parts[k - first];
    CounterRng rng(o.seed, stream + (k << 32), i);
    ++acc.paths;
    const Vec2 ab = strata.point(i, rng);
    WalkEnd end = walk_bsdf_path(p.scene->tracer(), p.window.origin0 + ab.x() * p.window.e1 + ab.y() * p.window.e2,
                                 -p.wl, o.material, rng, o.max_events, false, acc.counters, acc.events);
    end.direction = e.part(k).frame.to_world(end.direction);
    record_walk_end(acc, end, 1.0, map, plane);
  }
};

// A unit is one chunk: a pass of walk_passes.hpp takes the fewer of its chunks and its units (the
// scenes of the pass's parts live while it runs).
std::uint64_t units_per_pass(const EnsembleWalk& w) {
  const UnitPasses p = walk_passes(walk_tally_bytes(w.o.orders, w.map.size(), w.plane.size()));
  return std::min(p.min_chunks, p.max_units);
}

// The units of `share` a pass at a time: the scenes of the pass's parts built in parallel, then
// its units walked (run_units); done(unit, tally) in unit order, on the calling thread.
template <class Done>
void walk_units(const EnsembleWalk& w, UnitRange share, Done&& done) {
  const UnitPlan plan = w.plan();
  const std::vector<UnitRange>& blocks = w.blocks.leaves();
  const std::uint64_t per_pass = units_per_pass(w);
  for (std::uint64_t u0 = share.first; u0 < share.end;) {
    const std::uint64_t u1 = std::min(share.end, u0 + per_pass);
    const std::uint64_t k0 = blocks[u0].first, k1 = blocks[u1 - 1].end;
    std::vector<PartWalk> parts(k1 - k0);
    tbb::parallel_for(k0, k1, [&](std::uint64_t k) { parts[k - k0] = w.part_walk(k); });
    run_units<BsdfTally>(
        plan, [&] { return w.make(); },
        [&](int u, std::uint64_t j, BsdfTally& acc) { w.walk(blocks[u], j, parts.data(), k0, acc); },
        [&](int u, std::uint64_t, BsdfTally&& t) { done(static_cast<std::uint64_t>(u), std::move(t)); }, {u0, u1});
    u0 = u1;
  }
}

}  // namespace

BsdfTally trace_bsdf(const SceneEnsemble& e, const BsdfOptions& o, const Vec3& wi,
                     const HemisphereMap& map, const InPlaneBins& plane, std::uint64_t stream) {
  require_equal_parts(e, "trace_bsdf");
  const EnsembleWalk w(e, o, wi, map, plane, stream);
  const std::uint64_t units = w.blocks.leaves().size();
  const UnitRange mine = share_of(o.split, units);
  HalvingSum<BsdfTally> sum(w.blocks);
  if (!o.split) {
    walk_units(w, mine, [&](std::uint64_t, BsdfTally&& t) { sum.add(std::move(t)); });
    return sum.result();
  }
  // A split: this process's units kept until the others' arrive, then all added as in one process.
  std::vector<BsdfTally> tallies(units, w.make());
  walk_units(w, mine, [&](std::uint64_t u, BsdfTally&& t) { tallies[u] = std::move(t); });
  exchange_paths(*o.split, "bsdf_ensemble", mine, true, tallies);
  for (BsdfTally& t : tallies) sum.add(std::move(t));
  return sum.result();
}

}  // namespace microsim
