#include "microsim/measure/ensemble_estimators.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <string>

#include "estimator_steps.hpp"
#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/models/vgroove_multiple.hpp"

namespace microsim {

namespace {

void require_equal_parts(const SceneEnsemble& e, const char* what) {
  if (e.parts() == 0 || !e.equal_weights())
    throw UsageError(std::string(what) + ": the ensemble's parts must cover equal shares of the macro area");
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The point of ensemble facet j of part k drawn by rng (two draws), in the part's frame.
Vec3 draw_point(const Scene& scene, const SceneEnsemble::Part& p, std::size_t j, CounterRng& rng) {
  const double u = rng.uniform();
  const double w = rng.uniform();
  return scene.facet_point(j - p.first_facet, u, w);
}

// ---- G1 ----------------------------------------------------------------------------------------

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

// ---- G2 ----------------------------------------------------------------------------------------

namespace {

// Exact sums over the ensemble's facets (the weights and models of measure_g2); returns the CDF
// of w_f and sets bin[j].
std::vector<double> sum_g2_facets(G2Result& r, const SceneEnsemble& e, std::vector<int>& bin) {
  const Vec3 o = r.o, i = r.i;
  const std::size_t nf = e.num_facets();
  std::vector<double> cdf(nf);
  bin.resize(nf);
  double back_o = 0, back_i = 0, vcav_total = 0;
  for (std::size_t j = 0; j < nf; ++j) {
    const Vec3& m = e.facet_normal(j);
    const double a = e.facet_area(j), om = o.dot(m), im = i.dot(m);
    bin[j] = r.binning.bin_of(m);
    G2NormalBin& nb = r.bins[bin[j]];
    const bool front = om > 0 && im > 0;
    const double w = front ? 0.5 * a * (om + im) : 0.0;
    nb.area += a;
    r.total_area += a;
    if (front) {
      nb.front_area += a;
      nb.weight += w;
      nb.mean_normal += w * m;
      const double v2 = w * models::vcavity_G2(o, i, m);  // [Heitz14, eq. 24 and Sec. 6]
      nb.vcavity_sum += v2;
      vcav_total += v2;
      r.front_area += a;
    }
    back_o += a * std::max(0.0, -om);
    back_i += a * std::max(0.0, -im);
    cdf[j] = (j ? cdf[j - 1] : 0.0) + w;
  }
  for (auto& nb : r.bins)
    if (nb.mean_normal.norm() > 0) nb.mean_normal.normalize();
  r.lambda_o = back_o / (o.z() * r.macro_area);  // [Heitz14, App. A]
  r.lambda_i = back_i / (i.z() * r.macro_area);
  r.weight = cdf.back();
  if (!(r.weight > 0)) throw RuntimeFailure("no facet faces both directions");
  r.vcavity = vcav_total / r.weight;
  return cdf;
}

struct G2Counts {
  std::atomic<std::uint64_t> samples{0}, vis_o{0}, vis_i{0}, vis_both{0};
};

// Part k's share of the samples of the replicates `reps`: two occlusion rays each.
void trace_g2_part(const SceneEnsemble& e, std::size_t k, const G2Result& r, const CdfSamples& samples,
                   UnitRange reps, const std::vector<int>& bin, std::vector<G2Counts>& counts,
                   TraceCounters& tc) {
  const SceneEnsemble::Part& p = e.part(k);
  const std::unique_ptr<Scene> scene = e.build(k);
  const Vec3 ol = p.frame.to_local(r.o), il = p.frame.to_local(r.i);
  const std::size_t nf = p.facets, nbins = static_cast<std::size_t>(r.binning.size());
  const auto lo = static_cast<std::uint32_t>(p.first_facet), hi = static_cast<std::uint32_t>(p.first_facet + nf);
  std::vector<std::uint64_t> n(nf), vo(nf), vi(nf), vb(nf);  // per facet of the part
  for (int q = static_cast<int>(reps.first); q < static_cast<int>(reps.end); ++q) {
    for (auto* x : {&n, &vo, &vi, &vb}) std::fill(x->begin(), x->end(), 0);
    samples.for_each(q, lo, hi, [&](std::uint64_t j, std::uint32_t f) {
      CounterRng rng = samples.rng(q, j);
      const Vec3 x = draw_point(*scene, p, f, rng);
      const SourcePlane plane = scene->facet_plane(f - lo);
      const bool see_o = !scene->occluded(x, ol, &plane, tc);
      const bool see_i = r.o == r.i ? see_o : !scene->occluded(x, il, &plane, tc);
      ++n[f - lo];
      vo[f - lo] += see_o;
      vi[f - lo] += see_i;
      vb[f - lo] += see_o && see_i;
    });
    for (std::size_t f = 0; f < nf; ++f) {
      G2Counts& c = counts[static_cast<std::size_t>(q) * nbins + bin[p.first_facet + f]];
      c.samples += n[f];
      c.vis_o += vo[f];
      c.vis_i += vi[f];
      c.vis_both += vb[f];
    }
  }
}

}  // namespace

G2Result measure_g2(const SceneEnsemble& e, const Vec3& o_in, const Vec3& i_in, const G2Options& opt) {
  require_equal_parts(e, "measure_g2");
  G2Result r = start_g2(o_in, i_in, opt, e.macro_area());
  const auto t0 = std::chrono::steady_clock::now();
  const int nbins = r.binning.size();
  std::vector<int> bin;
  const std::vector<double> cdf = sum_g2_facets(r, e, bin);
  // Stratified samples along the CDF per replicate (this process's replicates only), each part
  // handling the contiguous run of each replicate's samples on its facets.
  const ReplicatePlan plan = plan_g2(r, opt);
  const int R = plan.replicates;
  const UnitRange reps = share_of(opt.split, static_cast<std::uint64_t>(R));
  const CdfSamples samples(cdf, opt.seed, pair_stream(r.o, r.i, 0xC3000000ull), plan.per_replicate(), reps);
  std::vector<G2Counts> counts(static_cast<std::size_t>(R) * nbins);
  std::vector<TraceCounters> part_counters(e.parts());
  tbb::parallel_for(std::size_t(0), e.parts(), [&](std::size_t k) {
    trace_g2_part(e, k, r, samples, reps, bin, counts, part_counters[k]);
  });
  for (int b = 0; b < nbins; ++b) {
    G2NormalBin& nb = r.bins[b];
    for (auto* x : {&nb.samples_r, &nb.visible_o_r, &nb.visible_i_r, &nb.visible_both_r}) x->assign(R, 0);
    for (int q = 0; q < R; ++q) {
      const G2Counts& c = counts[static_cast<std::size_t>(q) * nbins + b];
      nb.samples_r[q] = c.samples;
      nb.visible_o_r[q] = c.vis_o;
      nb.visible_i_r[q] = c.vis_i;
      nb.visible_both_r[q] = c.vis_both;
    }
  }
  for (const TraceCounters& c : part_counters) r.counters += c;  // in part order
  finish_g2(r, opt, reps);
  r.seconds = seconds_since(t0);
  if (opt.progress) opt.progress(1.0);
  return r;
}

// ---- VNDF --------------------------------------------------------------------------------------

namespace {

// This process's rays (`share`) bucketed by the part their first draw picks (a counting sort,
// in ray order), so that each part's scene is built once: rays order[start[k] .. start[k+1]).
struct RaysByPart {
  std::vector<std::uint64_t> start, order;
};
RaysByPart rays_by_part(const SceneEnsemble& e, std::uint64_t seed, std::uint64_t stream, UnitRange share) {
  const std::size_t K = e.parts();
  std::vector<std::uint32_t> part_of(share.size());
  tbb::parallel_for(std::uint64_t(0), share.size(), [&](std::uint64_t n) {
    CounterRng rng(seed, stream, share.first + n);
    part_of[n] = static_cast<std::uint32_t>(e.part_at(rng.uniform()));
  });
  RaysByPart b;
  b.start.assign(K + 1, 0);
  for (std::uint32_t k : part_of) ++b.start[k + 1];
  for (std::size_t k = 0; k < K; ++k) b.start[k + 1] += b.start[k];
  b.order.resize(share.size());
  std::vector<std::uint64_t> next(b.start.begin(), b.start.end() - 1);
  for (std::uint64_t n = 0; n < share.size(); ++n) b.order[next[part_of[n]]++] = share.first + n;
  return b;
}

}  // namespace

VndfResult measure_vndf(const SceneEnsemble& e, const Vec3& v_in, const VndfOptions& o) {
  require_equal_parts(e, "measure_vndf");
  VndfResult r = start_vndf(v_in, o, e.macro_area());
  const auto t0 = std::chrono::steady_clock::now();
  const Vec3 v = r.v;
  const int nbins = r.binning.size();
  const std::size_t nf = e.num_facets();
  std::vector<int> bin(nf);
  r.front_projected.assign(nbins, 0.0);
  for (std::size_t j = 0; j < nf; ++j) {
    bin[j] = r.binning.bin_of(e.facet_normal(j));
    const double proj = std::max(0.0, e.facet_area(j) * v.dot(e.facet_normal(j)));
    if (bin[j] >= 0) r.front_projected[bin[j]] += proj;
    r.front_projected_total += proj;
  }
  if (!(r.front_projected_total > 0)) throw RuntimeFailure("no facet faces the direction");
  r.window_area_perp = v.z() * r.macro_area;  // the parts' windows seen along v
  // Ray j: part, then origin on its window, all from its own counter (i.i.d. rays).
  const UnitRange share = share_of(o.split, r.rays);
  const std::uint64_t stream = 0xD100 + direction_stream_key(v);
  const RaysByPart rays = rays_by_part(e, o.seed, stream, share);
  std::vector<std::atomic<std::uint64_t>> counts(static_cast<std::size_t>(nbins) + 1);
  std::vector<TraceCounters> part_counters(e.parts());
  tbb::parallel_for(std::size_t(0), e.parts(), [&](std::size_t k) {
    if (rays.start[k] == rays.start[k + 1]) return;
    const SceneEnsemble::Part& p = e.part(k);
    const std::unique_ptr<Scene> scene = e.build(k);
    const Vec3 vl = p.frame.to_local(v);
    const RayWindow w = scene->ray_window(vl);
    std::vector<std::uint64_t> hits(p.facets);
    for (std::uint64_t n = rays.start[k]; n < rays.start[k + 1]; ++n) {
      CounterRng rng(o.seed, stream, rays.order[n]);
      rng.uniform();  // the draw that chose the part
      const double a = rng.uniform();
      const double b = rng.uniform();
      const std::size_t f = scene->front_facet(scene->intersect(w.origin0 + a * w.e1 + b * w.e2, -vl, nullptr, part_counters[k]));
      if (f != Scene::kNoFacet) ++hits[f];
    }
    for (std::size_t f = 0; f < p.facets; ++f) {
      const int b = bin[p.first_facet + f];
      counts[b >= 0 ? static_cast<std::size_t>(b) : static_cast<std::size_t>(nbins)] += hits[f];
    }
  });
  for (const TraceCounters& c : part_counters) r.counters += c;  // in part order
  finish_vndf(r, o, share, std::vector<std::uint64_t>(counts.begin(), counts.end()));
  r.seconds = seconds_since(t0);
  if (o.progress) o.progress(1.0);
  return r;
}

// ---- BSDF --------------------------------------------------------------------------------------

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
