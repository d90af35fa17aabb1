// The BSDF walk on an ensemble scene (the grooves of a V-cavity) as work units of the estimators'
// driver (measure/ensemble_estimators.hpp, measure/halving_sum.hpp): the halving tree adds its
// leaves as tbb::parallel_deterministic_reduce does, and the walk's tallies are, bit for bit, those
// of one such reduce over the grooves (each leaf a block of grooves walked groove after groove,
// path after path, from zero), for any thread count and with the units shared out over processes.
// Power: the same leaves added left to right give other sums.
#include <gtest/gtest.h>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/halving_sum.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/measure/shards.hpp"
#include "microsim/measure/vcavity_measure.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/trace/scene_ensemble.hpp"

using namespace microsim;
namespace mm = microsim::models;

namespace {

// Item k's value: magnitudes from 2^-4 to 2^5 and both signs, so that sums in another order
// round otherwise.
double item(std::uint64_t k) {
  const std::uint64_t h = mix64(k + 1);
  const double m = 1.0 + static_cast<double>(h >> 12) * 0x1p-52;
  return std::ldexp((h & 1) ? -m : m, static_cast<int>((h >> 1) % 9) - 4);
}
double leaf_sum(const UnitRange& r) {
  double s = 0.0;
  for (std::uint64_t k = r.first; k < r.end; ++k) s += item(k);
  return s;
}

// Leaf value l of the lopsided sums: 1e16 for the first leaf, 1 for the others. The ones are lost
// one at a time (1e16 + 1 rounds to 1e16) but not once summed among themselves, so the sum counts
// how many ones the tree adds before it meets the first leaf.
double lopsided(const UnitRange& r) { return r.first == 0 ? 1e16 : 1.0; }

template <class Leaf>
double reduce_of(std::uint64_t n, Leaf&& leaf) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::uint64_t>(0, n, 16), 0.0,
      [&](const tbb::blocked_range<std::uint64_t>& r, double acc) { return acc + leaf(UnitRange{r.begin(), r.end()}); },
      [](double a, double b) { return a + b; });
}
template <class Leaf>
double halving_of(const HalvingTree& tree, Leaf&& leaf) {
  HalvingSum<double> sum(tree);
  for (const UnitRange& r : tree.leaves()) sum.add(leaf(r));
  return sum.result();
}

}  // namespace

TEST(HalvingSum, AddsTheLeavesAsTheDeterministicReduce) {
  for (std::uint64_t n : {1, 5, 16, 17, 33, 100, 257, 1000}) {
    const HalvingTree tree(n, 16);
    // The leaves tile [0, n) in order, none larger than the grain.
    std::uint64_t next = 0;
    for (const UnitRange& r : tree.leaves()) {
      EXPECT_EQ(r.first, next) << n;
      EXPECT_GE(r.size(), 1u) << n;
      EXPECT_LE(r.size(), 16u) << n;
      next = r.end;
    }
    EXPECT_EQ(next, n);
    EXPECT_EQ(halving_of(tree, leaf_sum), reduce_of(n, leaf_sum)) << n;  // bitwise
    EXPECT_EQ(halving_of(tree, lopsided), reduce_of(n, lopsided)) << n;
    // Power: the same leaves added left to right lose every one (from three leaves on).
    double fold = 0.0;
    for (const UnitRange& r : tree.leaves()) fold += lopsided(r);
    if (tree.leaves().size() >= 3) {
      EXPECT_EQ(fold, 1e16) << n;
      EXPECT_GT(halving_of(tree, lopsided), 1e16) << n;
    }
  }
}

TEST(HalvingSum, RefusesASumTakenEarlyAndTooManyLeaves) {
  const HalvingTree tree(40, 16);  // [0, 20) and [20, 40), each split in two
  ASSERT_EQ(tree.leaves().size(), 4u);
  HalvingSum<double> sum(tree);
  sum.add(1.0);
  EXPECT_THROW(sum.result(), std::logic_error);
  for (int l = 0; l < 3; ++l) sum.add(1.0);
  EXPECT_EQ(sum.result(), 4.0);
  EXPECT_THROW(sum.add(1.0), std::logic_error);
}

