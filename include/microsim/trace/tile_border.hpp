// Crossing the border of a tile centred on the origin (half sizes hx, hy): how far a ray runs
// before it leaves the tile, and where it re-enters a periodic tile. Shared by the tracer's
// segment loops, which must follow a ray across the border identically.
#pragma once
#include <algorithm>
#include <limits>

#include "microsim/surface/microsurface.hpp"

namespace microsim {

// Distance along `dir` from `o` (inside the tile) to its border, 0 when already on it; infinite
// for a vertical ray.
inline double distance_to_tile_border(const Vec3& o, const Vec3& dir, double hx, double hy) {
  double t = std::numeric_limits<double>::infinity();
  if (dir.x() > 0) t = std::min(t, (hx - o.x()) / dir.x());
  if (dir.x() < 0) t = std::min(t, (-hx - o.x()) / dir.x());
  if (dir.y() > 0) t = std::min(t, (hy - o.y()) / dir.y());
  if (dir.y() < 0) t = std::min(t, (-hy - o.y()) / dir.y());
  return std::max(t, 0.0);
}

// True only when distance_to_tile_border(o, dir, hx, hy) >= t (t >= 0 finite): on each axis
// the ray moves along, the way to the border exceeds t |d| by the relative margin `rel`, far
// beyond the rounding of the quotients (a few 1e-16), so the quotients need not be formed. False
// also where that is too close to tell (the caller then forms them). No division.
constexpr double kBorderMargin = 1e-12;
inline bool reaches_before_border(const Vec3& o, const Vec3& dir, double hx, double hy, double t,
                                  double rel = kBorderMargin) {
  const double k = t * (1 + rel);
  // (-h - p) / d = (h + p) / -d, and the rounding of both is symmetric.
  auto clear = [k](double d, double p, double h) {
    if (d > 0) return h - p >= k * d;
    if (d < 0) return h + p >= k * -d;
    return true;
  };
  return t >= 0 && t < std::numeric_limits<double>::infinity() && clear(dir.x(), o.x(), hx) &&
         clear(dir.y(), o.y(), hy);
}

// `o`, on the border a ray along `dir` leaves through, moved to the opposite side (both sides
// at a corner) of the periodic tile `macro`; the tolerance absorbs the rounding of o + t dir.
inline void reenter_opposite_side(Vec3& o, const Vec3& dir, const Macrosurface& macro) {
  const double hx = 0.5 * macro.size_x, hy = 0.5 * macro.size_y;
  const double tol = 1e-12 * std::max(macro.size_x, macro.size_y);
  if (dir.x() > 0 && o.x() >= hx - tol) o.x() -= macro.size_x;
  else if (dir.x() < 0 && o.x() <= -hx + tol) o.x() += macro.size_x;
  if (dir.y() > 0 && o.y() >= hy - tol) o.y() -= macro.size_y;
  else if (dir.y() < 0 && o.y() <= -hy + tol) o.y() += macro.size_y;
}

}  // namespace microsim
