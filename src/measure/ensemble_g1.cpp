// The G1 estimators on an ensemble scene (measure/ensemble_estimators.hpp).
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

namespace {

// Per view, replicate and normal bin: ray-cast hits, area samples and visible samples.
// Integer sums, added atomically part by part: exact, so identical for any thread count.
struct G1Counts {
  std::atomic<std::uint64_t> hits{0}, samples{0}, visible{0};
  // The counts exchanged per replicate, in measure_g1's order (its tally's for_each_field).
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f("hits", &G1Counts::hits);
    f("samples", &G1Counts::samples);
    f("visible", &G1Counts::visible);
  }
};

std::uint64_t view_stream(std::uint64_t base, std::size_t view) { return base + 7919 * view; }

// The G1 measurement of an ensemble in progress: its plans, per-view results and CDFs, counts.
// The ray-casting plan: at least one ray per part and replicate, so that every replicate covers
// every part.
ReplicatePlan part_plan_of(const SceneEnsemble& e, const G1Options& o) {
  const std::size_t K = e.parts();
  return ReplicatePlan(std::max<std::uint64_t>((o.rays + K - 1) / K, static_cast<std::uint64_t>(std::max(0, o.replicates))),
                       o.replicates);
}

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
  std::vector<G1Counts> counts;  // (view, replicate, bin)
  std::vector<TraceCounters> part_counters;  // (part, view)
  G1Counts& at(std::size_t iv, int q, int b) { return counts[(iv * R + q) * nbins + b]; }
};

// Result iv's header and exact facet sums per bin, and its CDF of front projected area.
void sum_g1_facets(EnsembleG1& g, std::size_t iv, const Vec3& view) {
  const SceneEnsemble& e = g.e;
  G1Result& r = g.results[iv];
  r.v = view.normalized();
  r.theta = theta_of(r.v);
  r.phi = phi_of(r.v);
  r.macro_area = e.macro_area();
  r.bins.assign(g.nbins, G1NormalBin{});
  double back = 0;
  std::vector<double>& cdf = g.cdfs[iv];
  for (std::size_t j = 0; j < e.num_facets(); ++j) {
    const Vec3& m = e.facet_normal(j);
    const double area = e.facet_area(j), proj = area * r.v.dot(m);
    G1NormalBin& nb = r.bins[g.bin[j]];
    const double front = std::max(0.0, proj);
    nb.area += area;
    nb.front_projected += front;
    nb.mean_normal += front * m;
    if (front > 0) nb.vcavity_weighted += front * models::vcavity_G1(r.v, m);
    back += std::max(0.0, -proj);
    r.total_area += area;
    cdf[j] = (j ? cdf[j - 1] : 0.0) + front;
  }
  for (auto& nb : r.bins)
    if (nb.mean_normal.norm() > 0) nb.mean_normal.normalize();
  r.front_projected = cdf.back();
  r.lambda_numeric = back / (r.v.z() * r.macro_area);  // [Heitz14, App. A]
  r.window_area_perp = r.v.z() * r.macro_area;          // the parts' windows seen along v
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
    G1Result& r = g.results[iv];
    r.binning = binning;
    sum_g1_facets(g, iv, views[iv]);
    r.replicates = g.R;
    r.raycast_rays = g.per_part * K * g.R;
    r.sample_rays = g.n_samples * sample_plan.replicates;
  }
  g.reps = share_of(g.o.split, static_cast<std::uint64_t>(g.R));
  g.counts = std::vector<G1Counts>(g.nv * g.R * g.nbins);
  g.part_counters.assign(K * g.nv, TraceCounters{});
}

