// microsim measure ndf FILE -o OUT: D over the sphere from the facets.
#include <tbb/task_arena.h>

#include <iomanip>
#include <iostream>

#include "cli_common.hpp"
#include "option_checks.hpp"
#include "commands.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/ndf_measure.hpp"
#include "microsim/surface/surface_io.hpp"

namespace microsim::cli {

int run_measure_ndf(const MeasureOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv", "exr"});
  {
    // Area per block and bin in each live accumulator of the deterministic reduction (about two
    // per thread), refused before loading the surface.
    NdfOptions defaults;
    const double bins = static_cast<double>(o.theta_bins) * o.phi_bins;
    require_memory(bins * defaults.blocks * defaults.blocks * 8.0 * 2 * (tbb::this_task_arena::max_concurrency() + 1),
                   "{theta_bins} " + std::to_string(o.theta_bins) + " x {phi_bins} " + std::to_string(o.phi_bins));
  }
  Microsurface s = input_surface(g, o.surface);
  NdfOptions no;
  no.n_theta = o.theta_bins;
  no.n_phi = o.phi_bins;
  auto t0 = std::chrono::steady_clock::now();
  NdfResult r = measure_ndf(s, no);
  if (extension_of(o.output) == "exr") {
    write_exr(o.output, ndf_to_exr(r, s));
  } else {
    Json j;
    j["command"] = "measure ndf";
    j["surface"] = s.description;
    j["checks"] = surface_checks_json(r.sums, s);
    j["binning"] = {{"theta_bins", r.bins.n_theta()}, {"phi_bins", r.bins.n_phi()},
                    {"theta_range_deg", {0, 180}}, {"stderr_blocks", r.blocks * r.blocks},
                    {"rows", "one per theta ring, D averaged over phi"}};
    j["rows"] = ndf_table(r, s).rows;
    j.update(run_header("measure ndf", g));
    j["file"] = o.surface;
    j["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    write_record(g, o.output, j);
  }
  if (!g.quiet) {
    Json c = surface_checks_json(r.sums, s);
    std::cout << "D of " << o.surface << " (phi-averaged rings; stderr from "
              << r.blocks * r.blocks << " spatial blocks)\n"
              << "[GeomBSDF24, eq. 1b] |error| " << c["eq_1b_error"].get<double>() << ", eq. 1c |error| "
              << c["eq_1c_error"].get<double>() << "\n"
              << std::setw(12) << "theta_deg" << std::setw(14) << "D" << std::setw(12) << "stderr"
              << std::setw(14) << "nominal" << std::setw(9) << "z" << "\n";
    const Json rows = ndf_table(r, s).rows;
    for (const auto& row : rows) {
      if (row["d"].get<double>() == 0 && (row["d_nominal"].is_null() || row["d_nominal"].get<double>() < 1e-6))
        continue;
      std::cout << std::setw(5) << fmt(row["theta_lo_deg"].get<double>(), 0) << "-" << std::setw(6)
                << std::left << fmt(row["theta_hi_deg"].get<double>(), 0) << std::right
                << std::setw(14) << fmt(row["d"].get<double>(), 5) << std::setw(12)
                << fmt(row["d_stderr"].get<double>(), 5);
      if (!row["d_nominal"].is_null())
        std::cout << std::setw(14) << fmt(row["d_nominal"].get<double>(), 5) << std::setw(9)
                  << fmt(row["z"], 2);
      std::cout << "\n";
    }
    std::cout << "wrote " << o.output << "\n";
  }
  return 0;
}

void register_measure_ndf(CLI::App& measure, const GlobalOptions& g) {
  auto* ndf = measure.add_subcommand("ndf", "Normal distribution D over the sphere, from the facets");
  auto mo = std::make_shared<MeasureOptions>();
  ndf->add_option("surface", mo->surface, "Surface file")->required();
  ndf->add_option("-o,--output", mo->output, "Output (.json, .csv, .exr)")->required();
  ndf->add_option("--theta-bins", mo->theta_bins, "Theta bins over [0, 180] deg")
      ->check(CLI::Range(1, 3600))->capture_default_str();
  ndf->add_option("--phi-bins", mo->phi_bins, "Phi bins over [0, 360) deg")
      ->check(CLI::Range(1, 7200))->capture_default_str();
  ndf->callback([mo, &g] { run_measure_ndf(*mo, g); });
}

}  // namespace microsim::cli
