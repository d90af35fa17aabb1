// The G1, G2 and VNDF estimators and the BSDF random walk on an ensemble scene (parts of one
// surface, trace/scene_ensemble.hpp), written against Scene: each part is built and traced on
// its own, in its own frame, and its integer tallies are added to the surface's in part order
// (deterministic for any thread count). The parts must cover equal shares of the macro area
// (UsageError otherwise): ray-casting rays are spread evenly over them. G1 and G2 take their
// share of the work from options.split as the whole-surface estimators do (replicates; rays for
// the VNDF; blocks of parts for the BSDF walk; measure/shards.hpp), with the same tally layouts,
// so shards merged give the single run's result.
#pragma once
#include <cstdint>
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/measure/vndf_measure.hpp"
#include "microsim/trace/scene_ensemble.hpp"

namespace microsim {

// For each view v (v.n > 0), the whole surface's G1 estimator (its tallies, exact facet sums,
// rays and exchange, src/measure/g1_estimator.hpp) with its rays planned part by part: (a) ray
// casting, the same number of stratified rays on every part's window along -v; (b) area
// sampling, points drawn over the whole ensemble by front-facing projected area (a stratified
// CDF over its facets), one occlusion ray toward v each, traced in the point's part. Per normal
// bin the pooled counts and the exact facet sums (area, front-facing projected area,
// V-cavity-weighted area). Each part's scene is built once for all views. A vcavity surface's
// G1: measure_g1(vcavity_grooves(s, what, GrooveFrames::StoredNormalOverHypot), views, options).
std::vector<G1Result> measure_g1(const SceneEnsemble& e, const std::vector<Vec3>& views,
                                 const G1Options& options);

// G2(o, m, i) ([GeomBSDF24, eq. 16]), the one G2 estimator of measure_g2 (g2_estimator.hpp) with
// the ensemble's parts as its parts: points drawn over the whole ensemble with density
// w_f = A_f (max(0, o.m_f) + max(0, i.m_f)) / 2 over the facets facing both (a stratified CDF
// per replicate, the stream depending on the unordered pair {o, i}), each traced with two
// occlusion rays in its own part. `vcavity`: the V-cavity G2 min(G1(o, m), G1(i, m))
// [Heitz14, eq. 24 and Sec. 6] averaged with the same weights. The V-cavity model's grooves:
// measure_g2(vcavity_grooves(s, what, GrooveFrames::StoredNormalNormalized), o, i, options);
// for such separate grooves `vcavity` is exact per facet, the value the measurement must
// reproduce.
G2Result measure_g2(const SceneEnsemble& e, const Vec3& o, const Vec3& i, const G2Options& options);

// The VNDF histogram [Heitz14, eq. 13], the one VNDF estimator of measure_vndf
// (vndf_estimator.hpp) with the ensemble's parts as its parts: every ray picks a part by its
// weight and a uniform origin on that part's window, i.i.d. (the bin counts are multinomial), and
// a hit is binned by its facet's normal in the world frame. The V-cavity model's grooves:
// measure_vndf(vcavity_grooves(s, what, GrooveFrames::StoredNormalNormalized), v, options), as
// for measure_g2.
VndfResult measure_vndf(const SceneEnsemble& e, const Vec3& v, const VndfOptions& options);

// The BSDF random walk: on every part the same number of stratified paths along -wi, every
// interreflection kept; exit directions turned back to the world frame before binning. The
// tallies are per unit macro area of a part. Work units of run_units (measure/replicates.hpp):
// blocks of at most 16 consecutive parts, the leaves of the halving split of the parts, walked
// part after part from zero and added in that tree's order (measure/halving_sum.hpp); with
// options.split each process walks its share of the blocks and the path sums are exchanged
// (partial-record entry `bsdf_ensemble`).
BsdfTally trace_bsdf(const SceneEnsemble& e, const BsdfOptions& o, const Vec3& wi,
                     const HemisphereMap& map, const InPlaneBins& plane, std::uint64_t stream);

}  // namespace microsim
