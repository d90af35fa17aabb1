// What a BSDF measurement is asked for (measure/bsdf_measure.hpp, measure_bsdf).
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "microsim/models/microfacet_bsdf.hpp"

namespace microsim {

class TallySplit;  // measure/shards.hpp

// Most wavelengths of one spectral run (each adds a set of tallies).
constexpr int kMaxWavelengths = 64;

struct BsdfOptions {
  models::Material material = models::Material::mirror();
  // A spectral conductor: the conductor's index at each wavelength (nm, increasing). Every path
  // is traced once and carries one weight per wavelength (the product of that wavelength's
  // Fresnel reflectances); each wavelength gets its own tallies (BsdfResult::spectral).
  // `material` is then the conductor at the first wavelength (the models beside the
  // measurement and the record's scalar fields). Empty: the single `material`.
  std::vector<double> wavelengths_nm;
  std::vector<models::Material> spectral;
  double theta_i = 0.0, phi_i = 0.0;  // incidence, radians (light direction l)
  int orders = 4;                     // K: orders 1 .. K-1 separately, K and above together
  std::uint64_t rays = 1000000;
  std::uint64_t seed = 1;
  int resolution = 64;  // hemisphere map R (R x R pixels); also the number of in-plane bins
  int max_events = 10000;  // a walk longer than this is counted unterminated (lost)
  // Smith random-walk model: walks of the nominal NDF (0 = none); same seed, own stream.
  std::uint64_t model_walks = 0;
  // > 0: the walks tally expected escapes and their number is chosen from a pilot so that the walk's
  // standard error of every albedo slot is at most this fraction of the measurement's
  // (measure/smith_walk_budget.hpp), at most kWalkCapFactor model_walks; <= 0: exactly model_walks
  // walks with drawn escapes.
  double model_error_fraction = 1.0;
  // false: measure only (no analytic model beside the measurement: no single-scattering
  // integrals, no Smith walk, no V-groove closed forms), for tables where models cost time.
  bool models = true;
  // Independent randomized replicates the explicit surface's rays are split into: standard
  // errors of the replicate means (measure/replicates.hpp).
  int replicates = 32;
  // Mueller matrices along every reflected path, per order and wavelength
  // (measure/polarized_walk.hpp), built from the facets of the walk's own paths. Periodic
  // tiles and finite objects, in one process or split (measure/shards.hpp).
  bool polarized = false;
  // The run enters only a renderer table's azimuthal averages (measure/table_run_sums.hpp): its
  // replicates add their first moments without their spread; no errors for it.
  bool table_sums_only = false;
  // Called from the calling thread with the fraction of work done (progress display).
  std::function<void(double)> progress;
  // Other processes sharing the replicates and the model's batches (measure/shards.hpp);
  // nullptr: all computed here.
  TallySplit* split = nullptr;
};

}  // namespace microsim
