// Integer tallies of a walk's exits for the paths whose weight is exactly 1 (a mirror or a
// dielectric on a periodic tile: every exit adds 1 to its cells). A BsdfTally of such paths holds
// sums of 1.0, i.e. exact integers, and only its first moments enter add_replicate; so counting
// exits in integers per order and forming the total and the doubles at the end gives the very
// same BsdfTally, bit for bit, for any grouping of the paths. 4 bytes per (side, order, pixel)
// instead of 4 doubles (value and square, order and total): a unit's tallies stay in cache.
#pragma once
#include <cstdint>
#include <vector>

#include "microsim/measure/bsdf_tally.hpp"

namespace microsim {

template <class Count>
struct ExitCounts {
  int orders = 0, pixels = 0, plane_bins = 0;
  std::vector<Count> albedo, pix, plane;  // [s][k], [s][k][pixel], [s][k][bin]; k = order slot 0 .. K-1
  std::uint64_t paths = 0, lost = 0, unterminated = 0, events = 0;
  TraceCounters counters;

  ExitCounts() = default;
  ExitCounts(int K, int npix, int nplane)
      : orders(K), pixels(npix), plane_bins(nplane), albedo(2 * static_cast<std::size_t>(K), 0),
        pix(2 * static_cast<std::size_t>(K) * npix, 0), plane(2 * static_cast<std::size_t>(K) * nplane, 0) {}
  bool empty() const { return albedo.empty(); }
  // As BsdfTally::add_exit with w = 1.
  void add_exit(int s, int order, int px, int b) {
    const std::size_t sk = static_cast<std::size_t>(s) * orders + (order < orders ? order : orders) - 1;
    ++albedo[sk];
    if (px >= 0) ++pix[sk * pixels + px];
    if (b >= 0) ++plane[sk * plane_bins + b];
  }
  template <class Other>
  ExitCounts& operator+=(const ExitCounts<Other>& o) {
    if (o.empty()) return *this;
    if (empty()) *this = ExitCounts(o.orders, o.pixels, o.plane_bins);
    for (std::size_t k = 0; k < albedo.size(); ++k) albedo[k] += o.albedo[k];
    for (std::size_t k = 0; k < pix.size(); ++k) pix[k] += o.pix[k];
    for (std::size_t k = 0; k < plane.size(); ++k) plane[k] += o.plane[k];
    paths += o.paths;
    lost += o.lost;
    unterminated += o.unterminated;
    events += o.events;
    counters += o.counters;
    return *this;
  }
  // The BsdfTally of the same paths (replicates == 0): sums of 1.0 and of 1.0^2 per cell, the
  // total slot the sum over orders, both2 the number of exits.
  BsdfTally tally() const {
    BsdfTally t(orders, pixels, plane_bins);
    const int K = orders;
    for (int s = 0; s < 2; ++s)
      for (int k = 0; k < K; ++k) {
        const std::size_t sk = static_cast<std::size_t>(s) * K + k;
        t.albedo[t.a_index(s, k)] = static_cast<double>(albedo[sk]);
        t.albedo[t.a_index(s, K)] += static_cast<double>(albedo[sk]);
        t.both2 += static_cast<double>(albedo[sk]);
        for (int px = 0; px < pixels; ++px) {
          const double c = static_cast<double>(pix[sk * pixels + px]);
          t.pix[t.p_index(s, k, px)] = c;
          t.pix[t.p_index(s, K, px)] += c;
        }
        for (int b = 0; b < plane_bins; ++b) {
          const double c = static_cast<double>(plane[sk * plane_bins + b]);
          t.plane[t.b_index(s, k, b)] = c;
          t.plane[t.b_index(s, K, b)] += c;
        }
      }
    t.albedo2 = t.albedo;
    t.pix2 = t.pix;
    t.plane2 = t.plane;
    t.paths = paths;
    t.lost = lost;
    t.unterminated = unterminated;
    t.events = events;
    t.counters = counters;
    return t;
  }
};

}  // namespace microsim
