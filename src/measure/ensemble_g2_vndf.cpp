// The G2 and VNDF estimators on an ensemble scene (measure/ensemble_estimators.hpp).
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

}  // namespace microsim
