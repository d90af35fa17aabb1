// measure ndf as a request of the library: D over the sphere from the facets of one surface, its
// checks and its record (definitions included). The command line and the Python module fill the
// request and hand over or print what comes back.
#pragma once
#include <chrono>
#include <memory>

#include "microsim/api/run_context.hpp"
#include "microsim/api/surface_input.hpp"
#include "microsim/measure/ndf_measure.hpp"

namespace microsim {

struct NdfRequest {
  SurfaceInput surface;
  int theta_bins = 90;  // over [0, 180] degrees
  int phi_bins = 72;    // over [0, 360) degrees
  // ParameterError naming the bins out of range, or the bins' accumulators beyond memory (checked
  // before the surface is loaded).
  void check() const;
};

// The measurement before its record: the surface it was made on and D with its checks.
struct NdfRun {
  std::shared_ptr<const Microsurface> surface;
  NdfResult result;
  std::chrono::steady_clock::time_point start;  // after the surface was loaded
};

// Checks the request, loads the surface and measures D.
NdfRun run_ndf(const NdfRequest& r);
// The record of `run` (command "measure ndf").
Json ndf_record(const NdfRequest& r, const NdfRun& run, const RunContext& ctx);
// run_ndf, then its record.
Json measure_ndf_record(const NdfRequest& r, const RunContext& ctx);

}  // namespace microsim
