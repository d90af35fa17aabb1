// The window that parallel rays along -v start from (the primary rays of every estimator), for a
// Tracer's surface; Scene::ray_window (trace/scene.hpp) returns it for every kind of scene.
#pragma once
#include "microsim/common.hpp"

namespace microsim {

class Tracer;

struct RayWindow {
  Vec3 origin0, e1, e2;
  double area_perp = 0;  // |(e1 x e2) . v|
};

// The window the parallel rays along -v start from: origin0 + a e1 + b e2, (a, b) in [0,1]^2.
// Periodic tile: the horizontal tile at the top of the slab (wrap-around makes every ray
// equivalent). Finite object: a rectangle perpendicular to v covering its projection. A
// non-periodic heightfield measured in a region (Macrosurface::region, a window): a rectangle
// at the top of the slab covering every ray that can meet the region's facets. With a region,
// hits outside it are misses (periodic or not).
RayWindow make_ray_window(const Tracer& tracer, const Vec3& v);

}  // namespace microsim
