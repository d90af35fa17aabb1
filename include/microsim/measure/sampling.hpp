// Sampling pieces shared by the estimators: stratified, Morton-ordered points of the unit
// square, and the window that parallel rays along -v start from.
#pragma once
#include <cstdint>

#include "microsim/trace/tracer.hpp"

namespace microsim {

// Stratified origins: a G x G grid of strata (G a power of two, G^2 <= n) visited in Morton
// order, r points per stratum; the count is rounded up to r G^2.
struct Strata {
  std::uint32_t grid = 1;
  std::uint64_t per_stratum = 1;
  double inv_grid = 1;  // 1 / grid, exact (a power of two): the same quotients as a division
  explicit Strata(std::uint64_t n) {
    while (static_cast<std::uint64_t>(grid) * 2 * grid * 2 <= n && grid < (1u << 15)) grid *= 2;
    std::uint64_t cells = static_cast<std::uint64_t>(grid) * grid;
    per_stratum = (n + cells - 1) / cells;
    inv_grid = 1.0 / grid;
  }
  std::uint64_t total() const { return per_stratum * grid * grid; }
  // The stratum of point i (the same for every replicate's point i).
  struct Cell {
    std::uint32_t x = 0, y = 0;
  };
  Cell cell(std::uint64_t i) const {
    Cell c;
    morton_decode(i / per_stratum, c.x, c.y);
    return c;
  }
  // Point i, given its stratum cell(i).
  Vec2 point(const Cell& c, CounterRng& rng) const {
    // Two statements: the order of a call's arguments is unspecified (GCC and Clang differ),
    // and the draws must not depend on the compiler. y first keeps earlier GCC results.
    const double jy = rng.uniform();
    const double jx = rng.uniform();
    return Vec2((c.x + jx) * inv_grid, (c.y + jy) * inv_grid);
  }
  Vec2 point(std::uint64_t i, CounterRng& rng) const { return point(cell(i), rng); }
};

// The window the parallel rays along -v start from: origin0 + a e1 + b e2, (a, b) in [0,1]^2.
// Periodic tile: the horizontal tile at the top of the slab (wrap-around makes every ray
// equivalent). Finite object: a rectangle perpendicular to v covering its projection. A
// non-periodic heightfield measured in a region (Macrosurface::region, a window): a rectangle
// at the top of the slab covering every ray that can meet the region's facets. With a region,
// hits outside it are misses (periodic or not).
struct RayWindow {
  Vec3 origin0, e1, e2;
  double area_perp = 0;  // |(e1 x e2) . v|
};
RayWindow make_ray_window(const Tracer& tracer, const Vec3& v);

// A random stream id for a direction (same construction as the G1 estimator's).
inline std::uint64_t direction_stream_key(const Vec3& v) {
  return static_cast<std::uint64_t>(theta_of(v) * 1e6) * 7919 +
         static_cast<std::uint64_t>(phi_of(v) * 1e6);
}

}  // namespace microsim
