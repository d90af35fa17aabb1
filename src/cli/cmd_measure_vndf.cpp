// microsim measure vndf FILE... : histogram of first-hit normals of rays along -v against the
// analytic distribution of visible normals [Heitz14, eq. 13], and a chi-square test of the VNDF
// sampler of the surface's nominal NDF (the library's VndfRequest).
#include <iomanip>
#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "measure_options.hpp"
#include "option_checks.hpp"
#include "microsim/api/vndf_request.hpp"

namespace microsim::cli {

namespace {

struct VndfCliOptions {
  std::vector<std::string> files;
  std::string output;
  std::string theta = "0:80:20", phi = "0";
  long long rays = 1000000;
  long long sampler_samples = 1000000;
  std::uint64_t seed = 1;
  int theta_bins = 18, phi_bins = 16;
};

void print_vndf_table(const Json& rows, bool ensemble) {
  std::cout << std::setw(7) << "theta" << std::setw(6) << "phi" << std::setw(11) << "chi2/dof"
            << std::setw(10) << "p" << std::setw(9) << "max|z|" << std::setw(8) << "sidak"
            << std::setw(9) << "tv_dist" << std::setw(14) << "smith_num p" << std::setw(14)
            << "sampler p" << "\n";
  for (const auto& row : rows) {
    std::cout << cell(row["theta_deg"], 1, 7) << cell(row["phi_deg"], 0, 6);
    if (!ensemble && row["chi2"].is_number())
      std::cout << std::setw(11)
                << (fmt(row["chi2"].get<double>(), 0) + "/" + std::to_string(row["dof"].get<int>()))
                << cell(row["p_value"], 4, 10);
    else
      std::cout << std::setw(11) << "-" << std::setw(10) << "-";
    // Ensembles' z divide by the between-surface error, which can be tiny: max|z| of 10^6 and
    // more happen, and must not push the columns after it.
    std::cout << cell(row.value("max_abs_z", Json()), 2, 9) << cell(row.value("sidak_z", Json()), 2, 8)
              << cell(row.value("tv_distance", Json()), 4, 9) << cell(row.value("p_value_smith_numeric", Json()), 4, 14)
              << cell(row.value("sampler_p_value", Json()), 4, 14) << "\n";
  }
}

int run_measure_vndf(const VndfCliOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv"});
  VndfRequest request;
  request.surfaces = input_surface_sources(g, o.files);
  request.theta = angle_list(o.theta, "theta");
  request.phi = azimuth_list(o.phi, "phi");
  request.rays = o.rays;
  request.sampler_samples = o.sampler_samples;
  request.seed = o.seed;
  request.theta_bins = o.theta_bins;
  request.phi_bins = o.phi_bins;
  Progress progress("measure vndf", g.quiet);
  RunContext ctx = run_context(g);
  ctx.progress = [&](double f) { progress.update(f); };
  const Json j = measure_vndf_record(request, ctx);
  progress.finish();
  write_record(g, o.output, j);
  if (!g.quiet) {
    std::cout << "VNDF of "
              << (o.files.size() == 1 ? o.files[0] : std::to_string(o.files.size()) + " surfaces")
              << "  (" << o.rays << " rays per direction; " << o.theta_bins << " x "
              << o.phi_bins << " normal bins)\n";
    print_vndf_table(j["rows"], o.files.size() > 1);
    std::cout << "rays lost " << j["lost_rays"].get<std::uint64_t>() << ", back-face hits "
              << j["backface_hits"].get<std::uint64_t>() << "; wrote " << o.output << "\n";
  }
  return 0;
}

}  // namespace

void register_measure_vndf(CLI::App& measure, const GlobalOptions& g) {
  auto* cmd = measure.add_subcommand(
      "vndf", "Distribution of visible normals: first-hit normals of rays along -v against the "
              "analytic D_v, and a chi-square test of the nominal NDF's VNDF sampler");
  auto o = std::make_shared<VndfCliOptions>();
  cmd->add_option("surfaces", o->files,
                  "Surface file(s); several independent surfaces give between-surface errors")
      ->required();
  cmd->add_option("-o,--output", o->output, "Output (.json or .csv)")->required();
  cmd->add_option("--theta", o->theta, "View zenith angles in degrees, [0, 90): a, a,b,c or start:stop:step")
      ->capture_default_str();
  cmd->add_option("--phi", o->phi, "View azimuths in degrees, same syntax")->capture_default_str();
  add_rays_seed_options(*cmd, o->rays, o->seed, "Rays per direction");
  cmd->add_option("--sampler-samples", o->sampler_samples,
                  "Samples for the chi-square test of the nominal NDF's VNDF sampler (0: skip)")
      ->capture_default_str()
      ->check(integer_in(0, kMaxRays));
  cmd->add_option("--theta-bins", o->theta_bins, "Normal bins in theta_m over [0, 90] degrees")
      ->capture_default_str()
      ->check(integer_in(1, 360));
  cmd->add_option("--phi-bins", o->phi_bins, "Normal bins in phi_m over [0, 360) degrees")
      ->capture_default_str()
      ->check(integer_in(1, 720));
  cmd->callback([o, &g] { run_measure_vndf(*o, g); });
}

}  // namespace microsim::cli
