// microsim demo: the README's first command. Generates the default preset, measures D and G1
// and prints them beside Smith.
#include <iostream>

#include "cli_common.hpp"
#include "option_checks.hpp"
#include "commands.hpp"
#include "microsim/io/output.hpp"

namespace microsim::cli {

namespace {
int run_demo(const SurfaceRequest& surface, MeasureOptions meas, const std::string& dir,
             const GlobalOptions& g) {
  // Every option is checked before anything is written (the outputs are committed together at
  // the end by main's OutputTransaction).
  std::vector<double> thetas = parse_angle_list(meas.theta, "--theta");
  require_above_horizon(thetas, "--theta");
  check_surface_request(surface);
  // A folder created here is removed again if the command fails or is interrupted.
  if (!create_output_folder(dir))
    throw UsageError("--out-dir " + dir + ": cannot create the folder");
  meas.surface = dir + "/surface.exr";
  write_generated(surface, meas.surface, g);
  meas.output = dir + "/ndf.json";
  if (!g.quiet) std::cout << "\n";
  run_measure_ndf(meas, g);
  meas.output = dir + "/g1.json";
  if (!g.quiet) std::cout << "\n";
  run_measure_g1(meas, g);
  return 0;
}

}  // namespace

void register_demo(CLI::App& app, const GlobalOptions& g) {
  auto* demo = app.add_subcommand(
      "demo", "Generate a surface (default preset), measure D and G1, print measured vs Smith");
  const SurfaceKind* gaussian = &surface_kind("gaussian");
  auto gen = std::make_shared<SurfaceOptionValues>();
  auto meas = std::make_shared<MeasureOptions>();
  auto dir = std::make_shared<std::string>("microsim-demo");
  add_preset_option(*demo, "Surface preset (TOML), e.g. surfaces/beckmann-0.5.toml; command-line options win");
  add_surface_options(*demo, *gaussian, *gen);
  demo->add_option("--theta", meas->theta, "View zenith angles (deg)")->capture_default_str();
  demo->add_option("--rays", meas->rays, "Rays per estimator and direction")->capture_default_str()
      ->check(integer_in(1, kMaxRays));
  demo->add_option("--out-dir", *dir, "Folder for the surface and the tables")->capture_default_str();
  on_run(demo, [=, &g] { run_demo(given_surface_options(*gaussian, *gen), *meas, *dir, g); });
}

}  // namespace microsim::cli
