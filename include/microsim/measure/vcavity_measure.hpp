// The V-cavity model made explicit [Heitz14, Sec. 6.1]: masking measured on an ensemble of separate
// V-grooves, each traced on its own as an infinite periodic groove, averaged with the model's
// weights (every groove covers the same macro area; its normals were drawn from (n.m) D(m)).
// The grooves are an ensemble scene (vcavity_grooves, trace/scene_ensemble.hpp) and these are
// the ensemble estimators of measure/ensemble_estimators.hpp run on it. G1, G2 and the VNDF
// have no wrapper: measure_g1(vcavity_grooves(s, what, GrooveFrames::StoredNormalOverHypot),
// views, options) is the ensemble's G1, and measure_g2 / measure_vndf on
// vcavity_grooves(s, what, GrooveFrames::StoredNormalNormalized) its G2 and VNDF: the one G1,
// G2 and VNDF estimator each. They take their share of the work from options.split as on a
// whole surface (replicates for G1 and G2, rays for the VNDF; measure/shards.hpp), with the
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