// Part k, every view and replicate of this process: (a) stratified rays over its window along
// -v, (b) its share of each replicate's area samples.
void trace_g1_part(EnsembleG1& g, const std::vector<CdfSamples>& samples, std::size_t k) {
  const SceneEnsemble::Part& p = g.e.part(k);
  const std::unique_ptr<Scene> scene = g.e.build(k);
  const std::size_t nf = p.facets;
  std::vector<std::uint64_t> hits(nf), drawn(nf), visible(nf);  // per facet of the part
  for (std::size_t iv = 0; iv < g.nv; ++iv) {
    TraceCounters& tc = g.part_counters[k * g.nv + iv];
    const Vec3 vl = p.frame.to_local(g.results[iv].v);
    const RayWindow w = scene->ray_window(vl);
    for (int q = static_cast<int>(g.reps.first); q < static_cast<int>(g.reps.end); ++q) {
      for (auto* x : {&hits, &drawn, &visible}) std::fill(x->begin(), x->end(), 0);
      const std::uint64_t stream =
          ReplicatePlan::stream(view_stream(0xA000, iv) + (static_cast<std::uint64_t>(k) << 24), q);
      for (std::uint64_t i = 0; i < g.per_part; ++i) {
        CounterRng rng(g.o.seed, stream, i);
        const Vec2 ab = g.part_plan.strata.point(i, rng);
        const TraceHit h = scene->intersect(w.origin0 + ab.x() * w.e1 + ab.y() * w.e2, -vl, nullptr, tc);
        const std::size_t f = scene->front_facet(h);
        if (f != Scene::kNoFacet) ++hits[f];
      }
      const auto lo = static_cast<std::uint32_t>(p.first_facet), hi = static_cast<std::uint32_t>(p.first_facet + nf);
      samples[iv].for_each(q, lo, hi, [&](std::uint64_t i, std::uint32_t j) {
        CounterRng rng = samples[iv].rng(q, i);
        const SourcePlane plane = scene->facet_plane(j - lo);
        ++drawn[j - lo];
        if (!scene->occluded(draw_point(*scene, p, j, rng), vl, &plane, tc)) ++visible[j - lo];
      });
      for (std::size_t f = 0; f < nf; ++f) {
        G1Counts& c = g.at(iv, q, g.bin[p.first_facet + f]);
        c.hits += hits[f];
        c.samples += drawn[f];
        c.visible += visible[f];
      }
    }
  }
}

// The other processes' replicates, view by view, in measure_g1's tally layout.
void exchange_ensemble_g1(EnsembleG1& g, std::size_t iv) {
  const std::size_t nb = static_cast<std::size_t>(g.nbins);
  // Field f of bin b at f * nb + b, as measure_g1 packs its per-bin vectors.
  const auto each_count = [&](auto&& fn) {
    std::size_t f = 0;
    G1Counts::for_each_field([&](const char*, auto member) {
      for (int q = 0; q < g.R; ++q)
        for (int b = 0; b < g.nbins; ++b) fn(g.at(iv, q, b).*member, q, f * nb + b);
      ++f;
    });
  };
  std::size_t fields = 0;
  G1Counts::for_each_field([&](const char*, auto) { ++fields; });
  Tallies t("g1", g.R, g.reps, fields * nb, 0, kCounterValues, 0);
  each_count([&](const std::atomic<std::uint64_t>& c, int q, std::size_t pos) { t.count_row(q)[pos] = c; });
  put_counters(g.results[iv].counters, t.tail_counts.data());
  g.o.split->exchange(t);
  each_count([&](std::atomic<std::uint64_t>& c, int q, std::size_t pos) { c = t.count_row(q)[pos]; });
  g.results[iv].counters = get_counters(t.tail_counts.data());
}

// Per-replicate counts of view iv into its result.
void set_ensemble_g1_counts(EnsembleG1& g, std::size_t iv) {
  G1Result& r = g.results[iv];
  const int R = g.R;
  r.raycast_hits_r.assign(R, 0);
  r.sample_visible_r.assign(R, 0);
  for (int b = 0; b < g.nbins; ++b) {
    G1NormalBin& nb = r.bins[b];
    nb.raycast_hits_r.assign(R, 0);
    nb.samples_r.assign(R, 0);
    nb.visible_r.assign(R, 0);
    for (int q = 0; q < R; ++q) {
      const G1Counts& c = g.at(iv, q, b);
      nb.raycast_hits_r[q] = c.hits;
      nb.samples_r[q] = c.samples;
      nb.visible_r[q] = c.visible;
      nb.raycast_hits += c.hits;
      nb.samples += c.samples;
      nb.visible += c.visible;
      r.raycast_hits_r[q] += c.hits;
      r.sample_visible_r[q] += c.visible;
    }
    r.raycast_hits += nb.raycast_hits;
    r.sample_visible += nb.visible;
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
  for (std::size_t iv = 0; iv < g.nv; ++iv)  // in part order
    for (std::size_t k = 0; k < e.parts(); ++k) g.results[iv].counters += g.part_counters[k * g.nv + iv];
  for (std::size_t iv = 0; iv < g.nv; ++iv) {
    if (o.split) exchange_ensemble_g1(g, iv);
    set_ensemble_g1_counts(g, iv);
  }
  const double seconds = seconds_since(t0);
  for (auto& r : g.results) r.seconds = seconds / g.nv;
  if (o.progress) o.progress(1.0);
  return std::move(g.results);
}

}  // namespace microsim
