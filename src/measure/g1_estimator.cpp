// The steps of the G1 estimator shared by every scene (g1_estimator.hpp).
#include "g1_estimator.hpp"

#include <string>

#include "microsim/io/checks.hpp"

namespace microsim {

DirectionBinning g1_normal_binning(const G1Options& o) {
  return DirectionBinning(o.normal_theta_bins, o.normal_phi_bins, kPi);
}

G1Result start_g1(const Vec3& v, const G1Options& o, double macro_area) {
  G1Result r;
  r.v = v.normalized();
  r.theta = theta_of(r.v);
  r.phi = phi_of(r.v);
  r.macro_area = macro_area;
  r.binning = g1_normal_binning(o);
  r.bins.assign(r.binning.size(), G1NormalBin{});
  return r;
}

namespace {

// Counts received from other processes (or read back from a merge's parts) must be possible:
// per replicate at most its rays hit or are sampled, and no bin has more visible samples than
// samples. UsageError naming the field otherwise (a part edited by hand, or damaged).
void require_possible_g1_counts(const G1Tally& t, std::size_t q, G1RaysPerReplicate n) {
  std::uint64_t hits = 0, samples = 0;
  for (std::size_t b = 0; b < t.samples.size(); ++b) {
    if (t.visible[b] > t.samples[b])
      throw UsageError("g1 tallies of replicate " + std::to_string(q) + ": visible[" + std::to_string(b) + "] = " +
                       std::to_string(t.visible[b]) + " exceeds samples[" + std::to_string(b) + "] = " +
                       std::to_string(t.samples[b]) + " (a damaged or edited part)");
    hits += t.hits[b];
    samples += t.samples[b];
    if (hits > n.raycast || samples > n.samples)
      throw UsageError("g1 tallies of replicate " + std::to_string(q) + ": " +
                       (hits > n.raycast ? "hits exceed its " + std::to_string(n.raycast)
                                         : "samples exceed its " + std::to_string(n.samples)) +
                       " rays (a damaged or edited part)");
  }
}

// Completes the replicates' tallies from the other processes (measure/shards.hpp): per
// replicate the ray-casting hits, the area samples and the visible samples of every bin, field
// after field; then the trace counters.
void exchange_g1(TallySplit& split, UnitRange reps, std::vector<G1Tally>& tallies, TraceCounters& counters,
                 G1RaysPerReplicate rays) {
  const std::size_t R = tallies.size();
  const int nbins = static_cast<int>(R ? tallies[0].hits.size() : 0);
  Tallies t("g1", R, reps, field_sizes(G1Tally(nbins)).counts, 0, kCounterValues, 0);
  for (std::size_t q = 0; q < R; ++q) pack_fields(tallies[q], t.count_row(q));
  put_counters(counters, t.tail_counts.data());
  split.exchange(t);
  for (std::size_t q = 0; q < R; ++q) {
    unpack_fields(tallies[q], t.count_row(q));
    require_possible_g1_counts(tallies[q], q, rays);
  }
  counters = get_counters(t.tail_counts.data());
}

// Per-replicate totals and per-bin counts from the replicates' tallies.
void set_g1_counts(G1Result& r, const std::vector<G1Tally>& tallies) {
  const int R = r.replicates, nbins = r.binning.size();
  r.raycast_hits_r.assign(R, 0);
  r.sample_visible_r.assign(R, 0);
  r.raycast_hits = r.sample_visible = 0;
  for (int b = 0; b < nbins; ++b) {
    G1NormalBin& nb = r.bins[b];
    nb.raycast_hits_r.assign(R, 0);
    nb.samples_r.assign(R, 0);
    nb.visible_r.assign(R, 0);
    nb.raycast_hits = nb.samples = nb.visible = 0;
    for (int q = 0; q < R; ++q) {
      nb.raycast_hits_r[q] = tallies[q].hits[b];
      nb.samples_r[q] = tallies[q].samples[b];
      nb.visible_r[q] = tallies[q].visible[b];
      nb.raycast_hits += nb.raycast_hits_r[q];
      nb.samples += nb.samples_r[q];
      nb.visible += nb.visible_r[q];
      r.raycast_hits_r[q] += nb.raycast_hits_r[q];
      r.sample_visible_r[q] += nb.visible_r[q];
    }
    r.raycast_hits += nb.raycast_hits;
    r.sample_visible += nb.visible;
  }
}

}  // namespace

void finish_g1(G1Result& r, std::vector<G1Tally>& tallies, const TraceCounters& counters, TallySplit* split,
               UnitRange reps, G1RaysPerReplicate rays) {
  r.counters = counters;
  if (split) exchange_g1(*split, reps, tallies, r.counters, rays);
  set_g1_counts(r, tallies);
}

}  // namespace microsim
