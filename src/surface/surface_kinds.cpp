// The builders of the surface kinds (surface_spec.hpp): options given as text -> generator
// parameters, with the combinations checked in the order `microsim generate` has always checked
// them, and what is said after saving a surface.
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iomanip>
#include <sstream>

#include "microsim/common.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/heightmap_import.hpp"
#include "microsim/surface/mesh_check.hpp"
#include "microsim/surface/metrology.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/surface/surface_spec.hpp"

namespace microsim {

namespace {

using Build = std::function<Microsurface()>;

// The given options of a request, typed as the table says (values already checked).
struct Given {
  const SurfaceRequest& r;
  bool has(const char* n) const { return r.options.count(n) > 0; }
  const std::string& text(const char* n) const { return r.options.at(n); }
  // Numbers are read as the command line has always read them (long double, then rounded), so
  // a value gives the same double everywhere.
  void set(const char* n, double& x) const {
    if (has(n)) x = static_cast<double>(std::strtold(text(n).c_str(), nullptr));
  }
  void set(const char* n, int& x) const {
    if (has(n)) x = static_cast<int>(parse_integer_in(text(n), -2147483647LL, 2147483647LL, surface_option_placeholder(n)));
  }
  void set(const char* n, std::uint64_t& x) const {
    if (has(n)) x = parse_seed(text(n), surface_option_placeholder(n));
  }
  void set(const char* n, bool& x) const {
    if (has(n)) x = text(n) == "true";
  }
  void set(const char* n, std::string& x) const {
    if (has(n)) x = text(n);
  }
};

void require_mesh_extension(const std::string& path) {
  require_surface_extension(path);
  if (extension_of(path) == "exr")
    throw ParameterError("{output} " + literal_text(path) + ": this surface is a mesh; use .ply, .obj or .off");
}

// The alpha shorthand or alpha-x/alpha-y (one axis given: isotropic).
void resolve_alpha(const Given& v, double& ax, double& ay) {
  v.set("alpha-x", ax);
  v.set("alpha-y", ay);
  const bool x_given = v.has("alpha-x"), y_given = v.has("alpha-y");
  if (v.has("alpha")) {
    if (x_given || y_given) throw ParameterError("{alpha} cannot be combined with {alpha_x}/{alpha_y}");
    double alpha = 0;
    v.set("alpha", alpha);
    ax = ay = alpha;
  } else if (x_given != y_given) {
    if (x_given) ay = ax; else ax = ay;
  }
}

// `option`: the parameter as a ParameterError names it ("{matrix}").
std::vector<double> parse_numbers(const std::string& text, const std::string& option, std::size_t count) {
  const ParameterError bad(option + " '" + literal_text(text) + "': expected " + std::to_string(count) + " comma-separated numbers");
  std::vector<double> out;
  for (const std::string& item : split_items(text, ',', option)) {
    try {
      std::size_t used = 0;
      double x = std::stod(item, &used);
      if (used != item.size() || !std::isfinite(x)) throw std::invalid_argument(item);
      out.push_back(x);
    } catch (const std::exception&) {
      throw bad;
    }
  }
  if (out.size() != count) throw bad;
  return out;
}

std::vector<int> parse_crop(const std::string& text) {
  std::vector<int> out;
  for (const std::string& item : split_items(text, ',', "{crop}")) {
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
    throw ParameterError("{crop} '" + literal_text(text) + "': expected x0,y0,w,h (four non-negative pixel counts)");
  return out;
}

// `option`: the parameter as a ParameterError names it ("{pixel_size}").
void require_finite_positive(double v, const char* option) {
  if (!(std::isfinite(v) && v > 0)) {
    std::ostringstream s;
    s << option << " " << v << ": must be a finite number > 0";
    throw ParameterError(s.str());
  }
}

Build gaussian(const Given& v, const std::string& out) {
  GaussianParams p;
  v.set("resolution", p.resolution);
  v.set("size", p.size);
  v.set("correlation-length", p.correlation_length);
  v.set("seed", p.seed);
  resolve_alpha(v, p.alpha_x, p.alpha_y);
  validate(p);
  if (!out.empty()) require_surface_extension(out);
  return [p] { return generate_gaussian(p); };
}

Build flat(const Given& v, const std::string& out) {
  FlatParams p;
  v.set("resolution", p.resolution);
  v.set("size", p.size);
  if (!out.empty()) require_surface_extension(out);
  return [p] { return generate_flat(p); };
}

Build boxes(const Given& v, const std::string& out, bool tiled) {
  BoxParams p;
  if (tiled) p.tiles = 4;
  v.set("tiles", p.tiles);
  v.set("width", p.width);
  v.set("depth", p.depth);
  v.set("height", p.height);
  if (!out.empty()) require_mesh_extension(out);
  if (tiled) return [p] { return generate_tiled_boxes(p); };
  return [p] { return generate_box(p); };
}

Build square_wave(const Given& v, const std::string& out) {
  SquareWaveParams p;
  v.set("period", p.period);
  v.set("duty", p.duty);
  v.set("height", p.height);
  v.set("2d", p.two_d);
  if (!out.empty()) require_mesh_extension(out);
  return [p] { return generate_square_wave(p); };
}

Build vgroove(const Given& v, const std::string& out) {
  VGrooveParams p;
  v.set("facet-angle", p.facet_angle_deg);
  v.set("period", p.period);
  v.set("2d", p.two_d);
  if (!out.empty()) {
    require_surface_extension(out);
    if (p.two_d) require_mesh_extension(out);
  }
  return [p] { return generate_vgroove(p); };
}

Build vcavity(const Given& v, const std::string& out) {
  VCavityParams p;
  v.set("ndf", p.ndf);
  v.set("grooves", p.grooves);
  v.set("seed", p.seed);
  if (!out.empty()) require_mesh_extension(out);
  resolve_alpha(v, p.alpha_x, p.alpha_y);
  return [p] { return generate_vcavity(p); };
}

Build parallelepiped(const Given& v, const std::string& out) {
  ParallelepipedParams p;
  v.set("width", p.width);
  v.set("depth", p.depth);
  v.set("height", p.height);
  v.set("tiles", p.tiles);
  if (!out.empty()) require_mesh_extension(out);
  if (v.has("matrix") && !v.text("matrix").empty()) {
    if (v.has("shear-x") || v.has("shear-y"))
      throw ParameterError("{matrix} cannot be combined with {shear_x}/{shear_y}");
    auto m = parse_numbers(v.text("matrix"), "{matrix}", 9);
    std::copy(m.begin(), m.end(), p.matrix);
  } else {
    double shear_x = 0.5, shear_y = 0.0;
    v.set("shear-x", shear_x);
    v.set("shear-y", shear_y);
    const double L[9] = {1, 0, shear_x, 0, 1, shear_y, 0, 0, 1};
    std::copy(L, L + 9, p.matrix);
  }
  return [p] { return generate_parallelepiped(p); };
}

Build ellipsoid(const Given& v, const std::string& out) {
  EllipsoidParams p;
  v.set("rings", p.rings);
  v.set("segments", p.segments);
  if (!out.empty()) require_mesh_extension(out);
  resolve_alpha(v, p.alpha_x, p.alpha_y);
  return [p] { return generate_ellipsoid(p); };
}

Build gaussian_ggx(const Given& v, const std::string& out) {
  GaussianGgxParams p;
  v.set("resolution", p.resolution);
  v.set("size", p.size);
  v.set("correlation-length", p.correlation_length);
  v.set("roughness-correlation-length", p.roughness_correlation_length);
  v.set("tail-fraction", p.tail_fraction);
  v.set("seed", p.seed);
  if (!out.empty()) require_surface_extension(out);
  resolve_alpha(v, p.alpha_x, p.alpha_y);
  return [p] { return generate_gaussian_ggx(p); };
}

Build mesh(const Given& v, const std::string& out) {
  MeshImportParams p;
  std::string normal = "0,0,1";
  v.set("input", p.input);
  v.set("normal", normal);
  v.set("area", p.area);
  v.set("periodic", p.periodic);
  v.set("tile-x", p.tile_x);
  v.set("tile-y", p.tile_y);
  if (!v.has("input")) throw ParameterError("{input} is required");
  if (!out.empty()) require_mesh_extension(out);
  auto n = parse_numbers(normal, "{normal}", 3);
  p.normal = Vec3(n[0], n[1], n[2]);
  if (!p.periodic && (v.has("tile-x") || v.has("tile-y"))) throw ParameterError("{tile_x}/{tile_y} need {periodic}");
  return [p] { return import_mesh(p); };
}

Build heightmap(const Given& v, const std::string& out) {
  HeightmapImportParams p;
  bool window = false;
  std::string detrend = "mean";
  v.set("input", p.input);
  v.set("channel", p.channel);
  v.set("pixel-size", p.pixel_size_x);
  v.set("pixel-size-y", p.pixel_size_y);
  v.set("height-scale", p.height_scale);
  v.set("length-unit", p.length_unit);
  v.set("height-unit", p.height_unit);
  v.set("periodic", p.periodic);
  v.set("window", window);
  v.set("guard", p.guard_correlation_lengths);
  v.set("guard-width", p.guard_width);
  v.set("detrend", detrend);
  v.set("nodata", p.nodata);
  v.set("max-missing", p.max_missing_fraction);
  if (!v.has("input")) throw ParameterError("{input} is required");
  if (!out.empty() && extension_of(out) != "exr") throw ParameterError("{output} " + literal_text(out) + ": a heightmap is saved as .exr");
  if (p.periodic && window) throw ParameterError("{periodic} and {window} exclude each other");
  if (v.has("pixel-size")) require_finite_positive(p.pixel_size_x, "{pixel_size}");
  if (v.has("pixel-size-y")) require_finite_positive(p.pixel_size_y, "{pixel_size_y}");
  if (v.has("max-missing") && !(p.max_missing_fraction >= 0 && p.max_missing_fraction < 1))
    throw ParameterError("{max_missing}: must be in [0, 1)");
  if ((v.has("guard") || v.has("guard-width")) && p.periodic)
    throw ParameterError("{guard}/{guard_width}: a periodic tile has no guard band (a window option)");
  if (v.has("guard") && v.has("guard-width")) throw ParameterError("{guard} and {guard_width} exclude each other");
  if (v.has("guard") && !(std::isfinite(p.guard_correlation_lengths) && p.guard_correlation_lengths >= 0))
    throw ParameterError("{guard}: must be a finite number >= 0 (correlation lengths)");
  if (v.has("guard-width") && !(std::isfinite(p.guard_width) && p.guard_width >= 0))
    throw ParameterError("{guard_width}: must be a finite number >= 0");
  p.has_nodata = v.has("nodata");
  p.detrend = parse_detrend(detrend);
  if (v.has("crop") && !v.text("crop").empty()) {
    auto c = parse_crop(v.text("crop"));
    p.crop = true;
    p.crop_x0 = c[0];
    p.crop_y0 = c[1];
    p.crop_w = c[2];
    p.crop_h = c[3];
  }
  return [p] { return import_heightmap(p); };
}

// Every given option checked against the table (in the table's order, as the command line
// checks them), then the kind's own combinations.
Build prepare(const SurfaceRequest& r, const std::string& out) {
  const SurfaceKind& kind = surface_kind(r.kind);
  SurfaceRequest checked{r.kind, {}};
  for (const auto& [name, value] : r.options)
    if (!kind.option(name)) set_surface_option(checked, name, value);  // throws: unknown option
  for (const auto& o : kind.options) {
    auto it = r.options.find(o.name);
    if (it != r.options.end()) set_surface_option(checked, o.name, it->second);
  }
  const Given v{r};
  const std::string& k = r.kind;
  if (k == "gaussian") return gaussian(v, out);
  if (k == "flat") return flat(v, out);
  if (k == "box" || k == "tiled-boxes") return boxes(v, out, k == "tiled-boxes");
  if (k == "square-wave") return square_wave(v, out);
  if (k == "vgroove") return vgroove(v, out);
  if (k == "vcavity") return vcavity(v, out);
  if (k == "parallelepiped") return parallelepiped(v, out);
  if (k == "ellipsoid") return ellipsoid(v, out);
  if (k == "gaussian-ggx") return gaussian_ggx(v, out);
  if (k == "mesh") return mesh(v, out);
  return heightmap(v, out);
}

std::string fixed(double x, int precision = 4) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(precision) << x;
  return os.str();
}

std::string structured_summary(const Microsurface& s, const std::string& path) {
  FacetSums f = facet_sums(s);
  const Macrosurface& m = s.macro();
  const Vec3 e = f.sum_area_normal / m.area - m.normal;
  double below = 0;
  for (std::size_t k = 0; k < s.num_facets(); ++k) {
    Triangle t = s.facet(k);
    if (t.cross().z() < 0) below += t.area();
  }
  std::ostringstream os;
  os << "wrote " << path << ": " << s.description.value("kind", std::string("surface")) << ", " << s.num_facets()
     << " facets, " << (m.periodic ? "periodic tile " : "finite object, window ") << m.size_x << " x " << m.size_y
     << ", A = " << m.area << "; [GeomBSDF24, eq. 1b] |error| " << e.norm() << "; area facing down (n.m < 0): "
     << below / f.total_area * 100 << "%\n";
  return os.str();
}

void heightmap_report(const SurfaceRequest& r, const Microsurface& s, const std::string& path, bool with_summary,
                      SurfaceReport& report) {
  const Json& d = s.description;
  const std::string input = r.options.at("input");
  const bool periodic = d.value("boundary", std::string()) == "periodic";
  if (periodic) {
    // The seam's cliff raises the RMS slope of non-periodic data (a 128-cell crop of a Gaussian
    // tile: +5%); warn above 2%.
    const Json& c = d["seam_check"];
    auto ratio = [&](const char* tile, const char* inner) {
      const double b = c[inner].get<double>();
      return b > 0 ? c[tile].get<double>() / b : 1.0;
    };
    const double rx = ratio("slope_rms_x_tile", "slope_rms_x_without_wrap"),
                 ry = ratio("slope_rms_y_tile", "slope_rms_y_without_wrap");
    if (std::max(rx, ry) > 1.02)
      report.warnings.push_back("the wrap-around raises the RMS slope by " + fixed(100 * (rx - 1), 1) + "% (x), " +
                                fixed(100 * (ry - 1), 1) + "% (y): " + input +
                                " does not look periodic (docs/guide/heightmaps.md, Windows and the guard band)");
  }
  if (!with_summary) return;
  const std::string unit = r.options.count("length-unit") ? r.options.at("length-unit") : "";
  Metrology m = measure_metrology(grid_view(s));
  std::ostringstream os;
  os << "wrote " << path << ": heightmap " << s.nx() << " x " << s.ny() << " from " << d["format"].get<std::string>()
     << " " << input << ", " << (periodic ? "periodic tile " : "non-periodic window ") << s.macro().size_x << " x "
     << s.macro().size_y << (unit.empty() ? "" : " " + unit) << "; detrend " << d["detrend"].get<std::string>()
     << ", " << d["missing_filled"].get<std::size_t>() << " missing heights filled\n"
     << "Sq " << m.sq << ", Sdq " << fixed(m.slopes.sdq) << ", Beckmann alpha (" << fixed(m.slopes.beckmann_alpha_x)
     << ", " << fixed(m.slopes.beckmann_alpha_y) << "), Sal " << m.acf.sal << " ("
     << fixed(m.cells_per_correlation_length, 3) << " cells); microsim info " << path << " for the full report\n";
  if (d.contains("guard_band")) {
    const Json& gb = d["guard_band"];
    os << "guard band " << gb["cells_x"] << " x " << gb["cells_y"] << " cells ("
       << fixed(gb.value("width_correlation_lengths", 0.0), 3) << " correlation lengths); interior "
       << gb["interior"]["cells_x"] << " x " << gb["interior"]["cells_y"] << " cells measured\n";
  } else if (d.contains("guard_band_note")) {
    report.notes.push_back(d["guard_band_note"].get<std::string>());
  }
  report.summary = os.str();
}

}  // namespace

void require_surface_extension(const std::string& path) {
  const std::string ext = extension_of(path);
  if (ext != "exr" && ext != "ply" && ext != "obj" && ext != "off")
    throw ParameterError("{output} " + literal_text(path) + ": unknown surface format (use .exr, .ply, .obj or .off)");
}

// "generate KIND {a} 1 {b} 2" of a request (a ParameterError's message), to name its options.
std::string request_text(const SurfaceRequest& r) {
  std::string t = "generate " + literal_text(r.kind);
  for (const auto& [key, value] : r.options)
    t += " " + surface_option_placeholder(key) + (value == "true" ? "" : " " + literal_text(value));
  return t;
}

// A surface no reader accepts (sizes whose area underflows to 0 or overflows, facets too thin
// to have an area) is refused here rather than written.
Microsurface generate_surface(const SurfaceRequest& r, const std::string& output_path) {
  Microsurface s = prepare(r, output_path)();
  try {
    require_readable_surface(s, "surface");
  } catch (const UsageError& e) {
    throw ParameterError(request_text(r) + ": these sizes give a surface that no reader accepts (" +
                         message_template(e) + ")");
  }
  return s;
}

void check_surface_request(const SurfaceRequest& r, const std::string& output_path) { prepare(r, output_path); }

SurfaceReport surface_report(const SurfaceRequest& r, const Microsurface& s, const std::string& path,
                             bool with_summary) {
  SurfaceReport report;
  if (r.kind == "heightmap") {
    heightmap_report(r, s, path, with_summary, report);
  } else if (!with_summary) {
  } else if (r.kind == "flat") {
    report.summary = "wrote " + path + ": flat plane\n";
  } else if (r.kind == "gaussian") {
    FacetSums f = facet_sums(s);
    std::ostringstream os;
    os << "wrote " << path << ": gaussian " << s.nx() << "^2, alpha (" << s.nominal->alpha_x << ", "
       << s.nominal->alpha_y << "), fitted alpha (" << fixed(std::sqrt(2 * f.slope_var_x)) << ", "
       << fixed(std::sqrt(2 * f.slope_var_y)) << ")\n";
    report.summary = os.str();
  } else {
    report.summary = structured_summary(s, path);
  }
  return report;
}

}  // namespace microsim
