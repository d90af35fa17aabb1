// Software pipelining of independent rays: each ray is set up (and its memory asked for, e.g.
// by Tracer::prefetch_front) a few rays before it is traced, so that on tiles larger than the
// caches the reads of several rays overlap instead of each ray waiting for its own.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>

namespace microsim {

// Tiles from this many cells on trace their primary rays ahead: below, the tile's vertices and
// BVH stay in the caches between neighbouring rays and the set-up costs more than it hides
// (measured: 0.75-0.82 of the bare loop with it at 1024^2, 0.81-0.87 without; bench/).
constexpr double kAheadMinCells = 1536.0 * 1536.0;

// Calls next() m times and use(state) m times, in the same order: use receives the state the
// k-th next() returned, after next() has been called min(k + kAhead + 1, m) times. next() is
// called in order (it may keep a cursor); nothing is reordered, so results are those of
// `for k: use(next())`.
template <class State, std::size_t kAhead = 8, class Next, class Use>
void run_ahead(std::uint64_t m, Next&& next, Use&& use) {
  static_assert(kAhead > 0 && kAhead < 64, "a small look-ahead");
  constexpr std::size_t kRing = kAhead < 16 ? 16 : 64;  // a power of two > kAhead
  std::array<State, kRing> ring;
  const std::uint64_t lead = m < kAhead ? m : kAhead;
  for (std::uint64_t k = 0; k < lead; ++k) ring[k % kRing] = next();
  for (std::uint64_t k = 0; k < m; ++k) {
    if (k + kAhead < m) ring[(k + kAhead) % kRing] = next();
    use(ring[k % kRing]);
  }
}

}  // namespace microsim
