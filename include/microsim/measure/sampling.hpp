// Sampling pieces shared by the estimators: stratified, Morton-ordered points of the unit
// square, and the window that parallel rays along -v start from.
#pragma once
#include <algorithm>
#include <cstdint>

#include "microsim/trace/ray_window.hpp"
#include "microsim/trace/scene.hpp"  // Scene::ray_window, the window of any scene
#include "microsim/trace/tracer.hpp"

namespace microsim {

// Stratified origins along the Morton (Z-order) curve: point i of n lies in the i-th of n equal
// pieces [i/n, (i+1)/n) of the curve through a 2^16 x 2^16 grid of equal fine cells, uniform
// inside it. Every piece has area 1/n, so the count is exactly n, whatever n (no rounding up to
// whole squares); consecutive points are close on the tile (coherent rays); for n = r 4^k the
// pieces tile each of the 4^k Morton squares r at a time. The fine cell is drawn by where a
// uniform position along the piece falls, the point uniform inside that cell: each fine cell is
// reached with the probability of its share of the piece, so the n pieces together sample the
// square uniformly.
struct Strata {
  static constexpr int kFineBits = 16;  // fine cells per side: 2^16
  static constexpr std::uint64_t kFineCells = std::uint64_t(1) << (2 * kFineBits);
  std::uint64_t n = 1;
  double cells_per_piece = static_cast<double>(kFineCells);  // 4^16 / n
  explicit Strata(std::uint64_t count)
      : n(count > 0 ? count : 1),
        cells_per_piece(static_cast<double>(kFineCells) / static_cast<double>(n)) {}
  std::uint64_t total() const { return n; }
  // Point i's piece of the curve (the same for every replicate's point i): its start, in fine
  // cells along the curve.
  struct Cell {
    double start = 0;
  };
  Cell cell(std::uint64_t i) const { return Cell{static_cast<double>(i) * cells_per_piece}; }
  // Point i, given its piece cell(i).
  Vec2 point(const Cell& c, CounterRng& rng) const {
    // Separate statements: the order of a call's arguments is unspecified (GCC and Clang
    // differ), and the draws must not depend on the compiler.
    const double along = rng.uniform();
    const double jx = rng.uniform();
    const double jy = rng.uniform();
    // Fine cell index along the curve; the clamp keeps a rounding at the very end inside.
    const double pos = c.start + along * cells_per_piece;
    const std::uint64_t code = std::min(static_cast<std::uint64_t>(pos), kFineCells - 1);
    std::uint32_t fx, fy;
    morton_decode(code, fx, fy);
    constexpr double kInvSide = 1.0 / static_cast<double>(1u << kFineBits);  // exact
    return Vec2((fx + jx) * kInvSide, (fy + jy) * kInvSide);
  }
  Vec2 point(std::uint64_t i, CounterRng& rng) const { return point(cell(i), rng); }
};

// The window of parallel rays (RayWindow, make_ray_window): trace/ray_window.hpp.

// A random stream id for a direction (same construction as the G1 estimator's).
inline std::uint64_t direction_stream_key(const Vec3& v) {
  return static_cast<std::uint64_t>(theta_of(v) * 1e6) * 7919 +
         static_cast<std::uint64_t>(phi_of(v) * 1e6);
}

}  // namespace microsim
