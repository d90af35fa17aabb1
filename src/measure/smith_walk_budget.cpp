#include "microsim/measure/smith_walk_budget.hpp"

#include "microsim/measure/sobol_sequence.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace microsim {

namespace {

// Adds the per-walk sums of (index, weight) pairs to sum and sum2: one term per distinct index (sum2
// empty: a tally of first moments, BsdfTally::first_moments).
void add_cells(std::vector<std::pair<std::size_t, double>>& cells, std::vector<double>& sum,
               std::vector<double>& sum2) {
  const bool second = !sum2.empty();
  std::sort(cells.begin(), cells.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t i = 0; i < cells.size();) {
    double w = 0.0;
    std::size_t j = i;
    for (; j < cells.size() && cells[j].first == cells[i].first; ++j) w += cells[j].second;
    sum[cells[i].first] += w;
    if (second) sum2[cells[i].first] += w * w;
    i = j;
  }
}

// The slots with a target: every (side, slot) whose measured albedo error is above the floor.
template <class F>
void for_target_slots(const BsdfResult& r, F&& f) {
  const int K = r.measured.orders;
  for (int sd = 0; sd < 2; ++sd)
    for (int k = 0; k <= K; ++k) {
      const double se = r.albedo(sd, k).stderr_;
      if (std::isfinite(se) && se > kWalkErrorFloor) f(sd, k, se);
    }
}

}  // namespace

void add_walk_escapes(BsdfTally& t, const std::vector<models::WalkEscape>& escapes, const models::WalkExit* drawn,
                      const HemisphereMap& map, const InPlaneBins& plane) {
  const int K = t.orders;
  thread_local std::vector<std::pair<std::size_t, double>> a, p, b;
  a.clear();
  p.clear();
  b.clear();
  auto add = [&](int s, int slot, double w, int px, int bin) {
    a.push_back({t.a_index(s, slot), w});
    if (px >= 0) p.push_back({t.p_index(s, slot, px), w});
    if (bin >= 0) b.push_back({t.b_index(s, slot, bin), w});
  };
  for (const models::WalkEscape& e : escapes)  // orders 1 .. K - 1, expected
    if (e.order >= 1 && e.order < K) add(e.reflected ? 0 : 1, e.order - 1, e.weight, map.pixel_of(e.direction), plane.bin_of(e.direction));
  if (drawn && drawn->order >= 1) {  // the total, and the slot of orders K and above, drawn
    const int s = drawn->reflected ? 0 : 1, px = map.pixel_of(drawn->direction), bin = plane.bin_of(drawn->direction);
    if (drawn->order >= K) add(s, K - 1, drawn->weight, px, bin);
    add(s, K, drawn->weight, px, bin);
    t.both2 += drawn->weight * drawn->weight;
  }
  add_cells(a, t.albedo, t.albedo2);
  add_cells(p, t.pix, t.pix2);
  add_cells(b, t.plane, t.plane2);
}

void add_forced_walk_escapes(BsdfTally& t, const std::vector<models::WalkEscape>& escapes,
                             const models::WalkExit* drawn, const HemisphereMap& map, const InPlaneBins& plane) {
  const int K = t.orders;
  thread_local std::vector<std::pair<std::size_t, double>> a, p, b;
  a.clear();
  p.clear();
  b.clear();
  double both = 0.0;
  // a tally without cells (the pilot's: albedo slots only) bins no direction
  const bool pixels = t.pixels > 0, bins = t.plane_bins > 0;
  auto add = [&](int s, int order, double w, const Vec3& d) {
    const int px = pixels ? map.pixel_of(d) : -1, bin = bins ? plane.bin_of(d) : -1;
    for (int slot : {std::min(order, K) - 1, K}) {
      a.push_back({t.a_index(s, slot), w});
      if (px >= 0) p.push_back({t.p_index(s, slot, px), w});
      if (bin >= 0) b.push_back({t.b_index(s, slot, bin), w});
    }
    both += w;
  };
  for (const models::WalkEscape& e : escapes) {
    if (e.order >= 1) {
      add(e.reflected ? 0 : 1, e.order, e.weight, e.direction);
    } else {  // order 0: a correction of the total alone
      a.push_back({t.a_index(e.reflected ? 0 : 1, K), e.weight});
      both += e.weight;
    }
  }
  if (drawn && drawn->order >= K) add(drawn->reflected ? 0 : 1, drawn->order, drawn->weight, drawn->direction);
  t.both2 += both * both;
  add_cells(a, t.albedo, t.albedo2);
  add_cells(p, t.pix, t.pix2);
  add_cells(b, t.plane, t.plane2);
}

BsdfTally replicate_albedos(const std::vector<BsdfTally>& reps) {
  BsdfTally t;
  for (const BsdfTally& rep : reps) {
    BsdfTally a(rep.orders, 0, 0);
    a.albedo = rep.albedo;
    a.paths = rep.paths;
    t.add_replicate(a);
  }
  return t;
}

WalkNet walk_net(std::uint64_t seed, std::uint64_t stream, std::uint64_t first, std::uint64_t n) {
  WalkNet net;
  net.first = first;
  net.n = n;
  net.points.resize(static_cast<std::size_t>(kSobolDims) * n);
  for (int d = 0; d < kSobolDims; ++d) {
    CounterRng rng(seed, stream ^ 0x50B01500000000ull, static_cast<std::uint64_t>(d));
    const auto shift = static_cast<std::uint32_t>(rng.next_u64() >> 32);
    shifted_sobol_components(first, n, d, shift, net.points.data() + static_cast<std::size_t>(d) * n);
  }
  return net;
}

