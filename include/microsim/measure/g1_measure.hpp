// Masking G1 measured on an explicit microsurface by the two estimators of docs/theory/masking.md:
//  (a) ray casting: parallel rays along -v, first-hit normals binned: visible projected area
//      per normal bin over the bin's front-facing projected area sum_f A_f max(0, v.m_f);
//  (b) area sampling: points drawn with density proportional to projected area A_f max(0,v.m_f),
//      one occlusion ray toward v each; G1 = fraction unoccluded.
// Both estimate, per normal bin B, sum_{f in B} A_f (v.m_f)+ V_f / sum_{f in B} A_f (v.m_f)+,
// with V_f the visible fraction of facet f, so they must agree bin by bin.
#pragma once
#include <functional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <nlohmann/json.hpp>

#include "microsim/measure/binning.hpp"
#include "microsim/measure/facet_table.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/table.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

struct G1Options {
  std::uint64_t rays = 1000000;  // per estimator and direction
  std::uint64_t seed = 1;
  int normal_theta_bins = 18;  // normal bins over the whole sphere (10 degree rings)
  int normal_phi_bins = 8;     // 45 degree sectors
  // Independent randomized replicates the rays are split into (measure/replicates.hpp): the
  // standard errors are those of the replicate means.
  int replicates = 32;
  // Called from the calling thread with the fraction of work done (progress display).
  std::function<void(double)> progress;
  // Other processes sharing the replicates (measure/shards.hpp); nullptr: all computed here.
  TallySplit* split = nullptr;
  // A heightfield's fast routes (measure_g1 on a Tracer): rays decoded by its grid walk, draws
  // set up ahead. false: every ray traced on the surface's Scene, the exact route they must
  // equal ray for ray (the tests compare the two).
  bool grid_fast_paths = true;
};

struct G1NormalBin {
  Vec3 mean_normal = Vec3::Zero();  // projected-area-weighted mean unit normal
  double area = 0;                  // sum_f A_f in the bin
  double front_projected = 0;       // sum_f A_f max(0, v.m_f)
  double vcavity_weighted = 0;      // sum_f A_f max(0, v.m_f) G1_vcavity(v, m_f) [Heitz14, eq. 24]
  std::uint64_t raycast_hits = 0;   // estimator (a)
  std::uint64_t samples = 0;        // estimator (b)
  std::uint64_t visible = 0;
  // The same counts per replicate (size G1Result::replicates).
  std::vector<std::uint64_t> raycast_hits_r, samples_r, visible_r;
};

struct G1Result {
  Vec3 v;
  // v.n < 0: the explicit measurement of the undersurface (measured on undersurface(s) at
  // mirror_z(v)); bins are labelled by the undersurface normal -m_f, in the original frame.
  bool undersurface = false;
  double theta = 0, phi = 0;
  std::uint64_t raycast_rays = 0, sample_rays = 0;
  std::uint64_t raycast_hits = 0, sample_visible = 0;
  // Independent replicates (each a full stratified pass of raycast_rays / replicates rays and
  // as many area samples) and the totals per replicate.
  int replicates = 1;
  std::vector<std::uint64_t> raycast_hits_r, sample_visible_r;
  double window_area_perp = 0;     // area of the ray window perpendicular to v
  double front_projected = 0;      // sum_f A_f max(0, v.m_f)
  double total_area = 0;
  double macro_area = 1;           // A
  double total_area_macro() const { return macro_area; }
  double lambda_numeric = 0;       // Lambda from the surface's facets
  TraceCounters counters;
  std::vector<G1NormalBin> bins;
  DirectionBinning binning{1, 1, kPi};
  double seconds = 0;        // wall time of the whole measurement
  double facet_seconds = 0;  // of which the exact facet sums,
  double raycast_seconds = 0;  // estimator (a),
  double sample_seconds = 0;   // estimator (b)
  // Processor time (user + system, all threads of the process) of (a) and (b): the rate on a
  // shared machine, where wall time depends on the other processes.
  double raycast_cpu_seconds = 0, sample_cpu_seconds = 0;

  // Derived quantities with standard errors (of the replicate means, measure/replicates.hpp).
  Estimate g1_area_sampling() const;  // (b), averaged over front-facing projected area
  Estimate g1_raycast() const;        // (a), averaged
  Estimate visible_area_ratio() const;
  Estimate bin_g1_area_sampling(int b) const;
  Estimate bin_g1_raycast(int b) const;
};

