// The full BSDF of an explicit microsurface, per scattering order, by random walks (docs/theory/bsdf.md): light arrives from l; rays are traced along -l from stratified points of the periodic
// tile; at each hit a mirror reflects, a conductor reflects with weight F (complex index,
// [GeomBSDF24, eq. 8]), a dielectric reflects with probability F and otherwise refracts ([GeomBSDF24, eq. 15a]; total internal
// reflection; both sides of the interface). A ray that leaves upward is reflected, one that
// leaves the slab downward (inside a dielectric) is transmitted. Light is unpolarized.
//
// Tallies per side (reflected / transmitted) and scattering order (1, 2, ..., K-1, K+ and total):
//  * albedo: the mean over rays of the weight that leaves in that cell (with its standard error);
//  * the outgoing hemispheres on an equal-area R x R grid (HemisphereMap), f = p / int_B |cos| dw;
//  * in-plane rows: a narrow band around the plane of incidence (InPlaneBins), f likewise.
// The same tallies for the Smith random-walk model (models/smith_random_walk.hpp) of the
// surface's nominal NDF, and the single-scattering models (models/microfacet_bsdf.hpp) averaged
// over the same bins, go beside them.
//
// Random numbers: CounterRng(seed, stream, ray index); tallies are summed per chunk and merged
// by a deterministic reduction: results do not depend on the number of threads.
#pragma once
#include <functional>
#include <optional>
#include <vector>

#include "microsim/io/output.hpp"
#include "microsim/measure/bsdf_options.hpp"
#include "microsim/measure/bsdf_result.hpp"
#include "microsim/measure/bsdf_tally.hpp"
#include "microsim/measure/hemisphere_map.hpp"
#include "microsim/measure/in_plane_bins.hpp"
#include "microsim/measure/polarized_walk.hpp"
#include "microsim/measure/shards.hpp"
#include "microsim/measure/timing.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/models/smith_random_walk.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

// HemisphereMap and azimuth_near: measure/hemisphere_map.hpp; InPlaneBins: measure/in_plane_bins.hpp;
// BsdfOptions: measure/bsdf_options.hpp; BsdfTally, tally_estimate and order_key:
// measure/bsdf_tally.hpp; BsdfResult: measure/bsdf_result.hpp.

// Periodic tiles; finite objects (rays over a window covering the projection, tallies per unit
// of the flux on the macrosurface: a convex mirror object's total albedo is its visible area
// ratio); V-cavity ensembles (each groove traced on its own, measure/ensemble_estimators.hpp).
// Throws ParameterError for theta_i outside [0, 90) and bad counts.
BsdfResult measure_bsdf(const Tracer& tracer, const BsdfOptions& options);

// The record's tables: measure/bsdf_record.hpp; the table files: io/bsdf_files.hpp.

}  // namespace microsim