WalkWindow walk_window(const models::SmithRandomWalk& walk, const Vec3& wi, int orders, std::uint64_t seed,
                       std::uint64_t stream) {
  struct Rng {
    CounterRng c;
    double uniform() { return c.uniform(); }
  };
  // each walk's weight after its first event on TBB's threads, summed in walk order
  std::vector<double> after_first(kWindowWalks);
  tbb::parallel_for(std::uint64_t(0), kWindowWalks, [&](std::uint64_t j) {
    Rng rng{CounterRng(seed, stream ^ 0x3D1A0C0000000000ull, j)};
    double first = 0.0;
    walk.walk_with_weight_window(wi, rng, orders - 1, 0.0, std::numeric_limits<double>::infinity(), [&](const models::WalkEscape& e) {
      if (e.order == 1) first += e.weight;
    });
    after_first[j] = 1.0 - first;
  });
  double continuing = 0.0;
  for (const double x : after_first) continuing += x;
  const double w = std::max(continuing / static_cast<double>(kWindowWalks), kWindowFloor);
  return {kWindowLow * w, kWindowHigh * w};
}

void smith_walk_expected_path(const models::SmithRandomWalk& walk, const Vec3& wi, std::uint64_t seed,
                              std::uint64_t stream, std::uint64_t j, const WalkNet& net,
                              const BsdfResult& r, BsdfTally& t, const WalkWindow& window) {
  struct Rng {
    CounterRng c;
    const WalkNet& net;
    std::uint64_t j;
    int k = 0;
    double uniform() {
      const double u = c.uniform();
      if (k >= kSobolDims) return u;
      // the net's 32 bits, the walk's uniform below them: uniform on [0, 1)
      const double v = (net.point(k++, j) + u) * 0x1p-32;
      return std::min(v, 1.0 - 0x1p-53);
    }
  } rng{CounterRng(seed, stream, j), net, j};
  ++t.paths;
  const int expected_orders = t.orders - 1;
  thread_local std::vector<models::WalkEscape> escapes;
  escapes.clear();
  std::uint64_t lost = 0;
  t.events += walk.walk_with_weight_window(wi, rng, expected_orders, window.low, window.high,
                                           [&](const models::WalkEscape& x) { escapes.push_back(x); }, &lost);
  t.unterminated += lost;
  add_forced_walk_escapes(t, escapes, nullptr, r.map, r.plane);
}

WalkBudget smith_walk_budget(const BsdfTally& pilot, const BsdfResult& r, double fraction,
                             std::uint64_t max_per_replicate, double margin) {
  WalkBudget out;
  out.target_ratio = fraction;
  const double m0 = static_cast<double>(pilot.paths) / std::max(1, pilot.replicates);
  double need = m0;
  for_target_slots(r, [&](int sd, int k, double se) {
    const auto i = pilot.a_index(sd, k);
    const double sp = pilot.estimate(pilot.albedo[i], pilot.albedo2[i]).stderr_;
    const double ratio = margin * sp / (fraction * se);
    const double m = m0 * ratio * ratio;
    if (m > need) {
      need = m;
      out.limiting_side = sd;
      out.limiting_slot = k;
    }
  });
  const std::uint64_t m = std::min<std::uint64_t>(max_per_replicate, static_cast<std::uint64_t>(std::ceil(need)));
  out.walks = std::max<std::uint64_t>(m, static_cast<std::uint64_t>(m0)) * std::max(1, pilot.replicates);
  return out;
}

bool smith_walk_target_met(const BsdfTally& run, const BsdfResult& r, double fraction) {
  bool met = true;
  for_target_slots(r, [&](int sd, int k, double se) {
    const auto i = run.a_index(sd, k);
    if (!(run.estimate(run.albedo[i], run.albedo2[i]).stderr_ <= fraction * se)) met = false;
  });
  return met;
}

double smith_walk_error_ratio(const BsdfResult& r, int* side, int* slot) {
  double ratio = 0.0;
  if (side) *side = -1;
  if (slot) *slot = -1;
  if (!r.smith_walk) return ratio;
  for_target_slots(r, [&](int sd, int k, double se) {
    const double x = r.model_albedo(sd, k).stderr_ / se;
    if (x > ratio) {
      ratio = x;
      if (side) *side = sd;
      if (slot) *slot = k;
    }
  });
  return ratio;
}

Json smith_walk_error_json(const BsdfResult& r) {
  if (!r.smith_walk || !(r.model_budget.target_ratio > 0.0)) return nullptr;
  int side = -1, slot = -1;
  const double achieved = smith_walk_error_ratio(r, &side, &slot);
  const char* sides[2] = {"reflected", "transmitted"};
  return {{"ratio", r.model_budget.target_ratio},
          {"achieved_ratio", achieved},
          {"limiting", side < 0 ? Json(nullptr) : Json(std::string(sides[side]) + " " + order_key(slot, r.options.orders))},
          {"walks_cap", r.options.model_walks * kWalkCapFactor}};
}

}  // namespace microsim
