// microsim generate KIND: build a microsurface and save it.
#include <iostream>
#include <sstream>

#include "cli_common.hpp"
#include "commands.hpp"
#include "option_checks.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/surface/mesh_check.hpp"

namespace microsim::cli {

void require_surface_extension(const std::string& path) {
  std::string ext = extension_of(path);
  if (ext != "exr" && ext != "ply" && ext != "obj" && ext != "off")
    throw UsageError("-o " + path + ": unknown surface format (use .exr, .ply, .obj or .off)");
}

int run_generate_gaussian(GenerateOptions o, const GlobalOptions& g) {
  if (o.alpha_given) {
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
  output_surface(g, s, o.output);
  if (!g.quiet) {
    FacetSums f = facet_sums(s);
    std::cout << "wrote " << o.output << ": gaussian " << o.gaussian.resolution << "^2, alpha ("
              << o.gaussian.alpha_x << ", " << o.gaussian.alpha_y << "), fitted alpha ("
              << fmt(std::sqrt(2 * f.slope_var_x)) << ", " << fmt(std::sqrt(2 * f.slope_var_y))
              << ")\n";
  }
  return 0;
}

namespace {

// Mesh kinds cannot be saved as an EXR heightfield: refuse before generating.
void require_mesh_extension(const std::string& path) {
  require_surface_extension(path);
  if (extension_of(path) == "exr")
    throw UsageError("-o " + path + ": this surface is a mesh; use .ply, .obj or .off");
}

// --alpha shorthand or --alpha-x/--alpha-y (one axis given: isotropic). "Given" means on the
// command line or in the preset, never a sentinel value.
void resolve_alpha(const CLI::App& k, double alpha, double& ax, double& ay) {
  const bool x_given = k.count("--alpha-x") > 0, y_given = k.count("--alpha-y") > 0;
  if (k.count("--alpha") > 0) {
    if (x_given || y_given) throw UsageError("--alpha cannot be combined with --alpha-x/--alpha-y");
    ax = ay = alpha;
  } else if (x_given != y_given) {
    if (x_given) ay = ax; else ax = ay;
  }
}

void summary(const Microsurface& s, const std::string& path, const GlobalOptions& g) {
  if (g.quiet) return;
  FacetSums f = facet_sums(s);
  const Macrosurface& m = s.macro();
  const Vec3 e = f.sum_area_normal / m.area - m.normal;
  double below = 0;
  for (std::size_t k = 0; k < s.num_facets(); ++k) {
    Triangle t = s.facet(k);
    if (t.cross().z() < 0) below += t.area();
  }
  std::cout << "wrote " << path << ": " << s.description.value("kind", std::string("surface")) << ", "
            << s.num_facets() << " facets, " << (m.periodic ? "periodic tile " : "finite object, window ")
            << m.size_x << " x " << m.size_y << ", A = " << m.area << "; 000 eq. 1b |error| "
            << e.norm() << "; area facing down (n.m < 0): " << below / f.total_area * 100 << "%\n";
}

std::vector<double> parse_numbers(const std::string& text, const std::string& option, std::size_t count) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      std::size_t used = 0;
      double x = std::stod(item, &used);
      if (used != item.size() || !std::isfinite(x)) throw std::invalid_argument(item);
      out.push_back(x);
    } catch (const std::exception&) {
      throw UsageError(option + " '" + text + "': expected " + std::to_string(count) +
                       " comma-separated numbers");
    }
  }
  if (out.size() != count)
    throw UsageError(option + " '" + text + "': expected " + std::to_string(count) +
                     " comma-separated numbers");
  return out;
}

struct Out {
  std::string path;
};

CLI::App* kind(CLI::App& gen, const char* name, const char* help, std::shared_ptr<Out> out) {
  auto* k = gen.add_subcommand(name, help);
  add_preset_option(*k, "Read options from a TOML preset (see surfaces/); command-line options win");
  k->add_option("-o,--output", out->path, "Output surface file (.ply, .obj, .off; .exr for heightfields)")
      ->required();
  return k;
}

