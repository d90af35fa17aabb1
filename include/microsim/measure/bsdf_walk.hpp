// One random walk of the BSDF estimator on an explicit microsurface (docs/theory/bsdf.md): the ray
// starts at `origin` along `dir`; at each hit a mirror reflects, a conductor reflects with weight
// F (complex index, [GeomBSDF24, eq. 8]), a dielectric reflects with probability F and otherwise refracts
// ([GeomBSDF24, eq. 15a]; total internal reflection; both sides of the interface). Shared by the periodic
// tile, finite objects and the V-cavity ensemble (each groove traced on its own).
#pragma once
#include <cstdint>
#include <vector>

#include "microsim/measure/bsdf_tally.hpp"
#include "microsim/measure/exit_counts.hpp"
#include "microsim/measure/hemisphere_map.hpp"
#include "microsim/measure/in_plane_bins.hpp"
#include "microsim/measure/spectral_tally.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

struct WalkEnd {
  enum Kind { Reflected, Transmitted, Missed, Lost, Unterminated };
  Kind kind = Lost;
  int order = 0;       // scattering events before leaving
  double weight = 1.0;  // product of the conductor reflectances (1 for mirror and dielectric)
  Vec3 direction = Vec3::UnitZ();
};

// A spectral conductor's per-wavelength weights: at each conductor hit weights[l] is multiplied
// by materials[l]'s reflectance, in the order the single-index walk multiplies its weight, so
// weights[l] equals the weight of a walk with materials[l] alone bit for bit (the geometry of a
// conductor's path does not depend on its index). The caller sets the weights to 1 first;
// the walk's own `weight` is then left at 1.
struct SpectralWeights {
  const models::Material* materials = nullptr;
  int count = 0;
  double* weights = nullptr;
};

// One scattering event of a walk, as a polarized tally needs it (measure/polarized_walk.hpp):
// the facet's normal out of the material (the hit's front normal), the direction of travel
// before the event, the cosine the walk's Fresnel factor used, the side the ray came from, whether
// it refracted, and the probability of the branch taken (a dielectric's F or 1 - F; 1 otherwise).
struct WalkFacet {
  Vec3 normal, travel;
  double cos_i = 1.0;
  bool front = true, refracted = false;
  double probability = 1.0;
};

// `finite`: the surface is a finite object. Its rays that miss it at once are Missed, and a ray
// that leaves it outside after at least one event is reflected whatever its direction (walls send
// light below the base plane: [GeomBSDF24, "Inherent Assumptions"], the visible area exceeds the
// macrosurface's). `facets` (optional): cleared, then every event appended in order. On a periodic tile a reflected ray leaves upward, a transmitted one downward
// from inside the slab; anything else is Lost. `events` counts the scattering events.
WalkEnd walk_bsdf_path(const Tracer& tracer, const Vec3& origin, const Vec3& dir,
                       const models::Material& mat, CounterRng& rng, int max_events, bool finite,
                       TraceCounters& counters, std::uint64_t& events,
                       const SpectralWeights* spectral = nullptr,
                       std::vector<WalkFacet>* facets = nullptr);

// Adds a walk's end to the tallies with the path's starting weight w0: exits with their order
// and direction (binned when they point into their side's hemisphere: a finite object's
// reflected ray below the base plane counts in the albedo only), losses and unterminated walks.
void record_walk_end(BsdfTally& t, const WalkEnd& e, double w0, const HemisphereMap& map,
                     const InPlaneBins& plane);
// The same for a spectral conductor's path: weight w0 * weights[l] at wavelength l.
void record_walk_end(SpectralTally& t, const WalkEnd& e, const double* weights, double w0,
                     const HemisphereMap& map, const InPlaneBins& plane);
// The same for paths of weight 1 (w0 = 1, e.weight = 1) into integer counts.
void record_walk_end(ExitCounts<std::uint32_t>& t, const WalkEnd& e, const HemisphereMap& map,
                     const InPlaneBins& plane);

}  // namespace microsim
