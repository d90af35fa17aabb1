// A conservative escape test for rays that leave a facet of a periodic heightfield tile away
// from the surface: upward on the front side (a reflection), or downward on the back side (a
// refraction into the solid). When it says `clear`, every Embree query that Tracer::first_hit
// would make for that ray finds nothing (its answer is "no hit"), so the walk may take
// `no_hit`, which returns exactly what first_hit returns then (the same TraceHit and counters),
// without a query. When it cannot prove it, the caller traces as usual: results are the same bit
// for bit either way, only the cost changes.
//
// The proof: the ray must stay farther than a margin M from the surface (above it, or below it
// for the back side), except over its own facet, whose hits the tracer's filter rejects.
// Blocks of 2^L x 2^L cells (L >= 2) carry the maximum of their vertices' heights (a pyramid
// over the periodic tile; the back side uses the minimum); the ray skips a block when it is
// above that maximum plus M where it enters it (it only rises). A cell's own corners come from
// the tracer's vertex buffer; cells the ray is not above are tested per triangle: the ray's clearance to the triangle's plane is linear along the
// ray, so its values where the ray enters and leaves the triangle's footprint bound it.
// M covers what separates this double-precision geometry from Embree's: float vertices (x, y
// rounded, heights exact floats), the float ray (origin and direction rounded), the ray re-entering
// through the opposite side of the tile, and the rounding of Embree's own intersection
// arithmetic, each bounded by 2^-24 of the coordinates' magnitudes, times a safety factor;
// horizontal errors become vertical ones through the tile's steepest facet slope.
#pragma once
#include <cstddef>
#include <vector>

#include "microsim/trace/tracer.hpp"

namespace microsim {

class EscapeTest {
 public:
  // Applies to periodic heightfield tiles without a measured region (applies() false otherwise).
  // `lower`: for tests only, lowers every block's bound by this height (a wrong pyramid).
  explicit EscapeTest(const Tracer& tracer, double lower = 0.0);
  bool applies() const { return applies_; }
  // True when the ray from `p` (a hit point on facet `facet`) along unit `d` provably meets
  // nothing before it leaves the slab: side Front with d.z > 0, or Back with d.z < 0.
  bool clear(const Vec3& p, const Vec3& d, std::size_t facet, RaySide side) const;
  // What Tracer::first_hit(p, d, source, counters, side) returns when none of its queries hits
  // (the wrap-arounds it counts on the way, the exit below for a Back ray).
  TraceHit no_hit(const Vec3& p, const Vec3& d, TraceCounters& counters, RaySide side) const;
  // A hint, no effect on any result: starts loading the pyramid's blocks around facet `facet`
  // for the rays that will leave it (front side; `back` too), so that clear() finds them in cache.
  void prefetch(std::size_t facet, bool back) const;
  double margin() const { return margin_; }

 private:
  // In the frame where the surface is g = +-h (s 0: +h, 1: -h) and the ray must stay above.
  bool clear_frame(const Vec3& p, const Vec3& d, long ci, long cj, int half, int s) const;

  const Tracer& tracer_;
  bool applies_ = false;
  long nx_ = 0, ny_ = 0;
  double dx_ = 0, dy_ = 0, x0_ = 0, y0_ = 0;
  const float* h_ = nullptr;  // the surface's heights, row-major
  const float* grid_ = nullptr;  // the tracer's vertex buffer (x, y, z; one periodic cell around)
  std::size_t gw_ = 0;           // its vertices per row
  double margin_ = 0;          // M (height units)
  double shrink_ = 0;          // the source facet's footprint shrunk by this (cell units)
  // levels_[s][L - 1]: blocks of 2^L cells, the maximum of s-frame heights over each block's
  // vertices (bounds inclusive), row-major over ceil(n / 2^L) blocks (level 1 only builds the
  // next; the traversal starts at level 2).
  std::vector<std::vector<float>> levels_[2];
  std::vector<long> bw_, bh_;  // blocks per row / column at each level
  double top_[2] = {0, 0};      // the highest s-frame height
};

}  // namespace microsim
