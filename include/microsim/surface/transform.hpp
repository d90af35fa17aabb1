// Linear maps of a microsurface for the invariance checks of [Heitz14, Sec. 3]: stretching by
// diag(s_x, s_y, 1) (sec. 3.1) and vertical shearing z -> z + k_x x + k_y y (sec. 3.4). Both
// map straight lines to straight lines, so a ray (p, d) on the original surface and the ray
// (M p, M d) on the mapped one meet the same facets in the same order: occluded rays stay
// occluded and visible ones stay visible [Heitz14, Sec. 3.1, Fig. 2 and 4].
#pragma once
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// Direction (or point) images under the maps (not normalized).
inline Vec3 stretch_vector(const Vec3& d, double sx, double sy) {
  return Vec3(sx * d.x(), sy * d.y(), d.z());
}
inline Vec3 shear_vector(const Vec3& d, double kx, double ky) {
  return Vec3(d.x(), d.y(), d.z() + kx * d.x() + ky * d.y());
}
inline Vec3 unshear_vector(const Vec3& d, double kx, double ky) {
  return Vec3(d.x(), d.y(), d.z() - kx * d.x() - ky * d.y());
}

// The surface mapped by diag(sx, sy, 1): a heightfield stays a heightfield (tile sizes scaled,
// heights unchanged), a mesh has its vertices and macrosurface scaled. Facet k of the result is
// the image of facet k. Slopes scale by 1/sx, 1/sy, so a nominal Beckmann/GGX(ax, ay) becomes
// (ax/sx, ay/sy) (shape invariance, [Heitz14, Sec. 3.2-3.3]). sx, sy > 0 (UsageError otherwise).
Microsurface stretch_surface(const Microsurface& s, double sx, double sy);

// A vertically sheared copy of a periodic tile. The sheared surface is still periodic, but along
// the sheared lattice (a tile-size step in x rises by kx size_x), which the tracer's horizontal
// wrap-around cannot follow; it is therefore built as a finite mesh of (2 copies + 1)^2 sheared
// tiles around the central one. Facets [0, central_facets) are the central tile's, in the order
// of the original surface's facets (facet k is the image of facet k). Rays from the central
// tile are exact as long as they do not leave the patch before clearing the surface.
struct ShearedPatch {
  Microsurface surface;
  std::size_t central_facets = 0;
  Vec3 mesonormal = Vec3::UnitZ();  // unit normal of the sheared mean plane, ~ (-kx, -ky, 1)
  double tile_area = 0;             // horizontal (projected) area of one tile
};
ShearedPatch shear_surface(const Microsurface& s, double kx, double ky, int copies = 1);

}  // namespace microsim
