// microsim generate KIND: build a microsurface and save it.
#include <iostream>

#include "cli_common.hpp"
#include "commands.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/surface_io.hpp"

namespace microsim::cli {

void require_surface_extension(const std::string& path) {
  std::string ext = extension_of(path);
  if (ext != "exr" && ext != "ply" && ext != "obj" && ext != "off")
    throw UsageError("-o " + path + ": unknown surface format (use .exr, .ply, .obj or .off)");
}

int run_generate_gaussian(GenerateOptions o, const GlobalOptions& g) {
  if (o.alpha != -1) {
    if (o.alpha_x_given || o.alpha_y_given)
      throw UsageError("--alpha cannot be combined with --alpha-x/--alpha-y");
    o.gaussian.alpha_x = o.gaussian.alpha_y = o.alpha;
  } else if (o.alpha_x_given != o.alpha_y_given) {
    // One axis given: the other keeps the same value (isotropic unless both are given).
    if (o.alpha_x_given) o.gaussian.alpha_y = o.gaussian.alpha_x;
    else o.gaussian.alpha_x = o.gaussian.alpha_y;
  }
  validate(o.gaussian);
  require_surface_extension(o.output);
  Microsurface s = generate_gaussian(o.gaussian);
  save_surface(s, o.output);
  if (!g.quiet) {
    FacetSums f = facet_sums(s);
    std::cout << "wrote " << o.output << ": gaussian " << o.gaussian.resolution << "^2, alpha ("
              << o.gaussian.alpha_x << ", " << o.gaussian.alpha_y << "), fitted alpha ("
              << fmt(std::sqrt(2 * f.slope_var_x)) << ", " << fmt(std::sqrt(2 * f.slope_var_y))
              << ")\n";
  }
  return 0;
}

void register_generate(CLI::App& app, const GlobalOptions& g) {
  auto* gen = app.add_subcommand("generate", "Generate a microsurface and save it (.exr, .ply, .obj, .off)");
  gen->require_subcommand(1);
  auto go = std::make_shared<GenerateOptions>();
  auto* gauss = gen->add_subcommand(
      "gaussian", "Periodic Gaussian random heightfield with Beckmann slope statistics");
  gauss->set_config("--config", "", "Read options from a TOML preset (e.g. surfaces/beckmann-0.5.toml)");
  gauss->add_option("-o,--output", go->output, "Output surface file (.exr, .ply, .obj, .off)")->required();
  add_gaussian_options(*gauss, *go);
  gauss->callback([go, gauss, &g] {
    go->alpha_x_given = gauss->count("--alpha-x") > 0;
    go->alpha_y_given = gauss->count("--alpha-y") > 0;
    run_generate_gaussian(*go, g);
  });

  auto flat = std::make_shared<FlatParams>();
  auto flat_out = std::make_shared<std::string>();
  auto* fl = gen->add_subcommand("flat", "Periodic plane z = 0: the exact reference of every estimator");
  fl->set_config("--config", "", "Read options from a TOML preset");
  fl->add_option("-o,--output", *flat_out, "Output surface file (.exr, .ply, .obj, .off)")->required();
  fl->add_option("--resolution", flat->resolution, "Grid cells per side")->capture_default_str();
  fl->add_option("--size", flat->size, "Tile side length")->capture_default_str();
  fl->callback([=, &g] {
    require_surface_extension(*flat_out);
    Microsurface s = generate_flat(*flat);
    save_surface(s, *flat_out);
    if (!g.quiet) std::cout << "wrote " << *flat_out << ": flat plane\n";
  });
}

void add_gaussian_options(CLI::App& cmd, GenerateOptions& go) {
  cmd.add_option("--resolution", go.gaussian.resolution, "Grid cells per side")->capture_default_str();
  cmd.add_option("--size", go.gaussian.size, "Tile side length")->capture_default_str();
  cmd.add_option("--correlation-length", go.gaussian.correlation_length,
                 "Correlation length of the heights exp(-r^2/l^2), tile units (default: 4 cells)");
  cmd.add_option("--alpha", go.alpha, "Isotropic Beckmann roughness alpha (> 0)");
  cmd.add_option("--alpha-x", go.gaussian.alpha_x, "Roughness along x");
  cmd.add_option("--alpha-y", go.gaussian.alpha_y, "Roughness along y");
  cmd.add_option("--seed", go.gaussian.seed, "Random seed")->capture_default_str();
}

}  // namespace microsim::cli
