// The Smith random-walk model column of a bsdf measurement (models/smith_random_walk.hpp) at the
// measurement's accuracy: walks with forced continuation (walk_with_forced_continuation) tallied per walk, and
// the number of walks chosen from a pilot so that the walk's standard error of every albedo slot is at
// most a stated fraction of the measurement's standard error of the same slot.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "microsim/measure/bsdf_result.hpp"
#include "microsim/models/smith_random_walk.hpp"

namespace microsim {

// Adds one walk to the tally: its expected escapes (orders 1 .. K - 1) to their order slots, and its drawn
// exit (`drawn`, nullptr for a lost walk) to the total and, at orders K and above, to the slot K+. The total
// stays the drawn weight (a mirror's is exactly 1 per walk; expected escapes would add spread there). Per
// walk one term per cell: the second moments are those of the per-walk contributions.
void add_walk_escapes(BsdfTally& t, const std::vector<models::WalkEscape>& escapes, const models::WalkExit* drawn,
                      const HemisphereMap& map, const InPlaneBins& plane);

// Adds one walk with forced continuation (models::SmithRandomWalk::walk_with_forced_continuation) to the
// tally: its expected escapes of the orders 1 .. K - 1 and its drawn exit of order K or above (`drawn`,
// nullptr for a lost walk) to their slots, and all of them to the total (a mirror's walk adds exactly 1 there,
// to rounding: the weights telescope). Per walk one term per cell. A tally without pixels or in-plane bins
// (replicate_albedos makes such tallies) gets the albedo slots alone.
void add_forced_walk_escapes(BsdfTally& t, const std::vector<models::WalkEscape>& escapes,
                             const models::WalkExit* drawn, const HemisphereMap& map, const InPlaneBins& plane);

// The walk's error target: its standard error of an albedo slot at most this fraction of the
// measurement's standard error of that slot.
constexpr double kWalkErrorFraction = 1.0;
// Slots measured to rounding (standard error below this, e.g. a mirror's total 1) set no target.
constexpr double kWalkErrorFloor = 1e-9;

// The pilot: kWalkPilotPerReplicate walks in each replicate (the result when their errors meet the target); at
// most kWalkCapFactor model_walks walks (the model never costs more walks than requested; the record states the
// error reached). The walks of the pilot and the runs after it are pooled: each run adds
// walks to every replicate (the next points of its sequence), so a run that misses the target is topped up rather
// than run again. The pilot's error of a rare order, from 32 replicates of few walks, errs both ways by up to
// ~2x in walks, so the first run is sized for kWalkPilotMargin^2 = 1/2 of the pilot's estimate (rarely more
// than needed), and each later run tops the pooled walks up to the pooled errors' estimate for the target
// divided by kWalkRerunMargin (rarely short again).
constexpr std::uint64_t kWalkPilotPerReplicate = 64;
constexpr std::uint64_t kWalkCapFactor = 1;
constexpr double kWalkPilotMargin = 0.7071067811865476;
constexpr double kWalkRerunMargin = 1.1;
// Runs after the pilot (at most), each topping the pooled walks up to what the pooled errors ask for, until the
// pooled errors meet the target (smith_walk_target_met). A replicate of a few dozen walks has a rough error of a
// rare order: small runs may need more top-ups than large ones.
constexpr int kWalkPasses = 5;

// The albedo slots of per-walk replicate tallies added as BsdfTally::add_replicate adds them (no pixel or in-plane
// cells): what smith_walk_budget and smith_walk_target_met read, without the cost of the cells.
BsdfTally replicate_albedos(const std::vector<BsdfTally>& reps);

// The first kSobolDims uniforms of walk j of a replicate are point j of that replicate's digitally shifted Sobol
// sequence (measure/sobol_sequence.hpp), plus a uniform below 2^-32 from the walk's own generator: every walk's
// uniforms are still uniform, so each walk's expectation is unchanged, but the first heights and facet normals
// (through the order-2 escape) are spread over the replicate as a net, which removes most of the spread of the
// orders 1 and 2 (smooth functions of them with expected escapes). The errors come from the spread of the
// replicates, each shifted independently. A replicate's walks 0 .. m - 1 are the first m points whatever runs
// they were walked in, so runs that add walks extend the sequence.
struct WalkNet {
  std::uint64_t first = 0, n = 0;        // walks first .. first + n - 1
  std::vector<std::uint32_t> points;     // [d * n + (j - first)], shifted
  std::uint32_t point(int d, std::uint64_t j) const { return points[static_cast<std::size_t>(d) * n + (j - first)]; }
};
// The net of the walks first .. first + n - 1 of the replicate of `stream`: its shifts depend on (seed, stream) only.
WalkNet walk_net(std::uint64_t seed, std::uint64_t stream, std::uint64_t first, std::uint64_t n);

// The weight window of the walks (models::SmithRandomWalk::walk_with_weight_window) of one incidence:
// [kWindowLow, kWindowHigh] times the mean weight that goes on after the first event (1 - the order-1 albedo
// for a mirror), estimated from kWindowWalks forced walks of their own stream (at least kWindowFloor). Branches
// near that weight carry the orders 2 and up; much lighter ones are rouletted, much heavier ones (a first
// reflection downward keeps the weight 1) split.
struct WalkWindow {
  double low = 0.0, high = std::numeric_limits<double>::infinity();
};
constexpr std::uint64_t kWindowWalks = 256;
constexpr double kWindowLow = 0.25, kWindowHigh = 2.0, kWindowFloor = 1e-6;
WalkWindow walk_window(const models::SmithRandomWalk& walk, const Vec3& wi, int orders, std::uint64_t seed,
                       std::uint64_t stream);

// Walk j of a replicate (CounterRng(seed, stream, j), its first uniforms from `net`, which holds j) with forced
// continuation through the orders 1 .. K - 1 and its branches' weights in `window`
// (models::SmithRandomWalk::walk_with_weight_window: every walk adds to the orders up to K), added to t
// (add_forced_walk_escapes); the drawn escapes of orders K and above as more escapes. The default window
// [0, inf] is plain forced continuation.
void smith_walk_expected_path(const models::SmithRandomWalk& walk, const Vec3& wi, std::uint64_t seed,
                              std::uint64_t stream, std::uint64_t j, const WalkNet& net,
                              const BsdfResult& r, BsdfTally& t, const WalkWindow& window = {});

// The walks per replicate m = m_pilot (margin stderr_pilot / (fraction * stderr_measured))^2, the largest over the
// albedo slots whose measured error is above kWalkErrorFloor (the error of the replicate means falls at least
// like 1 / sqrt(m)), at least the pilot's and at most max_per_replicate. `pilot`: replicates of m_pilot walks.
WalkBudget smith_walk_budget(const BsdfTally& pilot, const BsdfResult& measured, double fraction,
                             std::uint64_t max_per_replicate, double margin = kWalkPilotMargin);

// True when the run's standard error of every albedo slot with a target is at most fraction times the
// measurement's (the run is kept).
bool smith_walk_target_met(const BsdfTally& run, const BsdfResult& measured, double fraction);

// The achieved ratio max over the same slots of walk stderr / measured stderr (0 when no slot sets a target);
// *side, *slot: where it is reached.
double smith_walk_error_ratio(const BsdfResult& r, int* side = nullptr, int* slot = nullptr);

// The record's albedo_models.smith_multiple.error_target: {ratio: the target fraction, achieved_ratio,
// limiting: "side order" where the achieved ratio is largest, walks_cap}, or null (fixed walks).
Json smith_walk_error_json(const BsdfResult& r);

}  // namespace microsim
