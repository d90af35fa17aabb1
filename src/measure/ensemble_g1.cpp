// The G1 estimator on an ensemble scene (measure/ensemble_estimators.hpp): the estimator of
// g1_estimator.hpp, its rays planned part by part.
#include "microsim/measure/ensemble_estimators.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <string>

#include "ensemble_parts.hpp"
#include "estimator_steps.hpp"
#include "g1_estimator.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"

namespace microsim {

namespace {

std::uint64_t view_stream(std::uint64_t base, std::size_t view) { return base + 7919 * view; }

// The ray-casting plan: at least one ray per part and replicate, so that every replicate covers
// every part.
ReplicatePlan part_plan_of(const SceneEnsemble& e, const G1Options& o) {
  const std::size_t K = e.parts();
  return ReplicatePlan(std::max<std::uint64_t>((o.rays + K - 1) / K, static_cast<std::uint64_t>(std::max(0, o.replicates))),
                       o.replicates);
}

// The G1 measurement of an ensemble in progress: its plans, per-view results, CDFs and tallies.
struct EnsembleG1 {
  EnsembleG1(const SceneEnsemble& ensemble, const G1Options& options, std::size_t views)
      : e(ensemble), o(options), nv(views), part_plan(part_plan_of(ensemble, options)) {}
  const SceneEnsemble& e;
  const G1Options& o;
  std::size_t nv = 0;
  int nbins = 0, R = 0;
  std::vector<int> bin;  // per ensemble facet
  std::vector<G1Result> results;
  std::vector<std::vector<double>> cdfs;  // per view: front-facing projected area
  std::uint64_t per_part = 0, n_samples = 0;
  ReplicatePlan part_plan;
  UnitRange reps;
  std::vector<std::vector<G1Tally>> tallies;  // [view][replicate]
  std::vector<TraceCounters> counters;        // per view
  std::mutex adding;  // the parts add their counts to tallies and counters one at a time
};

// Result iv: its header and exact facet sums per bin (sum_g1_facets), and its CDF of front
// projected area.
void sum_g1_view(EnsembleG1& g, std::size_t iv, const Vec3& view) {
  const SceneEnsemble& e = g.e;
  G1Result& r = g.results[iv] = start_g1(view, g.o, e.macro_area());
  sum_g1_facets(r, e.num_facets(), r.v.z() * r.macro_area, [&](std::size_t j, Vec3& m, double& a) {
    m = e.facet_normal(j);
    a = e.facet_area(j);
    return g.bin[j];
  });
  std::vector<double>& cdf = g.cdfs[iv];
  for (std::size_t j = 0; j < e.num_facets(); ++j)
    cdf[j] = (j ? cdf[j - 1] : 0.0) + std::max(0.0, e.facet_area(j) * r.v.dot(e.facet_normal(j)));
  r.front_projected = cdf.back();
  r.window_area_perp = r.v.z() * r.macro_area;  // the parts' windows seen along v
}

// The area-sampling plan and the per-view sums.
void start_ensemble_g1(EnsembleG1& g, const std::vector<Vec3>& views) {
  const std::size_t K = g.e.parts(), nf = g.e.num_facets();
  const DirectionBinning binning = g1_normal_binning(g.o);
  g.nbins = binning.size();
  g.bin.resize(nf);
  for (std::size_t j = 0; j < nf; ++j) g.bin[j] = binning.bin_of(g.e.facet_normal(j));
  g.R = g.part_plan.replicates;
  const ReplicatePlan sample_plan(std::max<std::uint64_t>(g.o.rays, g.R), g.R);
  g.per_part = g.part_plan.per_replicate();
  g.n_samples = sample_plan.per_replicate();
  g.results.resize(g.nv);
  g.cdfs.assign(g.nv, std::vector<double>(nf));
  for (std::size_t iv = 0; iv < g.nv; ++iv) {
    sum_g1_view(g, iv, views[iv]);
    G1Result& r = g.results[iv];
    r.replicates = g.R;
    r.raycast_rays = g.per_part * K * g.R;
    r.sample_rays = g.n_samples * sample_plan.replicates;
  }
  g.reps = share_of(g.o.split, static_cast<std::uint64_t>(g.R));
  g.tallies.assign(g.nv, std::vector<G1Tally>(g.R, G1Tally(g.nbins)));
  g.counters.assign(g.nv, TraceCounters{});
}

// Part k's counts of view iv, per replicate of this process and facet of the part (`part`: one
// G1Tally per replicate whose bins are the part's facets), added to the view's tallies by the
// facets' normal bins.
void add_part_counts(EnsembleG1& g, std::size_t iv, const SceneEnsemble::Part& p, const std::vector<G1Tally>& part) {
  const std::lock_guard<std::mutex> lock(g.adding);
  for (std::size_t i = 0; i < part.size(); ++i) {
    G1Tally& t = g.tallies[iv][g.reps.first + i];
    for (std::size_t f = 0; f < p.facets; ++f) {
      const int b = g.bin[p.first_facet + f];
      t.hits[b] += part[i].hits[f];
      t.samples[b] += part[i].samples[f];
      t.visible[b] += part[i].visible[f];
    }
    g.counters[iv] += part[i].counters;
  }
}

// Part k, every view and replicate of this process, with the estimator's kernels on the part's
// scene in its own frame: (a) stratified rays over its window along -v (cast_g1_ray), (b) its
// share of each replicate's area samples (sample_g1_point).
void trace_g1_part(EnsembleG1& g, const std::vector<CdfSamples>& samples, std::size_t k) {
  const SceneEnsemble::Part& p = g.e.part(k);
  const std::unique_ptr<Scene> scene = g.e.build(k);
  const int nf = static_cast<int>(p.facets);
  const auto facet_itself = [](const TraceHit&, std::size_t f) { return static_cast<int>(f); };
  std::vector<G1Tally> part(g.reps.size(), G1Tally(nf));  // per replicate of this process
  for (std::size_t iv = 0; iv < g.nv; ++iv) {
    const Vec3 vl = p.frame.to_local(g.results[iv].v);
    const RayWindow w = scene->ray_window(vl);
    std::fill(part.begin(), part.end(), G1Tally(nf));
    for (int q = static_cast<int>(g.reps.first); q < static_cast<int>(g.reps.end); ++q) {
      G1Tally& t = part[q - g.reps.first];
      const std::uint64_t stream =
          ReplicatePlan::stream(view_stream(0xA000, iv) + (static_cast<std::uint64_t>(k) << 24), q);
      for (std::uint64_t i = 0; i < g.per_part; ++i) {
        CounterRng rng(g.o.seed, stream, i);
        cast_g1_ray(*scene, window_point(w, g.part_plan.strata.point(i, rng)), vl, facet_itself, t);
      }
      const auto lo = static_cast<std::uint32_t>(p.first_facet), hi = static_cast<std::uint32_t>(p.first_facet + nf);
      samples[iv].for_each(q, lo, hi, [&](std::uint64_t i, std::uint32_t j) {
        CounterRng rng = samples[iv].rng(q, i);
        const Vec3 x = draw_point(*scene, p, j, rng);
        sample_g1_point(*scene, x, vl, scene->facet_plane(j - lo), static_cast<int>(j - lo), t);
      });
    }
    add_part_counts(g, iv, p, part);
  }
}

}  // namespace

std::vector<G1Result> measure_g1(const SceneEnsemble& e, const std::vector<Vec3>& views,
                                 const G1Options& o) {
  require_equal_parts(e, "measure_g1");
  if (o.rays == 0) throw ParameterError("{rays} must be positive");
  for (const Vec3& v : views)
    if (!(v.z() > 1e-12 * v.norm()))
      throw ParameterError("{theta} must be in [0, 90) degrees for a vcavity ensemble (its grooves are "
                           "heightfields)");
  const auto t0 = std::chrono::steady_clock::now();
  EnsembleG1 g(e, o, views.size());
  start_ensemble_g1(g, views);
  // Area sampling: per view, the stratified samples of every replicate along its CDF, each part
  // handling the contiguous run of each replicate's samples on its facets. Only the replicates
  // of this process are traced (measure/shards.hpp).
  std::vector<CdfSamples> samples;
  for (std::size_t iv = 0; iv < g.nv; ++iv)
    samples.emplace_back(g.cdfs[iv], o.seed, view_stream(0xC000, iv), g.n_samples, g.reps);
  tbb::parallel_for(std::size_t(0), e.parts(), [&](std::size_t k) { trace_g1_part(g, samples, k); });
  const G1RaysPerReplicate rays{g.per_part * e.parts(), g.n_samples};
  for (std::size_t iv = 0; iv < g.nv; ++iv) finish_g1(g.results[iv], g.tallies[iv], g.counters[iv], o.split, g.reps, rays);
  const double seconds = seconds_since(t0);
  for (auto& r : g.results) r.seconds = seconds / g.nv;
  if (o.progress) o.progress(1.0);
  return std::move(g.results);
}

}  // namespace microsim