DirectionBinning g1_normal_binning(const G1Options& options);
// Deterministic parallel sums over the facets: body(k, acc) adds facet k's terms into
// acc[0 .. width); the result does not depend on the thread count.
template <class Body>
std::vector<double> sum_over_facets(std::size_t num_facets, std::size_t width, Body&& body) {
  using Sums = std::vector<double>;
  Sums sums = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, num_facets,
                                      std::max<std::size_t>(1 << 15, num_facets / 64)),
      Sums{},
      [&](const tbb::blocked_range<std::size_t>& range, Sums acc) {
        if (acc.empty()) acc.assign(width, 0.0);
        for (std::size_t k = range.begin(); k != range.end(); ++k) body(k, acc.data());
        return acc;
      },
      [](Sums a, const Sums& b) {
        if (a.empty()) return b;
        for (std::size_t k = 0; k < b.size(); ++k) a[k] += b[k];
        return a;
      });
  if (sums.empty()) sums.assign(width, 0.0);
  return sums;
}

// v.n > 0: the surface seen from above. v.n < 0 (meshes only; UsageError for heightfields and
// for v.n = 0): the undersurface, measured explicitly on undersurface(s) at mirror_z(v)
// [GeomBSDF24, "Inherent Assumptions"]; pass `under` (a Tracer of undersurface(s)) to reuse it across
// directions. `table` (from build_facet_table with g1_normal_binning(options)) saves
// recomputing the facets of the traced surface for every direction.
G1Result measure_g1(const Tracer& tracer, const Vec3& v, const G1Options& options,
                    const FacetTable* table = nullptr, const Tracer* under = nullptr);

// How measure_g1 traces estimator (a)'s rays on a surface; every route counts the same hits, ray
// for ray (tests/test_g1_routes.cpp):
//  * SceneFirstHit: every ray traced on the surface's Scene (Tracer::first_hit), the exact
//    route, and a mesh's only one;
//  * GridBatched: a heightfield's rays decoded by the lean primary-ray walk of its grid, ray j
//    of every replicate as one block (Tracer::front_facets);
//  * GridAhead: the same walk ray by ray, each set up and prefetched a few rays ahead
//    (Tracer::prefetch_front): on heightfields of kAheadMinCells cells or more, larger than the
//    caches, the memory reads of consecutive rays then overlap.
// options.grid_fast_paths = false takes SceneFirstHit everywhere.
enum class G1RaycastRoute { SceneFirstHit, GridBatched, GridAhead };
G1RaycastRoute g1_raycast_route(const Microsurface& s, const G1Options& options);
// Whether measure_g1 sets estimator (b)'s draws up ahead of tracing them (the same draws in the
// same order, their facets' blocks and grid cells prefetched): on a periodic heightfield beyond
// the caches, unless options.grid_fast_paths is false.
bool g1_draws_ahead(const Microsurface& s, const G1Options& options);

// The table of G1 over view directions (measure/table.hpp): no rows yet, the columns an ensemble
// keeps and how they merge, and the comparisons with the models.
Table g1_table();
// Appends the row of one direction and returns it. Per normal bin: g1 (area sampling) and g1_raycast with standard errors, and the
// two models evaluated on the bin's own facets: smith_numeric = chi+(v.m)/(1 + Lambda_facets(v))
// and vcavity_numeric = sum A_f (v.m_f)+ G1_vcavity(v, m_f) / sum A_f (v.m_f)+ [Heitz14, eq. 24].
// Row summaries over the bins with samples, weighted by front-facing projected area w_b:
// bins_mad_* = sum_b w_b |g1_b - model_b| (noise floor bins_mad_noise = sum_b w_b se_b sqrt(2/pi))
// and bins_chi2_* = sum_b ((g1_b - model_b) / se_b)^2 over bins_dof bins.
Json& add_row(Table& t, const G1Result& r, const Microsurface& s);

// [GeomBSDF24, "Inherent Assumptions"]: the undersurface (a row of `under`, v.n < 0) approximated by the
// surface's own G1 with v reversed or reflected across the macrosurface; adds g1_reverse_v,
// g1_reflect_v with errors, and their z and rel_dev against the explicit measurement.
void add_undersurface_approximations(Json& row, const G1Result& under, const G1Result& reverse_v,
                                     const G1Result& reflect_v);

}  // namespace microsim
