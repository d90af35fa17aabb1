// measure g1 as a request of the library: masking G1 per view direction by ray casting and area
// sampling beside Smith, on one surface or an ensemble, and its record (definitions included).
#pragma once
#include <cstdint>
#include <vector>

#include "microsim/api/angle_list.hpp"
#include "microsim/api/run_context.hpp"
#include "microsim/api/surface_input.hpp"

namespace microsim {

struct G1Request {
  // One surface, or several independent surfaces of the same statistics (an ensemble: rows
  // averaged over them with the between-surface standard error).
  std::vector<SurfaceInput> surfaces;
  AngleList theta = angle_list("0:85:5", "theta");  // view zenith angles; (90, 180]: undersurface
  AngleList phi = azimuth_list("0", "phi");         // view azimuths
  long long rays = 1000000;                         // per estimator and direction
  std::uint64_t seed = 1;
  int replicates = 32;  // independent replicates the rays are split into (standard errors)
  // ParameterError naming what is out of range.
  void check() const;
};

// Checks the request, measures every surface and returns the record (command "measure g1").
Json measure_g1_record(const G1Request& r, const RunContext& ctx);

}  // namespace microsim
