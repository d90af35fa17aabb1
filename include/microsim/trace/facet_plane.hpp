// The plane a ray leaving facet k starts from (SourcePlane, trace/source_plane.hpp), for the walks,
// which need it at every scattering event.
#pragma once
#include <cstddef>

#include "microsim/surface/microsurface.hpp"
#include "microsim/trace/source_plane.hpp"

namespace microsim {

// Exactly s.facet(k): the same corner points, computed by the same double arithmetic as
// Microsurface::grid_point, but with one division for the cell and the wrap-around as a
// comparison (Microsurface::height's two modulos per corner cost the walks more than their own
// scattering).
inline Triangle facet_triangle(const Microsurface& s, std::size_t k) {
  if (s.kind() != Microsurface::Kind::Heightfield) return s.facet(k);
  const long nx = s.nx(), ny = s.ny();
  long i, j;
  const std::size_t nr = s.has_region() ? s.num_facets() : 0;
  if (k < nr) {  // region facets first (Microsurface::facet)
    const std::size_t cell = k / 2, w = static_cast<std::size_t>(s.region_i1() - s.region_i0());
    i = s.region_i0() + static_cast<long>(cell % w);
    j = s.region_j0() + static_cast<long>(cell / w);
  } else {
    const std::size_t cell = (k - nr) / 2;
    j = static_cast<long>(cell / static_cast<std::size_t>(nx));
    i = static_cast<long>(cell - static_cast<std::size_t>(j) * nx);
  }
  const Macrosurface& m = s.macro();
  const double dx = s.dx(), dy = s.dy();
  const float* h = s.heights().data();
  // i, j are inside the tile, so i + 1 and j + 1 wrap by one comparison.
  auto point = [&](long a, long b) {
    const long wa = a == nx ? 0 : a, wb = b == ny ? 0 : b;
    return Vec3(-0.5 * m.size_x + a * dx, -0.5 * m.size_y + b * dy,
                h[static_cast<std::size_t>(wb) * nx + wa]);
  };
  return k % 2 == 0 ? Triangle{point(i, j), point(i + 1, j), point(i, j + 1)}
                    : Triangle{point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)};
}

// Exactly SourcePlane::of(s.facet(k)).
inline SourcePlane facet_plane(const Microsurface& s, std::size_t k) {
  return SourcePlane::of(facet_triangle(s, k));
}

// The same triangles and planes for the facets a tracer reports, with the corner heights read
// from the tracer's own grid vertices (the floats its traversal has just read, in cache: the
// surface's height array is another 4 bytes per cell that a walk's hit misses in cache).
class FacetPlanes {
 public:
  // From a tracer's grid vertices (Tracer::grid_vertices; Tracer::facet_planes builds this);
  // null: from the surface's heights.
  FacetPlanes(const Microsurface& s, const float* grid_vertices) : s_(s) {
    if (s_.kind() != Microsurface::Kind::Heightfield || !grid_vertices) return;
    // The grid of Tracer: one periodic copy of cells around a periodic tile, none around a
    // window; vertex (i + pad, j + pad) is grid_point(i, j), its z the float height.
    pad_ = s_.macro().periodic ? 1 : 0;
    width_ = static_cast<std::size_t>(s_.traced_cells_x()) + 1 + 2 * pad_;
    vertices_ = grid_vertices;
  }
  Triangle triangle(std::size_t k) const {
    if (!vertices_) return facet_triangle(s_, k);
    const long nx = s_.nx();
    long i, j;
    const std::size_t nr = s_.has_region() ? s_.num_facets() : 0;
    if (k < nr) {
      const std::size_t cell = k / 2, w = static_cast<std::size_t>(s_.region_i1() - s_.region_i0());
      i = s_.region_i0() + static_cast<long>(cell % w);
      j = s_.region_j0() + static_cast<long>(cell / w);
    } else {
      const std::size_t cell = (k - nr) / 2;
      j = static_cast<long>(cell / static_cast<std::size_t>(nx));
      i = static_cast<long>(cell - static_cast<std::size_t>(j) * nx);
    }
    const Macrosurface& m = s_.macro();
    const double dx = s_.dx(), dy = s_.dy();
    auto point = [&](long a, long b) {
      const float* q = vertices_ + 3 * ((static_cast<std::size_t>(b + pad_)) * width_ + (a + pad_));
      return Vec3(-0.5 * m.size_x + a * dx, -0.5 * m.size_y + b * dy, q[2]);
    };
    return k % 2 == 0 ? Triangle{point(i, j), point(i + 1, j), point(i, j + 1)}
                      : Triangle{point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)};
  }
  SourcePlane plane(std::size_t k) const { return SourcePlane::of(triangle(k)); }

 private:
  const Microsurface& s_;
  const float* vertices_ = nullptr;
  long pad_ = 0;
  std::size_t width_ = 0;
};

}  // namespace microsim
