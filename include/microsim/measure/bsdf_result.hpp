// The result of a BSDF measurement (measure/bsdf_measure.hpp, measure_bsdf): its tallies, the
// binning they use and the models beside them. Defined in src/measure/bsdf_measure.cpp.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "microsim/measure/bsdf_options.hpp"
#include "microsim/measure/bsdf_tally.hpp"
#include "microsim/measure/hemisphere_map.hpp"
#include "microsim/measure/in_plane_bins.hpp"
#include "microsim/measure/polarized_walk.hpp"
#include "microsim/measure/timing.hpp"
#include "microsim/models/ndf.hpp"

namespace microsim {

// The number of Smith walks chosen for the error target (measure/smith_walk_budget.hpp).
struct WalkBudget {
  std::uint64_t walks = 0;                     // the walks run (pilot included)
  double target_ratio = 0.0;                   // walk stderr / measured stderr asked for (0: fixed walks)
  int limiting_side = -1, limiting_slot = -1;  // the albedo slot that needed the most walks (-1: none)
};

struct BsdfResult {
  BsdfOptions options;  // as run (progress callback dropped)
  Vec3 wi;              // light direction l
  HemisphereMap map;
  InPlaneBins plane{0.0, 1};
  BsdfTally measured;                // spectral runs: the first wavelength's tallies
  std::vector<BsdfTally> spectral;    // per wavelength of options.wavelengths_nm (empty if none)
  std::optional<BsdfTally> smith_walk;  // the model's tallies (nominal NDF available)
  WalkBudget model_budget;              // how many walks, for which error
  std::optional<models::Ndf> nominal;
  std::optional<PolarizationTally> polarization;  // options.polarized: the reflected Mueller sums
  Timing timing;        // the whole run (the record's `seconds`)
  Timing model_timing;  // the Smith walk model's part of it (`model_seconds`)

  int wavelengths() const { return static_cast<int>(spectral.size()); }
  // The tallies of wavelength index `lambda` (spectral runs), or `measured` for lambda < 0.
  const BsdfTally& tally(int lambda) const { return lambda < 0 ? measured : spectral[lambda]; }
  Estimate albedo(int side, int k, int lambda = -1) const;
  Estimate f_pixel(int side, int k, int px, int lambda = -1) const;
  Estimate f_plane(int side, int k, int b, int lambda = -1) const;
  Estimate model_albedo(int side, int k) const;
  Estimate model_f_plane(int side, int k, int b) const;
};

}  // namespace microsim
