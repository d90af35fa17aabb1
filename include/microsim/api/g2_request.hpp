// measure g2 as a request of the library: masking-shadowing G2 by area sampling with two occlusion
// rays per point, beside the four Smith forms [Heitz14, eq. 20-23] and the V-cavity model, on one
// surface or an ensemble, and its record (definitions included).
#pragma once
#include <cstdint>
#include <vector>

#include "microsim/api/angle_list.hpp"
#include "microsim/api/run_context.hpp"
#include "microsim/api/surface_input.hpp"

namespace microsim {

struct G2Request {
  std::vector<SurfaceInput> surfaces;  // one, or an ensemble (between-surface errors)
  AngleList theta_o;                   // view (outgoing) zenith angles in [0, 90); required
  AngleList phi_o = azimuth_list("0", "phi_o");
  AngleList theta_i;  // light (incoming) zenith angles in [0, 90); required
  AngleList phi_i = azimuth_list("0", "phi_i");
  long long rays = 1000000;  // area samples per direction pair (two occlusion rays each)
  std::uint64_t seed = 1;
  int replicates = 32;
  // ParameterError naming what is missing or out of range.
  void check() const;
};

// Checks the request, measures every surface and direction pair and returns the record
// (command "measure g2").
Json measure_g2_record(const G2Request& r, const RunContext& ctx);

}  // namespace microsim
