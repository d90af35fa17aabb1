// measure vndf as a request of the library: the histogram of first-hit normals of rays along -v
// against the analytic distribution of visible normals [Heitz14, eq. 13], and a chi-square test
// of the nominal NDF's VNDF sampler, on one surface or an ensemble, and its record.
#pragma once
#include <cstdint>
#include <vector>

#include "microsim/api/angle_list.hpp"
#include "microsim/api/run_context.hpp"
#include "microsim/api/surface_input.hpp"

namespace microsim {

struct VndfRequest {
  std::vector<SurfaceInput> surfaces;  // one, or an ensemble (between-surface errors)
  AngleList theta = angle_list("0:80:20", "theta");  // view zenith angles in [0, 90)
  AngleList phi = azimuth_list("0", "phi");
  long long rays = 1000000;               // per direction
  long long sampler_samples = 1000000;    // for the sampler's chi-square test (0: skip)
  std::uint64_t seed = 1;
  int theta_bins = 18;  // normal bins in theta_m over [0, 90] degrees
  int phi_bins = 16;    // normal bins in phi_m over [0, 360) degrees
  // ParameterError naming what is out of range.
  void check() const;
};

// Checks the request, measures every surface and direction and returns the record (command
// "measure vndf").
Json measure_vndf_record(const VndfRequest& r, const RunContext& ctx);

}  // namespace microsim
