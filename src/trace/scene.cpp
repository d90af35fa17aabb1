#include "microsim/trace/scene.hpp"

#include <cmath>

#include "microsim/trace/ray_window.hpp"

namespace microsim {

std::size_t TracerScene::front_facet(const TraceHit& h) const {
  // A measured region numbers its own facets first: a hit beyond them is outside it.
  if (!h.hit || h.backface || h.facet >= num_facets()) return kNoFacet;
  return h.facet;
}

Vec3 TracerScene::facet_point(std::size_t f, double u1, double u2) const {
  const double r1 = std::sqrt(u1);  // uniform over the triangle's area
  return tracer_.surface().facet(f).point(r1 * (1 - u2), r1 * u2);
}

RayWindow TracerScene::ray_window(const Vec3& v) const { return make_ray_window(tracer_, v); }

std::unique_ptr<Scene> make_scene(const Tracer& tracer) {
  const Macrosurface& m = tracer.surface().macro();
  if (m.periodic) return std::make_unique<PeriodicTileScene>(tracer);
  if (m.region) return std::make_unique<HeightfieldWindowScene>(tracer);
  return std::make_unique<FiniteObjectScene>(tracer);
}

}  // namespace microsim
