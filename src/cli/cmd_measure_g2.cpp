// microsim measure g2 FILE... : masking-shadowing by area sampling with two occlusion rays,
// beside the four Smith forms [Heitz14, eq. 20-23] and the V-cavity model (the library's G2Request).
#include <iomanip>
#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "measure_options.hpp"
#include "option_checks.hpp"
#include "microsim/api/g2_request.hpp"

namespace microsim::cli {

namespace {

struct G2CliOptions {
  std::vector<std::string> files;
  std::string output;
  std::string theta_o, phi_o = "0", theta_i, phi_i = "0";
  long long rays = 1000000;
  std::uint64_t seed = 1;
  int replicates = 32;
};

const char* kForms[] = {"separable", "height_correlated", "direction_correlated",
                        "height_direction_correlated"};

void print_g2_table(const Json& rows, bool ensemble) {
  std::cout << std::setw(6) << "th_o" << std::setw(6) << "ph_o" << std::setw(6) << "th_i"
            << std::setw(6) << "ph_i" << std::setw(9) << "g2" << std::setw(9) << "stderr"
            << std::setw(9) << "g1o*g1i" << std::setw(9) << "separ" << std::setw(9) << "height"
            << std::setw(9) << "dir" << std::setw(9) << "ht-dir" << std::setw(9) << "vcavity"
            << " |" << std::setw(8) << "sep" << std::setw(8) << "height" << std::setw(8) << "dir"
            << std::setw(8) << "ht-dir" << "\n"
            << "  Smith forms with Lambda from " << (ensemble ? "each surface's" : "the surface's")
            << " facets | z of the forms built per normal bin from the measured G1s\n";
  for (const auto& row : rows) {
    std::cout << std::setw(6) << fmt(row["theta_o_deg"].get<double>(), 1) << std::setw(6)
              << fmt(row["phi_o_deg"].get<double>(), 0) << std::setw(6)
              << fmt(row["theta_i_deg"].get<double>(), 1) << std::setw(6)
              << fmt(row["phi_i_deg"].get<double>(), 0) << std::setw(9)
              << fmt(row["g2"].get<double>()) << std::setw(9)
              << fmt(row["g2_stderr"].get<double>(), 5) << std::setw(9)
              << fmt(row["g1_o"].get<double>() * row["g1_i"].get<double>());
    for (const char* f : kForms)
      std::cout << std::setw(9) << fmt(row[std::string("smith_") + f].get<double>());
    std::cout << std::setw(9) << fmt(row["vcavity"].get<double>()) << " |";
    for (const char* f : kForms)
      std::cout << std::setw(8) << fmt(row[std::string("z_") + f + "_from_g1"], 1);
    std::cout << "\n";
  }
}

int run_measure_g2(const G2CliOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv"});
  G2Request request;
  request.surfaces = input_surface_sources(g, o.files);
  request.theta_o = angle_list(o.theta_o, "theta_o");
  request.phi_o = azimuth_list(o.phi_o, "phi_o");
  request.theta_i = angle_list(o.theta_i, "theta_i");
  request.phi_i = azimuth_list(o.phi_i, "phi_i");
  request.rays = o.rays;
  request.seed = o.seed;
  request.replicates = o.replicates;
  Progress progress("measure g2", g.quiet);
  RunContext ctx = run_context(g);
  ctx.progress = [&](double f) { progress.update(f); };
  const Json j = measure_g2_record(request, ctx);
  progress.finish();
  write_record(g, o.output, j);
  if (!g.quiet) {
    std::cout << "G2 of "
              << (o.files.size() == 1 ? o.files[0] : std::to_string(o.files.size()) + " surfaces")
              << "  (" << o.rays << " area samples per direction pair"
              << (o.files.size() > 1 ? "; stderr between surfaces" : "") << ")\n";
    print_g2_table(j["rows"], o.files.size() > 1);
    std::cout << "rays lost " << j["lost_rays"].get<std::uint64_t>() << ", back-face hits "
              << j["backface_hits"].get<std::uint64_t>() << ", "
              << fmt(j["rays_per_second"].get<double>() / 1e6, 2) << " Mrays/s; wrote " << o.output << "\n";
  }
  return 0;
}

}  // namespace

void register_measure_g2(CLI::App& measure, const GlobalOptions& g) {
  auto* cmd = measure.add_subcommand(
      "g2", "Masking-shadowing G2(o, m, i) by area sampling with two occlusion rays, beside the "
            "four Smith forms and the V-cavity model");
  auto o = std::make_shared<G2CliOptions>();
  cmd->add_option("surfaces", o->files,
                  "Surface file(s). Several independent surfaces of the same statistics give rows "
                  "averaged over them with the between-surface standard error")
      ->required();
  cmd->add_option("-o,--output", o->output, "Output (.json or .csv)")->required();
  cmd->add_option("--theta-o", o->theta_o,
                  "View (outgoing) zenith angles in degrees, [0, 90): a, a,b,c or start:stop:step")
      ->required();
  cmd->add_option("--phi-o", o->phi_o, "View azimuths in degrees, same syntax")->capture_default_str();
  cmd->add_option("--theta-i", o->theta_i, "Light (incoming) zenith angles in degrees, [0, 90)")
      ->required();
  cmd->add_option("--phi-i", o->phi_i, "Light azimuths in degrees")->capture_default_str();
  add_rays_seed_options(*cmd, o->rays, o->seed, "Area samples per direction pair (two occlusion rays each)");
  add_replicates_option(*cmd, o->replicates);
  cmd->callback([o, &g] { run_measure_g2(*o, g); });
}

}  // namespace microsim::cli
