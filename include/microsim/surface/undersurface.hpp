// The undersurface of a mesh microsurface ([GeomBSDF24, "Inherent Assumptions"]: for v.n < 0 "we must
// recompute the statistics for the undersurface").
#pragma once
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// The same sheet seen from below, as a microsurface in its own right: facet normals reversed
// (-m) and macrosurface normal reversed (-n), expressed in the mirrored frame z -> -z so that
// its macronormal is again +z (vertices mirrored, triangle order kept: the mirror reverses
// orientation, so each facet's normal becomes M(-m) = (-mx, -my, mz)). A view v with v.z < 0 of
// the original is the view M v = (vx, vy, -vz) of the undersurface; its G1 there is the
// explicit undersurface measurement. Meshes only (UsageError for heightfields).
Microsurface undersurface(const Microsurface& s);

// z -> -z.
inline Vec3 mirror_z(const Vec3& v) { return Vec3(v.x(), v.y(), -v.z()); }

}  // namespace microsim