namespace {

struct Walk {
  BsdfOptions o;
  Vec3 wi;
  HemisphereMap map{8};
  InPlaneBins plane{0.0, 8};
  std::uint64_t stream = 0xB5DF1234ull;
  Walk() {
    o.material = mm::Material::conductor(0.2, 3.0);
    o.theta_i = rad(60.0);
    o.phi_i = rad(25.0);
    o.rays = 3000;
    o.resolution = 8;
    wi = direction_from_angles(o.theta_i, o.phi_i);
    plane = InPlaneBins(o.phi_i, o.resolution);
  }
};

Microsurface vcavity(int grooves) {
  VCavityParams vp;
  vp.grooves = grooves;
  vp.seed = 7;
  return generate_vcavity(vp);
}

// The grooves' walks summed by one tbb::parallel_deterministic_reduce over the grooves with
// grain 16 (or, `fold`, the same leaves added left to right).
BsdfTally reduce_reference(const Microsurface& s, const Walk& w, bool fold) {
  const SceneEnsemble e = vcavity_grooves(s, "reference", GrooveFrames::OfModel);
  const std::size_t K = e.parts();
  const Strata strata((w.o.rays + K - 1) / K);
  auto leaf = [&](std::size_t k0, std::size_t k1) {
    BsdfTally acc(w.o.orders, w.map.size(), w.plane.size());
    for (std::size_t k = k0; k < k1; ++k) {
      const std::unique_ptr<Scene> scene = e.build(k);
      const Vec3 wl = e.part(k).frame.to_local(w.wi);
      const RayWindow win = scene->ray_window(wl);
      for (std::uint64_t i = 0; i < strata.total(); ++i) {
        CounterRng rng(w.o.seed, w.stream + (static_cast<std::uint64_t>(k) << 32), i);
        ++acc.paths;
        const Vec2 ab = strata.point(i, rng);
        WalkEnd end = walk_bsdf_path(scene->tracer(), win.origin0 + ab.x() * win.e1 + ab.y() * win.e2, -wl,
                                     w.o.material, rng, w.o.max_events, false, acc.counters, acc.events);
        end.direction = e.part(k).frame.to_world(end.direction);
        record_walk_end(acc, end, 1.0, w.map, w.plane);
      }
    }
    return acc;
  };
  if (fold) {
    BsdfTally total(w.o.orders, w.map.size(), w.plane.size());
    const HalvingTree tree(K, 16);
    for (const UnitRange& r : tree.leaves()) total += leaf(r.first, r.end);
    return total;
  }
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, K, 16), BsdfTally(),
      [&](const tbb::blocked_range<std::size_t>& r, BsdfTally) { return leaf(r.begin(), r.end()); },
      [](BsdfTally a, const BsdfTally& b) {
        a += b;
        return a;
      });
}

void expect_same_sums(const BsdfTally& a, const BsdfTally& b, const std::string& what) {
  EXPECT_EQ(a.albedo, b.albedo) << what;  // bitwise
  EXPECT_EQ(a.albedo2, b.albedo2) << what;
  EXPECT_EQ(a.pix, b.pix) << what;
  EXPECT_EQ(a.pix2, b.pix2) << what;
  EXPECT_EQ(a.plane, b.plane) << what;
  EXPECT_EQ(a.plane2, b.plane2) << what;
  EXPECT_EQ(a.both2, b.both2) << what;
  EXPECT_EQ(a.paths, b.paths) << what;
  EXPECT_EQ(a.events, b.events) << what;
  EXPECT_EQ(a.lost, b.lost) << what;
  EXPECT_EQ(a.counters.rays, b.counters.rays) << what;
}

bool same_first_moments(const BsdfTally& a, const BsdfTally& b) {
  return a.albedo == b.albedo && a.pix == b.pix && a.plane == b.plane;
}

}  // namespace

