#include "g2_estimator.hpp"

#include <algorithm>
#include <string>
#include <vector>

#include "microsim/measure/sampling.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/measure/shards.hpp"
#include "part_passes.hpp"

namespace microsim {

G2Result start_g2(const Vec3& o, const Vec3& i, const G2Options& opt, double macro_area) {
  if (!(o.z() > 0)) throw ParameterError("{theta_o} must be in [0, 90) degrees");
  if (!(i.z() > 0)) throw ParameterError("{theta_i} must be in [0, 90) degrees");
  if (opt.rays == 0) throw ParameterError("{rays} must be positive");
  G2Result r;
  r.o = o.normalized();
  r.i = i.normalized();
  r.macro_area = macro_area;
  r.binning = g2_normal_binning(opt);
  r.bins.assign(r.binning.size(), G2NormalBin{});
  return r;
}

std::uint64_t pair_stream(const Vec3& o, const Vec3& i, std::uint64_t salt) {
  const std::uint64_t ko = direction_stream_key(o), ki = direction_stream_key(i);
  return salt ^ mix64(std::min(ko, ki) ^ mix64(std::max(ko, ki)));
}

ReplicatePlan plan_g2(G2Result& r, const G2Options& opt) {
  const ReplicatePlan plan(opt.rays, opt.replicates);
  r.replicates = plan.replicates;
  r.samples = plan.total();
  return plan;
}

namespace {

constexpr std::uint64_t kChunk = 1 << 13;  // points of one work unit
// Work units of a pass: the scenes of its parts live while it runs; progress after each.
constexpr std::size_t kUnitsPerPass = 256;

// The counts of G2NormalBin, in its declaration order.
constexpr int kCounts = 4;

// Calls fn(count, q, k * nb + b) for the per-replicate count k of bin b in replicate q, for
// every count G2NormalBin declares (k in declaration order, nb bins).
template <class Bins, class Fn>
void each_g2_count(Bins& bins, int R, Fn&& fn) {
  const std::size_t nb = bins.size();
  std::size_t k = 0;
  G2NormalBin::for_each_replicate_count([&](const char*, auto, auto per_replicate) {
    for (int q = 0; q < R; ++q)
      for (std::size_t b = 0; b < nb; ++b) fn((bins[b].*per_replicate)[q], q, k * nb + b);
    ++k;
  });
}

// The per-replicate counts of the replicates `reps` are in r.bins[*].*_r and r.counters (the
// others zero): completes them from the other processes (opt.split), then sums the totals.
void finish_g2(G2Result& r, const G2Options& opt, UnitRange reps) {
  const int R = r.replicates;
  if (opt.split) {
    // Completes the replicates' counts from the other processes (measure/shards.hpp).
    std::size_t fields = 0;
    G2NormalBin::for_each_replicate_count([&](const char*, auto, auto) { ++fields; });
    Tallies t("g2", R, reps, fields * r.bins.size(), 0, kCounterValues, 0);
    each_g2_count(r.bins, R, [&](std::uint64_t c, int q, std::size_t at) { t.count_row(q)[at] = c; });
    put_counters(r.counters, t.tail_counts.data());
    opt.split->exchange(t);
    each_g2_count(r.bins, R, [&](std::uint64_t& c, int q, std::size_t at) { c = t.count_row(q)[at]; });
    r.counters = get_counters(t.tail_counts.data());
  }
  for (G2NormalBin& nb : r.bins) {
    G2NormalBin::for_each_replicate_count([&](const char*, auto total, auto per_replicate) {
      for (int q = 0; q < R; ++q) nb.*total += (nb.*per_replicate)[q];
    });
    r.visible_o += nb.visible_o;
    r.visible_i += nb.visible_i;
    r.visible_both += nb.visible_both;
  }
}

// A work unit: the points [first, end) of replicate q on part k.
struct G2Unit {
  std::size_t part;
  int q;
  UnitRange points;
};

// A unit's integer counts (samples, visible from o, from i, from both of bin b at b kCounts + k),
// held while its pass runs and then added into its replicate's counts.
using G2Counts = std::vector<std::uint64_t>;

// Traces the points of one unit on its part's scene (o and i in the world frame).
void trace_g2_unit(const G2Points& points, const Scene& scene, const Vec3& o_world, const Vec3& i_world,
                   const G2Unit& u, std::uint64_t seed, int nbins, G2Counts& c, TraceCounters& tc) {
  const std::size_t first = points.facets(u.part).first;
  const Vec3 o = points.to_local(u.part, o_world), i = points.to_local(u.part, i_world);
  c.assign(static_cast<std::size_t>(nbins) * kCounts, 0);
  for (std::uint64_t j = u.points.first; j < u.points.end; ++j) {
    CounterRng rng(seed, ReplicatePlan::stream(points.stream(), u.q), j);
    const std::size_t f = points.place(u.q, j, rng);
    const double u1 = rng.uniform();
    const double u2 = rng.uniform();
    const Vec3 x = scene.facet_point(f - first, u1, u2);
    const SourcePlane plane = scene.facet_plane(f - first);
    const bool buried = points.buried(f);
    const bool see_o = !buried && !scene.occluded(x, o, &plane, tc);
    const bool see_i = o == i ? see_o : !buried && !scene.occluded(x, i, &plane, tc);
    std::uint64_t* at = c.data() + static_cast<std::size_t>(points.bin(f)) * kCounts;
    at[0] += 1;
    at[1] += see_o;
    at[2] += see_i;
    at[3] += see_o && see_i;
  }
}

// The units, part after part: each replicate's run of points on the part's facets, cut in
// chunks.
std::vector<G2Unit> g2_units(const G2Points& points, UnitRange reps) {
  std::vector<G2Unit> units;
  for (std::size_t k = 0; k < points.parts(); ++k)
    for (int q = static_cast<int>(reps.first); q < static_cast<int>(reps.end); ++q) {
      const UnitRange run = points.points_on(q, points.facets(k));
      for (std::uint64_t j = run.first; j < run.end; j += kChunk)
        units.push_back({k, q, {j, std::min(run.end, j + kChunk)}});
    }
  return units;
}

// Empty per-replicate counts of r.bins (R each).
void clear_g2_counts(G2Result& r) {
  for (G2NormalBin& nb : r.bins)
    for (auto* x : {&nb.samples_r, &nb.visible_o_r, &nb.visible_i_r, &nb.visible_both_r}) x->assign(r.replicates, 0);
}

// A finished unit's counts added into its replicate's counts of r.bins. Integer sums: the
// order the units are added in does not change them.
void add_g2_counts(G2Result& r, int q, const G2Counts& c) {
  for (std::size_t b = 0; b < r.bins.size(); ++b) {
    G2NormalBin& nb = r.bins[b];
    const std::uint64_t* at = c.data() + b * kCounts;
    nb.samples_r[q] += at[0];
    nb.visible_o_r[q] += at[1];
    nb.visible_i_r[q] += at[2];
    nb.visible_both_r[q] += at[3];
  }
}

}  // namespace

void trace_g2_points(const G2Points& points, G2Result& r, const G2Options& opt, const ReplicatePlan& plan) {
  const int nbins = r.binning.size();
  const UnitRange reps = share_of(opt.split, static_cast<std::uint64_t>(plan.replicates));
  // The list of units is held until the end: refused before the work when it would not fit in
  // memory (rather than ending in std::bad_alloc). At most ceil(n / kChunk) + parts units a
  // replicate. Their counts live only while their pass runs (kUnitsPerPass at a time).
  const double most = static_cast<double>(reps.size()) *
                      (static_cast<double>(chunks_per_replicate(plan.per_replicate(), kChunk)) + points.parts());
  require_memory(most * sizeof(G2Unit) + kUnitsPerPass * (sizeof(TraceCounters) + kCounts * nbins * 8.0),
                 "{rays} " + std::to_string(opt.rays) + " (" + std::to_string(static_cast<std::uint64_t>(most)) +
                     " work units, " + std::to_string(nbins) + " normal bins)");
  const std::vector<G2Unit> units = g2_units(points, reps);
  // The counts of a pass's units: a pass starts at a multiple of kUnitsPerPass (run_part_passes).
  std::vector<G2Counts> counts(std::min(units.size(), kUnitsPerPass));
  std::vector<TraceCounters> tc(counts.size());
  clear_g2_counts(r);
  const double mine = static_cast<double>(plan.per_replicate() * reps.size());
  std::uint64_t done = 0;
  std::size_t counted = 0;
  run_part_passes(
      units.size(), kUnitsPerPass, [&](std::size_t u) { return units[u].part; },
      [&](std::size_t k) { return points.scene(k); },
      [&](std::size_t u, const Scene& scene) {
        const std::size_t slot = u % kUnitsPerPass;
        tc[slot] = TraceCounters{};
        trace_g2_unit(points, scene, r.o, r.i, units[u], opt.seed, nbins, counts[slot], tc[slot]);
      },
      [&](std::size_t units_done) {
        for (; counted < units_done; ++counted) {  // the pass's units, in unit order
          const std::size_t slot = counted % kUnitsPerPass;
          add_g2_counts(r, units[counted].q, counts[slot]);
          r.counters += tc[slot];
          done += units[counted].points.size();
        }
        if (opt.progress) opt.progress(static_cast<double>(done) / mine);
      });
  finish_g2(r, opt, reps);
}

}  // namespace microsim
