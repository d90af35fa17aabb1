#include "estimator_steps.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "microsim/measure/sampling.hpp"

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
}  // namespace

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

VndfResult start_vndf(const Vec3& v, const VndfOptions& o, double macro_area) {
  if (!(v.z() > 0)) throw ParameterError("{theta} must be in [0, 90) degrees");
  if (o.rays == 0) throw ParameterError("{rays} must be positive");
  VndfResult r;
  r.v = v.normalized();
  r.binning = vndf_binning(o);
  r.macro_area = macro_area;
  r.rays = o.rays;
  return r;
}

void finish_vndf(VndfResult& r, const VndfOptions& o, UnitRange share, std::vector<std::uint64_t> counts) {
  const int nbins = r.binning.size();
  if (o.split) {
    // Integer bin counts and counters: the other processes' rays are added (measure/shards.hpp).
    Tallies t("vndf", r.rays, share, 0, 0, counts.size() + kCounterValues, 0);
    std::copy(counts.begin(), counts.end(), t.tail_counts.begin());
    put_counters(r.counters, t.tail_counts.data() + counts.size());
    o.split->exchange(t);
    std::copy(t.tail_counts.begin(), t.tail_counts.begin() + static_cast<std::ptrdiff_t>(counts.size()),
              counts.begin());
    r.counters = get_counters(t.tail_counts.data() + counts.size());
  }
  r.bin_hits.assign(counts.begin(), counts.begin() + nbins);
  r.hits_below = counts[nbins];
  for (auto c : counts) r.hits += c;
}

CdfSamples::CdfSamples(const std::vector<double>& cdf, std::uint64_t seed, std::uint64_t base,
                       std::uint64_t n, UnitRange reps)
    : seed_(seed), base_(base), n_(n), reps_(reps), facet_(reps.size() * n) {
  const double total = cdf.back();
  const std::size_t nf = cdf.size();
  tbb::parallel_for(std::uint64_t(0), reps.size() * n, [&](std::uint64_t g) {
    const int q = static_cast<int>(reps.first + g / n);
    const std::uint64_t i = g % n;
    CounterRng rng(seed, ReplicatePlan::stream(base, q), i);
    const double u = (static_cast<double>(i) + rng.uniform()) / n * total;
    std::size_t j = std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin();
    j = std::min(j, nf - 1);
    while (j > 0 && cdf[j] == cdf[j - 1]) --j;  // never a zero-weight facet
    facet_[g] = static_cast<std::uint32_t>(j);
  });
}

}  // namespace microsim