TEST(EnsembleBsdfUnits, TalliesAreTheDeterministicReduceOverTheGroovesBitForBit) {
  const Walk w;
  int folds_differ = 0;
  for (int grooves : {5, 33, 100}) {  // one leaf; leaves at two depths; leaves of 12 and 13
    const Microsurface s = vcavity(grooves);
    const BsdfTally reference = reduce_reference(s, w, false);
    ASSERT_GT(reference.paths, 0u);
    for (int threads : {1, 2}) {
      tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
      const BsdfTally t = trace_vcavity_bsdf(s, w.o, w.wi, w.map, w.plane, w.stream);
      expect_same_sums(t, reference, std::to_string(grooves) + " grooves, " + std::to_string(threads) + " threads");
    }
    if (!same_first_moments(reduce_reference(s, w, true), reference)) ++folds_differ;
  }
  EXPECT_GE(folds_differ, 1);  // power: the leaves added left to right round otherwise
}

// Shards: each process walks its share of the units and the exchange brings the others' rows
// (measure/shards.hpp); every share's run then gives the one-process tallies.
namespace {
// Shard k of n for one estimator call, whose exchange puts the other shards' rows from `all`
// (every unit's row, as a merge places them).
class RowsFromOthers : public TallySplit {
 public:
  RowsFromOthers(int k, int n, const Tallies* all) : k_(k), n_(n), all_(all) {}
  UnitRange share(std::uint64_t units) const override { return shard_range(units, k_, n_); }
  void exchange(Tallies& t) override {
    kinds.push_back(t.kind);
    covered = t.covered;
    units = t.units;
    if (!all_) {  // the one-process run: its rows are every row
      rows = t;
      return;
    }
    for (std::uint64_t u = 0; u < t.units; ++u) {
      if (t.covered.contains(u)) continue;
      std::copy(all_->count_row(u), all_->count_row(u) + t.row_counts, t.count_row(u));
      std::copy(all_->real_row(u), all_->real_row(u) + t.row_reals, t.real_row(u));
    }
  }
  std::vector<std::string> kinds;
  UnitRange covered;
  std::uint64_t units = 0;
  Tallies rows;

 private:
  int k_, n_;
  const Tallies* all_;
};
}  // namespace

TEST(EnsembleBsdfUnits, SharesOfTheUnitsExchangedGiveTheOneProcessTallies) {
  Walk w;
  const Microsurface s = vcavity(100);  // 8 units of 12 or 13 grooves
  const BsdfTally one = trace_vcavity_bsdf(s, w.o, w.wi, w.map, w.plane, w.stream);
  RowsFromOthers whole(0, 1, nullptr);
  w.o.split = &whole;
  expect_same_sums(trace_vcavity_bsdf(s, w.o, w.wi, w.map, w.plane, w.stream), one, "one share");
  ASSERT_EQ(whole.kinds, std::vector<std::string>{"bsdf_ensemble"});
  ASSERT_EQ(whole.units, 8u);
  for (int k = 0; k < 3; ++k) {
    RowsFromOthers shard(k, 3, &whole.rows);
    w.o.split = &shard;
    const BsdfTally t = trace_vcavity_bsdf(s, w.o, w.wi, w.map, w.plane, w.stream);
    EXPECT_GT(shard.covered.size(), 0u);
    EXPECT_LT(shard.covered.size(), 8u);  // a share, not the whole walk
    expect_same_sums(t, one, "shard " + std::to_string(k + 1) + " of 3");
  }
  // Power: a share whose exchange brings nothing from the others (zero rows) lacks their sums.
  Tallies none = whole.rows;
  std::fill(none.counts.begin(), none.counts.end(), 0);
  std::fill(none.reals.begin(), none.reals.end(), 0.0);
  RowsFromOthers alone(0, 3, &none);
  w.o.split = &alone;
  const BsdfTally partial = trace_vcavity_bsdf(s, w.o, w.wi, w.map, w.plane, w.stream);
  EXPECT_LT(partial.paths, one.paths);
  EXPECT_FALSE(same_first_moments(partial, one));
}
