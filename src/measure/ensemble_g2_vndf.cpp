// The G2 and VNDF estimators on an ensemble scene (measure/ensemble_estimators.hpp).
#include "microsim/measure/ensemble_estimators.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "ensemble_parts.hpp"
#include "estimator_steps.hpp"
#include "g2_estimator.hpp"
#include "vndf_estimator.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"

namespace microsim {

namespace {

// Exact sums over the ensemble's facets, in facet order (g2_facet_terms); returns the CDF of
// w_f and sets bin[j]. Not the whole surface's sum_over_facets (g2_measure.cpp): its totals are
// sums of per-bin block sums, these facet by facet, so one loop would change the records' last bits.
std::vector<double> sum_g2_facets(G2Result& r, const SceneEnsemble& e, std::vector<int>& bin) {
  const Vec3 o = r.o, i = r.i;
  const std::size_t nf = e.num_facets();
  std::vector<double> cdf(nf);
  bin.resize(nf);
  double back_o = 0, back_i = 0, vcav_total = 0;
  for (std::size_t j = 0; j < nf; ++j) {
    const Vec3& m = e.facet_normal(j);
    const double a = e.facet_area(j);
    const G2FacetTerms t = g2_facet_terms(o, i, m, a);
    bin[j] = r.binning.bin_of(m);
    G2NormalBin& nb = r.bins[bin[j]];
    nb.area += a;
    r.total_area += a;
    if (t.front) {
      nb.front_area += a;
      nb.weight += t.weight;
      nb.mean_normal += t.weight * m;
      nb.vcavity_sum += t.vcavity;
      vcav_total += t.vcavity;
      r.front_area += a;
    }
    back_o += t.back_o;
    back_i += t.back_i;
    cdf[j] = (j ? cdf[j - 1] : 0.0) + t.weight;
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

// The ensemble's parts as the estimator's parts: the points drawn along the CDF of w_f over
// all of the ensemble's facets (CdfSamples), each replicate's points on a part's facets a
// contiguous run.
class EnsemblePoints : public G2Points {
 public:
  EnsemblePoints(const SceneEnsemble& e, const std::vector<int>& bin, const CdfSamples& samples, std::uint64_t stream)
      : e_(e), bin_(bin), samples_(samples), stream_(stream) {}
  std::uint64_t stream() const override { return stream_; }
  std::size_t parts() const override { return e_.parts(); }
  std::unique_ptr<Scene> scene(std::size_t k) const override { return e_.build(k); }
  Vec3 to_local(std::size_t k, const Vec3& w) const override { return e_.part(k).frame.to_local(w); }
  UnitRange facets(std::size_t k) const override {
    return {e_.part(k).first_facet, e_.part(k).first_facet + e_.part(k).facets};
  }
  UnitRange points_on(int q, UnitRange f) const override {
    return samples_.run(q, static_cast<std::uint32_t>(f.first), static_cast<std::uint32_t>(f.end));
  }
  std::size_t place(int q, std::uint64_t j, CounterRng& rng) const override {
    rng.uniform();  // the draw CdfSamples placed the point with
    return samples_.facet(q, j);
  }
  int bin(std::size_t f) const override { return bin_[f]; }

 private:
  const SceneEnsemble& e_;
  const std::vector<int>& bin_;
  const CdfSamples& samples_;
  std::uint64_t stream_;
};

}  // namespace

G2Result measure_g2(const SceneEnsemble& e, const Vec3& o_in, const Vec3& i_in, const G2Options& opt) {
  require_equal_parts(e, "measure_g2");
  G2Result r = start_g2(o_in, i_in, opt, e.macro_area());
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<int> bin;
  const std::vector<double> cdf = sum_g2_facets(r, e, bin);
  const ReplicatePlan plan = plan_g2(r, opt);
  const UnitRange reps = share_of(opt.split, static_cast<std::uint64_t>(plan.replicates));
  const std::uint64_t stream = pair_stream(r.o, r.i, 0xC3000000ull);
  const CdfSamples samples(cdf, opt.seed, stream, plan.per_replicate(), reps);
  trace_g2_points(EnsemblePoints(e, bin, samples, stream), r, opt, plan);
  r.seconds = seconds_since(t0);
  return r;
}

// ---- VNDF --------------------------------------------------------------------------------------

namespace {

// The ensemble's parts as the estimator's parts: ray n picks a part by its first draw (by the
// parts' weights), then a uniform origin on that part's window, all from its own counter
// (i.i.d. rays). Each batch's rays (2^20: 20 bytes each) are grouped by part in ray order, so
// that each part's scene is built once a batch. A hit is binned by its facet's normal in the world frame.
class EnsembleRays : public VndfRays {
 public:
  EnsembleRays(const SceneEnsemble& e, const std::vector<int>& bin, std::uint64_t seed, std::uint64_t stream)
      : e_(e), bin_(bin), seed_(seed), stream_(stream) {}
  std::size_t parts() const override { return e_.parts(); }
  std::unique_ptr<Scene> scene(std::size_t k) const override { return e_.build(k); }
  Vec3 to_local(std::size_t k, const Vec3& w) const override { return e_.part(k).frame.to_local(w); }
  std::uint64_t batch() const override { return std::uint64_t(1) << 20; }
  std::vector<std::vector<VndfOrigin>> origins(UnitRange rays, UnitRange share) const override {
    const UnitRange mine{std::max(rays.first, share.first), std::min(rays.end, share.end)};
    std::vector<std::uint32_t> part(mine.size());
    tbb::parallel_for(std::uint64_t(0), mine.size(), [&](std::uint64_t n) {
      CounterRng rng(seed_, stream_, mine.first + n);
      part[n] = static_cast<std::uint32_t>(e_.part_at(rng.uniform()));
    });
    std::vector<std::uint64_t> size(e_.parts(), 0);
    for (std::uint32_t k : part) ++size[k];
    std::vector<std::vector<VndfOrigin>> out(e_.parts());
    for (std::size_t k = 0; k < out.size(); ++k) out[k].reserve(size[k]);
    for (std::uint64_t n = 0; n < mine.size(); ++n) {
      CounterRng rng(seed_, stream_, mine.first + n);
      rng.uniform();  // the draw that chose the part
      const double a = rng.uniform();
      const double b = rng.uniform();
      out[part[n]].push_back(VndfOrigin::of(a, b));
    }
    return out;
  }
  int bin(std::size_t k, const Scene& scene, const TraceHit& h) const override {
    return bin_[e_.part(k).first_facet + scene.front_facet(h)];
  }

 private:
  const SceneEnsemble& e_;
  const std::vector<int>& bin_;
  std::uint64_t seed_, stream_;
};

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
  // Facet by facet (the whole surface's sum_over_facets adds per-bin block sums: other last bits).
  for (std::size_t j = 0; j < nf; ++j) {
    bin[j] = r.binning.bin_of(e.facet_normal(j));
    const double proj = std::max(0.0, e.facet_area(j) * v.dot(e.facet_normal(j)));
    if (bin[j] >= 0) r.front_projected[bin[j]] += proj;
    r.front_projected_total += proj;
  }
  if (!(r.front_projected_total > 0)) throw RuntimeFailure("no facet faces the direction");
  r.window_area_perp = v.z() * r.macro_area;  // the parts' windows seen along v
  trace_vndf_rays(EnsembleRays(e, bin, o.seed, 0xD100 + direction_stream_key(v)), r, o);
  r.seconds = seconds_since(t0);
  return r;
}

}  // namespace microsim
