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
#include "microsim/measure/g1_result.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/table.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

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
// Not on run_units (measure/replicates.hpp): its units lie in one replicate and its body sees one ray, while
// GridBatched traces ray j of every replicate as one block and the ahead routes pipeline a chunk across replicates.
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
