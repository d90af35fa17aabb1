// microsim measure ndf FILE -o OUT: D over the sphere from the facets (the library's NdfRequest).
#include <iomanip>
#include <iostream>

#include "cli_common.hpp"
#include "option_checks.hpp"
#include "commands.hpp"
#include "microsim/api/ndf_request.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/surface_io.hpp"

namespace microsim::cli {

namespace {

void print_ndf_table(const NdfRun& run, const std::string& file) {
  const NdfResult& r = run.result;
  Json c = surface_checks_json(r.sums, *run.surface);
  std::cout << "D of " << file << " (phi-averaged rings; stderr from "
            << r.blocks * r.blocks << " spatial blocks)\n"
            << "[GeomBSDF24, eq. 1b] |error| " << c["eq_1b_error"].get<double>() << ", eq. 1c |error| "
            << c["eq_1c_error"].get<double>() << "\n"
            << std::setw(12) << "theta_deg" << std::setw(14) << "D" << std::setw(12) << "stderr"
            << std::setw(14) << "nominal" << std::setw(9) << "z" << "\n";
  const Json rows = ndf_table(r, *run.surface).rows;
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
}

}  // namespace

int run_measure_ndf(const MeasureOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv", "exr"});
  NdfRequest request;
  request.surface = input_surface_source(g, o.surface);
  request.theta_bins = o.theta_bins;
  request.phi_bins = o.phi_bins;
  const NdfRun run = run_ndf(request);
  if (extension_of(o.output) == "exr") write_exr(o.output, ndf_to_exr(run.result, *run.surface));
  else write_record(g, o.output, ndf_record(request, run, run_context(g)));
  if (!g.quiet) {
    print_ndf_table(run, o.surface);
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