void register_structured_kinds(CLI::App& gen, const GlobalOptions& g) {
  {
    auto out = std::make_shared<Out>();
    auto p = std::make_shared<BoxParams>();
    auto* k = kind(gen, "box", "A box whose flipped bottom face is the macrosurface (000 Fig. 2); finite", out);
    k->add_option("--width", p->width, "W, along x")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--depth", p->depth, "D, along y")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--height", p->height, "H, along z")->capture_default_str()
        ->check(number_in(positive()));
    on_run(k, [=, &g] {
      require_mesh_extension(out->path);
      Microsurface s = generate_box(*p);
      output_surface(g, s, out->path);
      summary(s, out->path, g);
    });
  }
  {
    auto out = std::make_shared<Out>();
    auto p = std::make_shared<BoxParams>();
    p->tiles = 4;
    auto* k = kind(gen, "tiled-boxes",
                   "The box's macrosurface covered by N x N copies of the box scaled by 1/N (000 Fig. 6)", out);
    k->add_option("--tiles", p->tiles, "N")->capture_default_str()
        ->check(integer_in(1, 256));
    k->add_option("--width", p->width, "W of the whole (macrosurface), along x")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--depth", p->depth, "D of the whole, along y")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--height", p->height, "H of the unscaled box (each copy is H/N high)")->capture_default_str()
        ->check(number_in(positive()));
    on_run(k, [=, &g] {
      require_mesh_extension(out->path);
      Microsurface s = generate_tiled_boxes(*p);
      output_surface(g, s, out->path);
      summary(s, out->path, g);
    });
  }
  {
    auto out = std::make_shared<Out>();
    auto p = std::make_shared<SquareWaveParams>();
    auto* k = kind(gen, "square-wave",
                   "Periodic ridges along y (duty F of period P raised by H, vertical walls); --2d: blocks", out);
    k->add_option("--period", p->period, "P (the tile is P x P)")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--duty", p->duty, "F, raised fraction of the period, in (0, 1)")->capture_default_str()
        ->check(number_in({0, 1, true, true}));
    k->add_option("--height", p->height, "H")->capture_default_str()
        ->check(number_in(positive()));
    k->add_flag("--2d", p->two_d, "Raised F P x F P square blocks instead of ridges");
    on_run(k, [=, &g] {
      require_mesh_extension(out->path);
      Microsurface s = generate_square_wave(*p);
      output_surface(g, s, out->path);
      summary(s, out->path, g);
    });
  }
  {
    auto out = std::make_shared<Out>();
    auto p = std::make_shared<VGrooveParams>();
    auto* k = kind(gen, "vgroove",
                   "Periodic V-grooves along y, facet normals (+-sin tm, 0, cos tm); --2d: pyramids", out);
    k->add_option("--facet-angle", p->facet_angle_deg, "theta_m in degrees, in (0, 90)")->capture_default_str()
        ->check(number_in({0, 90, true, true}));
    k->add_option("--period", p->period, "P (the tile is one period, P x P)")->capture_default_str()
        ->check(number_in(positive()));
    k->add_flag("--2d", p->two_d, "Square pyramids (a mesh) instead of grooves (a heightfield)");
    on_run(k, [=, &g] {
      require_surface_extension(out->path);
      if (p->two_d) require_mesh_extension(out->path);
      Microsurface s = generate_vgroove(*p);
      output_surface(g, s, out->path);
      summary(s, out->path, g);
    });
  }
  {
    auto out = std::make_shared<Out>();
    auto p = std::make_shared<VCavityParams>();
    auto alpha = std::make_shared<double>(0.5);
    auto* k = kind(gen, "vcavity",
                   "The V-cavity model made explicit (001 Sec. 6.1): separate V-grooves with normals "
                   "drawn from D, each traced on its own by measure g1", out);
    k->add_option("--ndf", p->ndf, "beckmann or ggx")->capture_default_str();
    k->add_option("--alpha", *alpha, "Isotropic roughness alpha")
        ->check(number_in(positive()));
    k->add_option("--alpha-x", p->alpha_x, "Roughness along x")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--alpha-y", p->alpha_y, "Roughness along y")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--grooves", p->grooves, "Number of grooves K")->capture_default_str()
        ->check(integer_in(1, 1000000));
    k->add_option("--seed", p->seed, "Random seed")->capture_default_str()
        ->check(seed_value());
    on_run(k, [=, &g] {
      require_mesh_extension(out->path);
      resolve_alpha(*k, *alpha, p->alpha_x, p->alpha_y);
      Microsurface s = generate_vcavity(*p);
      output_surface(g, s, out->path);
      summary(s, out->path, g);
    });
  }
  {
    auto out = std::make_shared<Out>();
    auto p = std::make_shared<ParallelepipedParams>();
    auto shear_x = std::make_shared<double>(0.5), shear_y = std::make_shared<double>(0.0);
    auto matrix = std::make_shared<std::string>();
    auto* k = kind(gen, "parallelepiped",
                   "A box under a linear map (000 Fig. 3); shears make walls face downward (n.m < 0)", out);
    k->add_option("--width", p->width, "W of the box before the map")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--depth", p->depth, "D")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--height", p->height, "H")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--tiles", p->tiles, "N x N mapped boxes of size 1/N (neighbours share walls)")->capture_default_str()
        ->check(integer_in(1, 256));
    k->add_option("--shear-x", *shear_x, "x += shear_x z")->capture_default_str()
        ->check(finite_number());
    k->add_option("--shear-y", *shear_y, "y += shear_y z")->capture_default_str()
        ->check(finite_number());
    k->add_option("--matrix", *matrix,
                  "Row-major 3x3 map l11,...,l33 (third row 0,0,k with k > 0); replaces the shears");
    on_run(k, [=, &g] {
      require_mesh_extension(out->path);
      if (!matrix->empty()) {
        if (k->count("--shear-x") || k->count("--shear-y"))
          throw UsageError("--matrix cannot be combined with --shear-x/--shear-y");
        auto v = parse_numbers(*matrix, "--matrix", 9);
        std::copy(v.begin(), v.end(), p->matrix);
      } else {
        const double L[9] = {1, 0, *shear_x, 0, 1, *shear_y, 0, 0, 1};
        std::copy(L, L + 9, p->matrix);
      }
      Microsurface s = generate_parallelepiped(*p);
      output_surface(g, s, out->path);
      summary(s, out->path, g);
    });
  }
  {
    auto out = std::make_shared<Out>();
    auto p = std::make_shared<EllipsoidParams>();
    auto alpha = std::make_shared<double>(0.5);
    auto* k = kind(gen, "ellipsoid",
                   "Upper half of (ax x)^2 + (ay y)^2 + z^2 = 1: its NDF is GGX(ax, ay) (002); finite", out);
    k->add_option("--alpha", *alpha, "Isotropic alpha")
        ->check(number_in(positive()));
    k->add_option("--alpha-x", p->alpha_x, "alpha_x (semi-axis 1/alpha_x)")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--alpha-y", p->alpha_y, "alpha_y (semi-axis 1/alpha_y)")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--rings", p->rings, "Latitude steps of the tessellation")->capture_default_str()
        ->check(integer_in(2, 4096));
    k->add_option("--segments", p->segments, "Longitude steps")->capture_default_str()
        ->check(integer_in(8, 16384));
    on_run(k, [=, &g] {
      require_mesh_extension(out->path);
      resolve_alpha(*k, *alpha, p->alpha_x, p->alpha_y);
      Microsurface s = generate_ellipsoid(*p);
      output_surface(g, s, out->path);
      summary(s, out->path, g);
    });
  }
  {
    auto out = std::make_shared<Out>();
    auto p = std::make_shared<GaussianGgxParams>();
    auto alpha = std::make_shared<double>(0.5);
    auto* k = kind(gen, "gaussian-ggx",
                   "Periodic heightfield whose pooled NDF is GGX(alpha): Gaussian process with slowly "
                   "varying local roughness alpha/sqrt(E), E ~ Exp(1)", out);
    k->add_option("--resolution", p->resolution, "Grid cells per side")->capture_default_str()
        ->check(integer_in(4, 32760));
    k->add_option("--size", p->size, "Tile side length")->capture_default_str()
        ->check(number_in(closed(1e-6, 1e6)));
    k->add_option("--correlation-length", p->correlation_length,
                  "Of the heights (default: 16 cells, at least 16 per tile and 4 cells)")
        ->check(number_in(positive()));
    k->add_option("--roughness-correlation-length", p->roughness_correlation_length,
                  "Of the local roughness field (default: 16 correlation lengths)")
        ->check(number_in(positive()));
    k->add_option("--alpha", *alpha, "Isotropic GGX alpha")
        ->check(number_in(positive()));
    k->add_option("--alpha-x", p->alpha_x, "GGX alpha along x")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--alpha-y", p->alpha_y, "GGX alpha along y")->capture_default_str()
        ->check(number_in(positive()));
    k->add_option("--tail-fraction", p->tail_fraction,
                  "Area fraction whose local roughness is capped at alpha/sqrt(-ln(1-q))")->capture_default_str()
        ->check(number_in({0, 0.5, true, true}));
    k->add_option("--seed", p->seed, "Random seed")->capture_default_str()
        ->check(seed_value());
    on_run(k, [=, &g] {
      require_surface_extension(out->path);
      resolve_alpha(*k, *alpha, p->alpha_x, p->alpha_y);
      Microsurface s = generate_gaussian_ggx(*p);
      output_surface(g, s, out->path);
      summary(s, out->path, g);
    });
  }
  {
    auto out = std::make_shared<Out>();
    auto p = std::make_shared<MeshImportParams>();
    auto normal = std::make_shared<std::string>("0,0,1");
    auto* k = kind(gen, "mesh",
                   "Any PLY/OBJ/OFF mesh with a declared macrosurface (validated: manifold, not "
                   "degenerate, closed but for its rim, 000 eq. 1b)", out);
    k->add_option("--input", p->input, "Input mesh (.ply, .obj, .off)")->required();
    k->add_option("--normal", *normal, "Macrosurface normal x,y,z in the file's frame (rotated to +z)")
        ->capture_default_str();
    k->add_option("--area", p->area, "Macrosurface area A (default: from 000 eq. 1c, or the tile's)")
        ->check(number_in(positive()));
    k->add_flag("--periodic", p->periodic, "A periodic tile centered on the origin (else a finite object)");
    k->add_option("--tile-x", p->tile_x, "Periodic tile size along x")
        ->check(number_in(positive()));
    k->add_option("--tile-y", p->tile_y, "Periodic tile size along y")
        ->check(number_in(positive()));
    on_run(k, [=, &g] {
      require_mesh_extension(out->path);
      auto n = parse_numbers(*normal, "--normal", 3);
      p->normal = Vec3(n[0], n[1], n[2]);
      if (!p->periodic && (k->count("--tile-x") || k->count("--tile-y")))
        throw UsageError("--tile-x/--tile-y need --periodic");
      Microsurface s = import_mesh(*p);
      output_surface(g, s, out->path);
      summary(s, out->path, g);
    });
  }
}

}  // namespace

