// The V-cavity model made explicit (001 Sec. 6.1): masking measured on an ensemble of separate
// V-grooves, each traced on its own as an infinite periodic groove, averaged with the model's
// weights (every groove covers the same macro area; its normals were drawn from (n.m) D(m)).
#pragma once
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/g1_measure.hpp"

namespace microsim {

// `s` is a vcavity surface (generate_vcavity / is_vcavity). For each view v (v.n > 0):
//  (a) ray casting: the same number of stratified rays on every groove's tile along -v;
//  (b) area sampling: points drawn over the whole ensemble by front-facing projected area
//      (stratified CDF over the 2K facets), one occlusion ray toward v each.
// Per normal bin the G1Result holds the pooled counts and the exact facet sums of the stored
// strips (area, front-facing projected area, V-cavity-weighted area), so g1_row_json reports
// the ensemble's G1 beside the V-cavity model (vcavity_numeric, 001 eq. 24) and Smith.
// Each groove's Embree scene is built once for all views.
std::vector<G1Result> measure_vcavity_g1(const Microsurface& s, const std::vector<Vec3>& views,
                                         const G1Options& options);

// The BSDF random walk on a vcavity ensemble: each groove traced on its own as an infinite
// periodic V-groove (its tile one period, in the groove's frame) with the same number of
// stratified rays along -wi, every interreflection kept; exit directions are turned back to the
// world frame before binning. Every groove covers the same macro area, so the tallies are per
// unit macro area (the V-cavity multiple-scattering model's normalization). Deterministic for
// any thread count.
BsdfTally trace_vcavity_bsdf(const Microsurface& s, const BsdfOptions& o, const Vec3& wi,
                             const HemisphereMap& map, const InPlaneBins& plane, std::uint64_t stream);

}  // namespace microsim
