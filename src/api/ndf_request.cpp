#include "microsim/api/ndf_request.hpp"

#include <tbb/task_arena.h>

#include <string>

#include "microsim/api/request_checks.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {

void NdfRequest::check() const {
  require_integer_in(theta_bins, 1, 3600, "theta_bins");
  require_integer_in(phi_bins, 1, 7200, "phi_bins");
  // Area per block and bin in each live accumulator of the deterministic reduction (about two
  // per thread), refused before loading the surface.
  NdfOptions defaults;
  const double bins = static_cast<double>(theta_bins) * phi_bins;
  require_memory(bins * defaults.blocks * defaults.blocks * 8.0 * 2 * (tbb::this_task_arena::max_concurrency() + 1),
                 "{theta_bins} " + std::to_string(theta_bins) + " x {phi_bins} " + std::to_string(phi_bins));
}

NdfRun run_ndf(const NdfRequest& r) {
  r.check();
  NdfRun run;
  run.surface = r.surface.get();
  NdfOptions no;
  no.n_theta = r.theta_bins;
  no.n_phi = r.phi_bins;
  run.start = std::chrono::steady_clock::now();
  run.result = measure_ndf(*run.surface, no);
  return run;
}

Json ndf_record(const NdfRequest& r, const NdfRun& run, const RunContext& ctx) {
  const NdfResult& m = run.result;
  const Microsurface& s = *run.surface;
  Json j;
  j["command"] = "measure ndf";
  j["surface"] = s.description;
  j["checks"] = surface_checks_json(m.sums, s);
  j["binning"] = {{"theta_bins", m.bins.n_theta()}, {"phi_bins", m.bins.n_phi()},
                  {"theta_range_deg", {0, 180}}, {"stderr_blocks", m.blocks * m.blocks},
                  {"rows", "one per theta ring, D averaged over phi"}};
  j["rows"] = ndf_table(m, s).rows;
  j.update(record_header("measure ndf", ctx));
  j["file"] = r.surface.name;
  j["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - run.start).count();
  return j;
}

Json measure_ndf_record(const NdfRequest& r, const RunContext& ctx) { return ndf_record(r, run_ndf(r), ctx); }

}  // namespace microsim
