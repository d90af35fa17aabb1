// microsim measure g1 FILE... : masking by ray casting and area sampling, beside Smith (the
// library's G1Request).
#include <iomanip>
#include <memory>
#include <iostream>

#include "cli_common.hpp"
#include "measure_options.hpp"
#include "option_checks.hpp"
#include "commands.hpp"
#include "microsim/api/g1_request.hpp"
#include "microsim/io/output.hpp"

namespace microsim::cli {

namespace {

void print_g1_table(const Json& rows, bool ensemble) {
  std::cout << std::setw(7) << "theta" << std::setw(6) << "phi" << std::setw(10) << "g1"
            << std::setw(10) << "stderr" << std::setw(10) << "raycast" << std::setw(10)
            << "smith_num" << std::setw(8) << "z_num" << std::setw(10) << "smith_nom"
            << std::setw(10) << "rel_dev" << std::setw(9) << (ensemble ? "z_nom" : "vis_ar")
            << std::setw(8) << (ensemble ? "" : "max|z|") << "\n";
  for (const auto& row : rows) {
    std::cout << std::setw(7) << fmt(row["theta_deg"].get<double>(), 1) << std::setw(6)
              << fmt(row["phi_deg"].get<double>(), 0) << std::setw(10)
              << fmt(row["g1"].get<double>()) << std::setw(10)
              << fmt(row["g1_stderr"].get<double>(), 5) << std::setw(10)
              << fmt(row["g1_raycast"].get<double>()) << std::setw(10)
              << fmt(row["smith_numeric"].get<double>()) << std::setw(8)
              << fmt(row["z_numeric"], 2);
    if (!row["smith_nominal"].is_null())
      std::cout << std::setw(10) << fmt(row["smith_nominal"].get<double>()) << std::setw(9)
                << fmt(100 * row["rel_dev_nominal"].get<double>(), 2) << "%";
    else
      std::cout << std::setw(10) << "-" << std::setw(10) << "-";
    if (ensemble)
      std::cout << std::setw(9)
                << (row["z_nominal"].is_null() ? std::string("-") : fmt(row["z_nominal"].get<double>(), 2));
    else
      std::cout << std::setw(9) << fmt(row["visible_area_ratio"].get<double>()) << std::setw(8)
                << fmt(row["max_abs_z_estimators"].get<double>(), 2);
    std::cout << "\n";
  }
}

}  // namespace

int run_measure_g1(const MeasureOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv"});
  G1Request request;
  request.theta = angle_list(o.theta, "theta");
  request.phi = azimuth_list(o.phi, "phi");
  request.surfaces = input_surface_sources(g, {o.surface});
  for (const std::string& f : o.extra_surfaces) request.surfaces.push_back(input_surface_source(g, f));
  request.rays = o.rays;
  request.seed = o.seed;
  request.replicates = o.replicates;
  Progress progress("measure g1", g.quiet);
  RunContext ctx = run_context(g);
  ctx.progress = [&](double f) { progress.update(f); };
  const Json j = measure_g1_record(request, ctx);
  progress.finish();
  write_record(g, o.output, j);
  if (!g.quiet) {
    const std::size_t n = request.surfaces.size();
    std::cout << "G1 of " << (n == 1 ? o.surface : std::to_string(n) + " surfaces")
              << "  (" << o.rays << " rays per estimator and direction"
              << (n > 1 ? "; stderr between surfaces" : "") << ")\n";
    print_g1_table(j["rows"], n > 1);
    std::cout << "rays lost " << j["lost_rays"].get<std::uint64_t>()
              << (j.contains("missed_rays")
                      ? ", rays missing the object " + std::to_string(j["missed_rays"].get<std::uint64_t>())
                      : std::string())
              << ", back-face hits " << j["backface_hits"].get<std::uint64_t>() << ", "
              << fmt(j["rays_per_second"].get<double>() / 1e6, 2) << " Mrays/s; wrote " << o.output << "\n";
  }
  return 0;
}

void register_measure_g1(CLI::App& measure, const GlobalOptions& g) {
  auto* g1 = measure.add_subcommand("g1", "Masking G1 per direction: ray casting and area sampling, beside Smith");
  auto mo = std::make_shared<MeasureOptions>();
  auto files = std::make_shared<std::vector<std::string>>();
  g1->add_option("surfaces", *files,
                 "Surface file(s). Several independent surfaces of the same statistics (e.g. "
                 "seeds) give rows averaged over them with the between-surface standard error")
      ->required();
  g1->add_option("-o,--output", mo->output, "Output (.json or .csv)")->required();
  g1->add_option("--theta", mo->theta, "View zenith angles in degrees: a, a,b,c or start:stop:step")->capture_default_str();
  g1->add_option("--phi", mo->phi, "View azimuths in degrees, same syntax")->capture_default_str();
  add_rays_seed_options(*g1, mo->rays, mo->seed, "Rays per estimator and direction");
  add_replicates_option(*g1, mo->replicates);
  g1->callback([mo, files, &g] {
    mo->surface = files->front();
    mo->extra_surfaces.assign(files->begin() + 1, files->end());
    run_measure_g1(*mo, g);
  });
}

}  // namespace microsim::cli
