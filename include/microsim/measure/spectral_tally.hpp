// The sums of a spectral conductor's paths within one replicate (measure/bsdf_measure.hpp): per
// side, slot and cell the weight of every wavelength, the wavelengths innermost (one path's exit
// adds to neighbouring memory), and the path counts once. Only first moments: a replicate's
// second moments are those of its replicate means (BsdfTally::add_replicate), which reads its
// sums alone. wavelength(l) gives wavelength l's sums as the BsdfTally a run with that index alone
// would have summed: every element receives the same additions in the same order.
#pragma once
#include <cstdint>
#include <vector>

#include "microsim/measure/bsdf_tally.hpp"

namespace microsim {

struct SpectralTally {
  int wavelengths = 0, orders = 0, pixels = 0, plane_bins = 0;
  std::vector<double> albedo;  // [s][k][l]
  std::vector<double> pix;     // [s][k][pixel][l]
  std::vector<double> plane;   // [s][k][bin][l]
  std::uint64_t paths = 0, lost = 0, unterminated = 0, events = 0;
  TraceCounters counters;

  // Every sum, declared once (tally_fields.hpp): added (operator+=) and exchanged between
  // processes (a replicate's row, measure/shards.hpp) from this list alone.
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f("albedo", &SpectralTally::albedo);
    f("pix", &SpectralTally::pix);
    f("plane", &SpectralTally::plane);
    f("paths", &SpectralTally::paths);
    f("lost", &SpectralTally::lost);
    f("unterminated", &SpectralTally::unterminated);
    f("events", &SpectralTally::events);
    f("counters", &SpectralTally::counters);
  }

  SpectralTally() = default;
  SpectralTally(int wavelengths, int K, int npix, int nplane);
  int slots() const { return orders + 1; }
  // A path that left on side s after `order` >= 1 events with weight w[l] at wavelength l.
  void add_exit(int s, int order, const double* w, int px, int b);
  SpectralTally& operator+=(const SpectralTally& o);
  // Wavelength l's sums and the counts, as a BsdfTally of one replicate (replicates == 0).
  BsdfTally wavelength(int l) const;
  // The path counts, shared by every wavelength, written into t (its sums untouched).
  void put_path_counts(BsdfTally& t) const;
};

}  // namespace microsim
