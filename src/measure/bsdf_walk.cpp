#include "microsim/measure/bsdf_walk.hpp"

#include <algorithm>

#include "microsim/measure/bsdf_options.hpp"

namespace microsim {

namespace {

// Whether the walk ends at the ray of this order (hit: what it met), with e.kind set: a first
// ray outside a measured region or beside a finite object missed; a ray that met nothing left
// the surface; a hit on the unexpected side crossed it through a rounding gap; and one event
// more than max_events leaves the walk unterminated. False: the ray scatters at `hit`.
inline bool walk_ends(const TraceHit& hit, RaySide side, int order, const Vec3& dir, bool finite,
                      const Microsurface& s, int max_events, WalkEnd& e) {
  // A measured region: a first hit outside it is a miss (trace/ray_window.hpp), and so is a
  // first ray that meets nothing (it entered the patch through a side wall, below it).
  const bool region = s.macro().region;
  if (order == 0 && region && (!hit.hit || hit.facet >= s.num_facets())) {
    e.kind = WalkEnd::Missed;
    return true;
  }
  if (!hit.hit) {
    if (side == RaySide::Front && order == 0 && finite) e.kind = WalkEnd::Missed;
    else if (side == RaySide::Front && order > 0 && (finite || dir.z() > 0.0)) e.kind = WalkEnd::Reflected;
    else if (side == RaySide::Back && hit.exit_below) e.kind = WalkEnd::Transmitted;
    else e.kind = WalkEnd::Lost;  // lost below / unresolved (tracer counters), or left the solid upward
    return true;
  }
  // A hit on the unexpected side crossed the surface through a rounding gap.
  if (hit.backface != (side == RaySide::Back)) {
    e.kind = WalkEnd::Lost;
    return true;
  }
  if (order + 1 > max_events) {
    e.kind = WalkEnd::Unterminated;
    return true;
  }
  return false;
}

// One scattering event at `hit` of the ray travelling along dir on `side`: the new direction
// and side, the conductor's reflectance into `weight` (or each wavelength's into `spectral`),
// and the event as a polarized tally records it.
inline WalkFacet scatter(const TraceHit& hit, const models::Material& mat,
                         const SpectralWeights* spectral, CounterRng& rng, Vec3& dir, RaySide& side,
                         double& weight) {
  using models::MaterialKind;
  // Normal on the side of the current medium; v toward where the ray came from.
  const Vec3 m = side == RaySide::Front ? hit.normal : Vec3(-hit.normal);
  const Vec3 v = -dir;
  const double vm = std::max(0.0, v.dot(m));
  const bool front = side == RaySide::Front;
  WalkFacet event{hit.normal, dir, vm, front, false, 1.0};
  switch (mat.kind) {
    case MaterialKind::Mirror:
      dir = models::reflect(v, m);  // [GeomBSDF24, eq. 13a]
      break;
    case MaterialKind::Conductor:
      if (spectral)  // one weight per wavelength; the walk's weight stays 1
        for (int l = 0; l < spectral->count; ++l)
          spectral->weights[l] *= spectral->materials[l].reflectance(vm, true);
      else
        weight *= mat.reflectance(vm, true);  // [GeomBSDF24, eq. 8], complex index
      dir = models::reflect(v, m);
      break;
    case MaterialKind::Dielectric: {
      const double F = mat.reflectance(vm, front);
      if (rng.uniform() < F) {
        dir = models::reflect(v, m);
        event.probability = F;
      } else {
        event.probability = 1.0 - F;
        const double n = front ? mat.eta : 1.0 / mat.eta;  // far side over near side
        Vec3 t_dir;
        if (models::refract(v, m, 1.0 / n, &t_dir)) {  // [GeomBSDF24, eq. 15a]
          dir = t_dir;
          side = front ? RaySide::Back : RaySide::Front;
          event.refracted = true;
        } else {
          dir = models::reflect(v, m);  // F < 1 under total reflection only by rounding
          event.probability = 1.0;
        }
      }
      break;
    }
  }
  dir.normalize();
  return event;
}

}  // namespace

WalkEnd walk_bsdf_path(const Tracer& tracer, const Vec3& origin, const Vec3& dir0,
                       const models::Material& mat, CounterRng& rng, int max_events, bool finite,
                       TraceCounters& counters, std::uint64_t& events,
                       const SpectralWeights* spectral, std::vector<WalkFacet>* facets) {
  const Microsurface& s = tracer.surface();
  WalkEnd e;
  Vec3 dir = dir0;
  RaySide side = RaySide::Front;
  TraceHit hit = tracer.first_hit(origin, dir, nullptr, counters);
  if (facets) facets->clear();
  for (int order = 0;; ++order) {
    e.order = order;
    e.direction = dir;
    if (walk_ends(hit, side, order, dir, finite, s, max_events, e)) return e;
    ++events;
    const WalkFacet event = scatter(hit, mat, spectral, rng, dir, side, e.weight);
    if (facets) facets->push_back(event);
    // The plane left is formed only if a candidate hit is nearly parallel to it (SourceFacet).
    const SourceFacet left{hit.facet, hit.normal};
    hit = tracer.first_hit(hit.point, dir, left, counters, side);
  }
}

namespace {
// Where a walk's end goes in a tally: `add(s, px, b)` for an exit on side s (0 reflected, 1
// transmitted) in pixel px and in-plane bin b (-1: below the side's horizon, not binned).
template <class Tally, class AddExit>
void record_end(Tally& t, const WalkEnd& e, const HemisphereMap& map, const InPlaneBins& plane,
                AddExit add) {
  switch (e.kind) {
    case WalkEnd::Reflected:
    case WalkEnd::Transmitted: {
      const bool reflected = e.kind == WalkEnd::Reflected;
      const bool binned = reflected ? e.direction.z() > 0.0 : e.direction.z() < 0.0;
      add(reflected ? 0 : 1, binned ? map.pixel_of(e.direction) : -1,
          binned ? plane.bin_of(e.direction) : -1);
      break;
    }
    case WalkEnd::Missed: break;
    case WalkEnd::Lost: ++t.lost; break;
    case WalkEnd::Unterminated: ++t.unterminated; break;
  }
}
}  // namespace

void record_walk_end(BsdfTally& t, const WalkEnd& e, double w0, const HemisphereMap& map,
                     const InPlaneBins& plane) {
  record_end(t, e, map, plane,
             [&](int s, int px, int b) { t.add_exit(s, e.order, w0 * e.weight, px, b); });
}

void record_walk_end(SpectralTally& t, const WalkEnd& e, const double* weights, double w0,
                     const HemisphereMap& map, const InPlaneBins& plane) {
  record_end(t, e, map, plane, [&](int s, int px, int b) {
    double w[kMaxWavelengths];
    for (int l = 0; l < t.wavelengths; ++l) w[l] = w0 * weights[l];
    t.add_exit(s, e.order, w, px, b);
  });
}

void record_walk_end(ExitCounts<std::uint32_t>& t, const WalkEnd& e, const HemisphereMap& map,
                     const InPlaneBins& plane) {
  record_end(t, e, map, plane, [&](int s, int px, int b) { t.add_exit(s, e.order, px, b); });
}

}  // namespace microsim
