// microsim command line: parse with CLI11, dispatch to src/cli/commands.cpp.
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <iostream>
#include <memory>

#include "commands.hpp"
#include "microsim/common.hpp"

using namespace microsim;
using namespace microsim::cli;

int main(int argc, char** argv) {
  CLI::App app{"microsim: explicit microsurface Monte Carlo simulator.\n"
               "Builds microgeometry, ray-traces it with Embree, measures D, G1 (and more) with "
               "standard errors beside the analytic Smith model."};
  app.require_subcommand(1);
  app.fallthrough();  // --threads and --quiet are accepted after the subcommand too
  GlobalOptions g;
  app.add_option("--threads", g.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 4096));
  app.add_flag("--quiet,-q", g.quiet, "No progress display and no table on stdout");
  app.set_version_flag("--version", "microsim 0.1.0");

  // generate
  auto* gen = app.add_subcommand("generate", "Generate a microsurface and save it (.exr, .ply, .obj)");
  gen->require_subcommand(1);
  GenerateOptions go;
  auto* gauss = gen->add_subcommand(
      "gaussian", "Periodic Gaussian random heightfield with Beckmann slope statistics");
  gauss->set_config("--config", "", "Read options from a TOML preset (e.g. surfaces/beckmann-0.5.toml)");
  gauss->add_option("-o,--output", go.output, "Output surface file (.exr, .ply, .obj, .off)")->required();
  gauss->add_option("--resolution", go.gaussian.resolution, "Grid cells per side")->capture_default_str();
  gauss->add_option("--size", go.gaussian.size, "Tile side length")->capture_default_str();
  gauss->add_option("--correlation-length", go.gaussian.correlation_length,
                    "Correlation length of the heights, in tile units (default: 4 cells)");
  gauss->add_option("--alpha", go.alpha, "Isotropic Beckmann roughness alpha (> 0)");
  gauss->add_option("--alpha-x", go.gaussian.alpha_x, "Roughness along x");
  gauss->add_option("--alpha-y", go.gaussian.alpha_y, "Roughness along y");
  gauss->add_option("--seed", go.gaussian.seed, "Random seed")->capture_default_str();

  // demo: generate the default preset, measure D and G1, print them beside Smith.
  auto* demo = app.add_subcommand(
      "demo", "Generate a surface (default preset), measure D and G1, print measured vs Smith");
  GenerateOptions demo_gen;
  MeasureOptions demo_meas;
  std::string demo_dir = "microsim-demo";
  demo->set_config("--config", "", "Surface preset (TOML), e.g. surfaces/beckmann-0.5.toml");
  demo->add_option("--resolution", demo_gen.gaussian.resolution, "Grid cells per side")->capture_default_str();
  demo->add_option("--size", demo_gen.gaussian.size, "Tile side length");
  demo->add_option("--correlation-length", demo_gen.gaussian.correlation_length, "Correlation length");
  demo->add_option("--alpha", demo_gen.alpha, "Isotropic Beckmann roughness");
  demo->add_option("--alpha-x", demo_gen.gaussian.alpha_x, "Roughness along x");
  demo->add_option("--alpha-y", demo_gen.gaussian.alpha_y, "Roughness along y");
  demo->add_option("--seed", demo_gen.gaussian.seed, "Random seed")->capture_default_str();
  demo->add_option("--theta", demo_meas.theta, "View zenith angles (deg)")->capture_default_str();
  demo->add_option("--rays", demo_meas.rays, "Rays per estimator and direction")->capture_default_str();
  demo->add_option("--out-dir", demo_dir, "Folder for the surface and the tables")->capture_default_str();

  // convert
  auto* conv = app.add_subcommand("convert", "Save a surface in another format (.exr heightfield, .ply/.obj/.off mesh)");
  std::string conv_in, conv_out;
  conv->add_option("surface", conv_in, "Surface file")->required();
  conv->add_option("-o,--output", conv_out, "Output surface file")->required();

  // info
  auto* info = app.add_subcommand("info", "Describe a surface: parameters, slope statistics, fitted alpha, 000 eq. 1b/1c");
  std::string info_file, info_json;
  info->add_option("surface", info_file, "Surface file")->required();
  info->add_option("--json", info_json, "Also write the description as JSON");

  // measure
  auto* meas = app.add_subcommand("measure", "Measure a quantity on a surface");
  meas->require_subcommand(1);
  MeasureOptions mo;
  auto* ndf = meas->add_subcommand("ndf", "Normal distribution D over the sphere, from the facets");
  ndf->add_option("surface", mo.surface, "Surface file")->required();
  ndf->add_option("-o,--output", mo.output, "Output (.json, .csv, .exr)")->required();
  ndf->add_option("--theta-bins", mo.theta_bins, "Theta bins over [0, 180] deg")->check(CLI::Range(1, 3600));
  ndf->add_option("--phi-bins", mo.phi_bins, "Phi bins over [0, 360) deg")->check(CLI::Range(1, 7200));
  auto* g1 = meas->add_subcommand("g1", "Masking G1 per direction: ray casting and area sampling, beside Smith");
  std::vector<std::string> g1_surfaces;
  g1->add_option("surfaces", g1_surfaces,
                 "Surface file(s). Several independent surfaces of the same statistics (e.g. "
                 "seeds) give rows averaged over them with the between-surface standard error")
      ->required();
  g1->add_option("-o,--output", mo.output, "Output (.json or .csv)")->required();
  g1->add_option("--theta", mo.theta, "View zenith angles in degrees: a, a,b,c or start:stop:step")->capture_default_str();
  g1->add_option("--phi", mo.phi, "View azimuths in degrees, same syntax")->capture_default_str();
  g1->add_option("--rays", mo.rays, "Rays per estimator and direction")->capture_default_str();
  g1->add_option("--seed", mo.seed, "Random seed")->capture_default_str();

  // An unknown command or surface kind names itself (CLI11 would only say that a subcommand
  // is missing): walk the leading words down the command tree.
  {
    const CLI::App* level = &app;
    for (int k = 1; k < argc && argv[k][0] != '-' && !level->get_subcommands({}).empty(); ++k) {
      std::string names;
      const CLI::App* next = nullptr;
      for (const auto* sub : level->get_subcommands({})) {
        names += (names.empty() ? "" : ", ") + sub->get_name();
        if (sub->get_name() == argv[k]) next = sub;
      }
      if (!next) {
        std::cerr << "microsim: error: unknown " << (level == gen ? "surface kind" : "command")
                  << " '" << argv[k] << "' (known: " << names << ")\n";
        return 2;
      }
      level = next;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "microsim: error: " << e.what() << "\n";
    return 2;
  }

  std::unique_ptr<tbb::global_control> threads;
  if (g.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    g.threads);
  try {
    if (*gauss) {
      go.alpha_x_given = gauss->count("--alpha-x") > 0;
      go.alpha_y_given = gauss->count("--alpha-y") > 0;
      return run_generate_gaussian(go, g);
    }
    if (*demo) {
      demo_gen.alpha_x_given = demo->count("--alpha-x") > 0;
      demo_gen.alpha_y_given = demo->count("--alpha-y") > 0;
      return run_demo(demo_gen, demo_meas, demo_dir, g);
    }
    if (*info) return run_info(info_file, info_json, g);
    if (*conv) return run_convert(conv_in, conv_out, g);
    if (*ndf) return run_measure_ndf(mo, g);
    if (*g1) {
      mo.surface = g1_surfaces.front();
      mo.extra_surfaces.assign(g1_surfaces.begin() + 1, g1_surfaces.end());
      return run_measure_g1(mo, g);
    }
  } catch (const UsageError& e) {
    std::cerr << "microsim: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "microsim: failed: " << e.what() << "\n";
    return 1;
  }
  return 2;
}