// Measured heightmaps (cmd_generate_heightmap.cpp).
void register_generate_heightmap(CLI::App& gen, const GlobalOptions& g);

void register_generate(CLI::App& app, const GlobalOptions& g) {
  auto* gen = app.add_subcommand("generate", "Generate a microsurface and save it (.exr, .ply, .obj, .off)");
  gen->require_subcommand(1);
  auto go = std::make_shared<GenerateOptions>();
  auto* gauss = gen->add_subcommand(
      "gaussian", "Periodic Gaussian random heightfield with Beckmann slope statistics");
  add_preset_option(*gauss, "Read options from a TOML preset (e.g. surfaces/beckmann-0.5.toml); command-line options win");
  gauss->add_option("-o,--output", go->output, "Output surface file (.exr, .ply, .obj, .off)")->required();
  add_gaussian_options(*gauss, *go);
  on_run(gauss, [go, gauss, &g] {
    go->alpha_given = gauss->count("--alpha") > 0;
    go->alpha_x_given = gauss->count("--alpha-x") > 0;
    go->alpha_y_given = gauss->count("--alpha-y") > 0;
    run_generate_gaussian(*go, g);
  });

  auto flat = std::make_shared<FlatParams>();
  auto flat_out = std::make_shared<std::string>();
  auto* fl = gen->add_subcommand("flat", "Periodic plane z = 0: the exact reference of every estimator");
  add_preset_option(*fl, "Read options from a TOML preset; command-line options win");
  fl->add_option("-o,--output", *flat_out, "Output surface file (.exr, .ply, .obj, .off)")->required();
  fl->add_option("--resolution", flat->resolution, "Grid cells per side")->capture_default_str()
        ->check(integer_in(1, 4096));
  fl->add_option("--size", flat->size, "Tile side length")->capture_default_str()
        ->check(number_in(closed(1e-6, 1e6)));
  on_run(fl, [=, &g] {
    require_surface_extension(*flat_out);
    Microsurface s = generate_flat(*flat);
    output_surface(g, s, *flat_out);
    if (!g.quiet) std::cout << "wrote " << *flat_out << ": flat plane\n";
  });
  register_structured_kinds(*gen, g);
  register_generate_heightmap(*gen, g);
}

void add_gaussian_options(CLI::App& cmd, GenerateOptions& go) {
  cmd.add_option("--resolution", go.gaussian.resolution, "Grid cells per side")->capture_default_str()
        ->check(integer_in(4, 32760));
  cmd.add_option("--size", go.gaussian.size, "Tile side length")->capture_default_str()
        ->check(number_in(closed(1e-6, 1e6)));
  cmd.add_option("--correlation-length", go.gaussian.correlation_length,
                 "Correlation length of the heights exp(-r^2/l^2), tile units (default: 16 cells, "
                 "at least 16 per tile and 4 cells; converged grid)")
        ->check(number_in(positive()));
  cmd.add_option("--alpha", go.alpha, "Isotropic Beckmann roughness alpha (> 0)")
        ->check(number_in(open_closed(0, 10)));
  cmd.add_option("--alpha-x", go.gaussian.alpha_x, "Roughness along x")
        ->check(number_in(open_closed(0, 10)));
  cmd.add_option("--alpha-y", go.gaussian.alpha_y, "Roughness along y")
        ->check(number_in(open_closed(0, 10)));
  cmd.add_option("--seed", go.gaussian.seed, "Random seed")->capture_default_str()
        ->check(seed_value());
}

}  // namespace microsim::cli
