// The plane of the facet a ray leaves (Tracer, trace/tracer.hpp; FacetPlanes,
// trace/facet_plane.hpp).
#pragma once
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// A ray leaving a facet never meets that facet's plane again; hits on it are rounding
// artefacts and are rejected by an Embree filter (docs/theory/numerics.md).
struct SourcePlane {
  Vec3 normal;    // unit
  double offset;  // normal . p for p on the plane
  static SourcePlane of(const Triangle& t) {
    Vec3 n = t.normal();
    return {n, n.dot(t.p0)};
  }
};

}  // namespace microsim
