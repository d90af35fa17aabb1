// The V-cavity model's columns of a vcavity ensemble, and the ensemble's measurements: its
// grooves as an ensemble scene (trace/scene_ensemble.hpp) run through the ensemble estimators
// (measure/ensemble_estimators.hpp).
#include <algorithm>

#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/measure/vcavity_measure.hpp"
#include "microsim/models/vgroove_multiple.hpp"

namespace microsim {

BsdfTally trace_vcavity_bsdf(const Microsurface& s, const BsdfOptions& o, const Vec3& wi,
                             const HemisphereMap& map, const InPlaneBins& plane, std::uint64_t stream) {
  return trace_bsdf(vcavity_grooves(s, "trace_vcavity_bsdf", GrooveFrames::OfModel), o, wi, map, plane, stream);
}

std::vector<double> vcavity_vndf_probabilities(const Microsurface& s, const Vec3& v_in,
                                               const DirectionBinning& binning) {
  const SceneEnsemble g = vcavity_grooves(s, "vcavity_vndf_probabilities", GrooveFrames::StoredNormalNormalized);
  const Vec3 v = v_in.normalized();
  std::vector<double> p(binning.size(), 0.0);
  double total = 0;
  for (std::size_t j = 0; j < g.num_facets(); ++j) {
    const Vec3& m = g.facet_normal(j);
    // Visible projected area of the side: A (v.m)+ G1 ([GeomBSDF24, eq. 2], [Heitz14, eq. 24]).
    const double vis = g.facet_area(j) * std::max(0.0, v.dot(m)) * models::vcavity_G1(v, m);
    const int b = binning.bin_of(m);
    if (b >= 0) p[b] += vis;
    total += vis;
  }
  for (double& x : p) x /= total;
  return p;
}

}  // namespace microsim
