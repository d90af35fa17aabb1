// microsim generate heightmap: a measured heightmap (image or text grid) as a microsurface.
#include <iostream>
#include <sstream>

#include "cli_common.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/guard_band.hpp"
#include "microsim/surface/heightmap_import.hpp"
#include "microsim/surface/metrology.hpp"
#include "microsim/surface/surface_io.hpp"

namespace microsim::cli {

namespace {
std::vector<int> parse_crop(const std::string& text) {
  std::vector<int> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      std::size_t used = 0;
      long v = std::stol(item, &used);
      if (used != item.size() || v < 0 || v > 1000000000) throw std::invalid_argument(item);
      out.push_back(static_cast<int>(v));
    } catch (const std::exception&) {
      out.clear();
      break;
    }
  }
  if (out.size() != 4)
    throw UsageError("--crop '" + text + "': expected x0,y0,w,h (four non-negative pixel counts)");
  return out;
}

void require_finite_positive(double v, const char* option) {
  if (!(std::isfinite(v) && v > 0)) {
    std::ostringstream s;
    s << option << " " << v << ": must be a finite number > 0";
    throw UsageError(s.str());
  }
}
}  // namespace

void register_generate_heightmap(CLI::App& gen, const GlobalOptions& g) {
  auto p = std::make_shared<HeightmapImportParams>();
  auto out = std::make_shared<std::string>();
  auto detrend = std::make_shared<std::string>("mean");
  auto crop = std::make_shared<std::string>();
  auto window = std::make_shared<bool>(false);
  auto* k = gen.add_subcommand(
      "heightmap",
      "A measured heightmap (EXR/TIFF/PNG image or text/CSV grid) as a heightfield; --periodic "
      "for a tile the estimators measure, else a window for info");
  k->set_config("--config", "", "Read options from a TOML preset");
  k->add_option("-o,--output", *out, "Output heightfield (.exr)")->required();
  k->add_option("--input", p->input,
                "Heightmap: an image (one channel, or --channel) or a text grid (.txt/.csv/.asc/"
                ".xyz/.dat: a matrix, one row per line, or x,y,z columns)")
      ->required();
  k->add_option("--channel", p->channel, "Image channel holding the heights (default: the only one, else Z, else Y)");
  k->add_option("--pixel-size", p->pixel_size_x,
                "Grid spacing along x, in --length-unit (required unless the file has x,y columns)");
  k->add_option("--pixel-size-y", p->pixel_size_y, "Grid spacing along y (default: --pixel-size)");
  k->add_option("--height-scale", p->height_scale,
                "Height = file value * S (integer images give raw counts)")->capture_default_str();
  k->add_option("--length-unit", p->length_unit, "Unit of the pixel sizes and of the surface: m, mm, um, nm, pm");
  k->add_option("--height-unit", p->height_unit,
                "Unit of the scaled file values (converted to --length-unit; default: the same)");
  k->add_flag("--periodic", p->periodic,
              "The map is one period of a periodic surface: a tile every estimator measures");
  k->add_flag("--window", *window,
              "A non-periodic patch (the default): the estimators measure its interior, inside a guard band");
  k->add_option("--guard", p->guard_correlation_lengths,
                "Window guard band in correlation lengths l (Sal / sqrt(ln 5)) of the patch (default " +
                    fmt(kDefaultGuardCorrelationLengths, 3) + ", from the guard-band bias table)");
  k->add_option("--guard-width", p->guard_width, "Window guard band in --length-unit (instead of --guard)");
  k->add_option("--detrend", *detrend,
                "Least-squares form removed: none, mean, plane (tilt) or poly2 (quadratic form)")
      ->capture_default_str();
  k->add_option("--crop", *crop, "x0,y0,w,h: keep this pixel rectangle (before everything else)");
  k->add_option("--nodata", p->nodata, "File value that marks a missing pixel (NaN always does)");
  k->add_option("--max-missing", p->max_missing_fraction,
                "Largest fraction of missing pixels filled (harmonic inpainting); more is refused")
      ->capture_default_str();
  k->callback([=, &g] {
    if (extension_of(*out) != "exr") throw UsageError("-o " + *out + ": a heightmap is saved as .exr");
    if (p->periodic && *window) throw UsageError("--periodic and --window exclude each other");
    if (k->count("--pixel-size")) require_finite_positive(p->pixel_size_x, "--pixel-size");
    if (k->count("--pixel-size-y")) require_finite_positive(p->pixel_size_y, "--pixel-size-y");
    if (k->count("--max-missing") && !(p->max_missing_fraction >= 0 && p->max_missing_fraction < 1))
      throw UsageError("--max-missing: must be in [0, 1)");
    if ((k->count("--guard") || k->count("--guard-width")) && p->periodic)
      throw UsageError("--guard/--guard-width: a periodic tile has no guard band (a window option)");
    if (k->count("--guard") && k->count("--guard-width"))
      throw UsageError("--guard and --guard-width exclude each other");
    if (k->count("--guard") && !(std::isfinite(p->guard_correlation_lengths) && p->guard_correlation_lengths >= 0))
      throw UsageError("--guard: must be a finite number >= 0 (correlation lengths)");
    if (k->count("--guard-width") && !(std::isfinite(p->guard_width) && p->guard_width >= 0))
      throw UsageError("--guard-width: must be a finite number >= 0");
    p->has_nodata = k->count("--nodata") > 0;
    p->detrend = parse_detrend(*detrend);
    if (!crop->empty()) {
      auto c = parse_crop(*crop);
      p->crop = true;
      p->crop_x0 = c[0];
      p->crop_y0 = c[1];
      p->crop_w = c[2];
      p->crop_h = c[3];
    }
    Microsurface s = import_heightmap(*p);
    output_surface(g, s, *out);
    const Json& d = s.description;
    if (p->periodic) {
      // The seam's cliff raises the RMS slope of non-periodic data (a 128-cell crop of a
      // Gaussian tile: +5%); warn above 2%.
      const Json& c = d["seam_check"];
      auto ratio = [&](const char* tile, const char* inner) {
        const double b = c[inner].get<double>();
        return b > 0 ? c[tile].get<double>() / b : 1.0;
      };
      const double rx = ratio("slope_rms_x_tile", "slope_rms_x_without_wrap"),
                   ry = ratio("slope_rms_y_tile", "slope_rms_y_without_wrap");
      if (std::max(rx, ry) > 1.02)
        std::cerr << "microsim: warning: the wrap-around raises the RMS slope by " << fmt(100 * (rx - 1), 1)
                  << "% (x), " << fmt(100 * (ry - 1), 1) << "% (y): " << p->input
                  << " does not look periodic (see README, Measured surfaces)\n";
    }
    if (g.quiet) return;
    Metrology m = measure_metrology(grid_view(s));
    std::cout << "wrote " << *out << ": heightmap " << s.nx() << " x " << s.ny() << " from "
              << d["format"].get<std::string>() << " " << p->input << ", "
              << (p->periodic ? "periodic tile " : "non-periodic window ") << s.macro().size_x << " x "
              << s.macro().size_y << (p->length_unit.empty() ? "" : " " + p->length_unit) << "; detrend "
              << d["detrend"].get<std::string>() << ", " << d["missing_filled"].get<std::size_t>()
              << " missing heights filled\n"
              << "Sq " << m.sq << ", Sdq " << fmt(m.slopes.sdq) << ", Beckmann alpha ("
              << fmt(m.slopes.beckmann_alpha_x) << ", " << fmt(m.slopes.beckmann_alpha_y) << "), Sal "
              << m.acf.sal << " (" << fmt(m.cells_per_correlation_length, 3)
              << " cells); microsim info " << *out << " for the full report\n";
    if (d.contains("guard_band")) {
      const Json& gb = d["guard_band"];
      std::cout << "guard band " << gb["cells_x"] << " x " << gb["cells_y"] << " cells ("
                << fmt(gb.value("width_correlation_lengths", 0.0), 3) << " correlation lengths); interior "
                << gb["interior"]["cells_x"] << " x " << gb["interior"]["cells_y"] << " cells measured\n";
    } else if (d.contains("guard_band_note")) {
      std::cerr << "microsim: warning: " << d["guard_band_note"].get<std::string>() << "\n";
    }
  });
}

}  // namespace microsim::cli
