// How far float vertex rounding can move the facet sums of [GeomBSDF24, eq. 1b/1c] on a mesh.
//
// sum_f A_f m_f = 1/2 sum_f (a x b + b x c + c x a) over the triangles (a, b, c): a half-edge
// shared with its reverse cancels, so the sum is 1/2 sum of a x b over the boundary half-edges,
// whatever the vertices are. A closed mesh satisfies eq. 1b exactly for its float vertices, and
// so does a periodic tile whose opposite seams are bit-exact translates by the tile size. An
// open boundary that is not (the V-cavity's strips: a groove's two ends are translates of each
// other only before their vertices were rounded to float) moves the sum by
//   1/2 sum_v delta_v x T_v  (+ second order),   T_v = sum_{v->b} b - sum_{a->v} a,
// over the vertices v of such boundary half-edges, delta_v the rounding of v's coordinates
// (at most half a float ulp each, plus the double rounding that produced them). The bound is
// the same sum in absolute values, component by component.
#pragma once
#include <cstddef>

#include "microsim/surface/microsurface.hpp"

namespace microsim {

struct FacetSumRounding {
  Vec3 bound = Vec3::Zero();          // |sum_f A_f m_f - its value for unrounded vertices| <= bound
  std::size_t boundary_half_edges = 0;  // half-edges without a reverse twin
  std::size_t seam_matched = 0;         // of which matched with a bit-exact periodic translate
  std::size_t open_vertices = 0;        // vertices on the remaining (open) boundary
};

// Zero for a heightfield (its grid is exact and wraps onto itself) and for a closed or
// bit-exactly periodic mesh.
FacetSumRounding facet_sum_rounding_bound(const Microsurface& s);

}  // namespace microsim
