// The V-cavity model made explicit [Heitz14, Sec. 6.1]: masking measured on an ensemble of separate
// V-grooves, each traced on its own as an infinite periodic groove, averaged with the model's
// weights (every groove covers the same macro area; its normals were drawn from (n.m) D(m)).
// The grooves are an ensemble scene (vcavity_grooves, trace/scene_ensemble.hpp) and these are
// the ensemble estimators of measure/ensemble_estimators.hpp run on it (vcavity_model.cpp).
// G1, G2 and the VNDF take their share of the work from options.split as the whole-surface
// estimators do (replicates for G1 and G2, rays for the VNDF; measure/shards.hpp), with the
// same tally layouts, so shards merged give the single run's result.
#pragma once
#include <vector>

#include "microsim/measure/bsdf_options.hpp"
#include "microsim/measure/bsdf_tally.hpp"
#include "microsim/measure/hemisphere_map.hpp"
#include "microsim/measure/in_plane_bins.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/measure/vndf_measure.hpp"

namespace microsim {

// `s` is a vcavity surface (generate_vcavity / is_vcavity). For each view v (v.n > 0):
//  (a) ray casting: the same number of stratified rays on every groove's tile along -v;
//  (b) area sampling: points drawn over the whole ensemble by front-facing projected area
//      (stratified CDF over the 2K facets), one occlusion ray toward v each.
// Per normal bin the G1Result holds the pooled counts and the exact facet sums of the stored
// strips (area, front-facing projected area, V-cavity-weighted area), so the G1 record (cli/cmd_measure_g1.cpp) reports
// the ensemble's G1 beside the V-cavity model (vcavity_numeric, [Heitz14, eq. 24]) and Smith.
// Each groove's Embree scene is built once for all views.
std::vector<G1Result> measure_vcavity_g1(const Microsurface& s, const std::vector<Vec3>& views,
                                         const G1Options& options);

// G2(o, m, i) of a vcavity ensemble ([GeomBSDF24, eq. 16], the weights of measure_g2): points drawn over
// the whole ensemble with density w_f = A_f (max(0, o.m_f) + max(0, i.m_f)) / 2 over the
// facets facing both (a stratified CDF over the 2K facets per replicate, the stream depending
// on the unordered pair {o, i}), each traced with two occlusion rays on its own groove, an
// infinite periodic V-groove in the groove's frame. For such a groove the V-cavity G2
// min(G1(o, m), G1(i, m)) [Heitz14, eq. 24 and Sec. 6] is exact per facet, so `vcavity` is the value the
// measurement must reproduce. Deterministic for any thread count.
G2Result measure_vcavity_g2(const Microsurface& s, const Vec3& o, const Vec3& i, const G2Options& options);

// The VNDF histogram [Heitz14, eq. 13] of a vcavity ensemble: every ray picks a groove uniformly
// (every groove covers the same macro area) and a uniform origin on its tile, i.i.d. (the bin
// counts are multinomial, as measure_vndf's), and is traced along -v on that groove alone.
VndfResult measure_vcavity_vndf(const Microsurface& s, const Vec3& v, const VndfOptions& options);

// The V-cavity model's VNDF of a vcavity ensemble, exact for its separate grooves: the bin
// probabilities sum_{f in B} A_f (v.m_f)+ G1_vcavity(v, m_f) / sum_f (same) over its facets
// (each groove's visible projected area, [GeomBSDF24, eq. 2] with [Heitz14, eq. 24]).
std::vector<double> vcavity_vndf_probabilities(const Microsurface& s, const Vec3& v,
                                               const DirectionBinning& binning);

// The BSDF random walk on a vcavity ensemble: each groove traced on its own as an infinite
// periodic V-groove (its tile one period, in the groove's frame) with the same number of
// stratified rays along -wi, every interreflection kept; exit directions are turned back to the
// world frame before binning. Every groove covers the same macro area, so the tallies are per
// unit macro area (the V-cavity multiple-scattering model's normalization). Deterministic for
// any thread count.
BsdfTally trace_vcavity_bsdf(const Microsurface& s, const BsdfOptions& o, const Vec3& wi,
                             const HemisphereMap& map, const InPlaneBins& plane, std::uint64_t stream);

}  // namespace microsim
