// microsim info FILE and microsim convert FILE -o OUT.
#include <iomanip>
#include <iostream>
#include <sstream>

#include "cli_common.hpp"
#include "commands.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/ndf_measure.hpp"
#include "microsim/surface/discretization.hpp"
#include "microsim/surface/heightmap_import.hpp"
#include "microsim/surface/metrology.hpp"
#include "microsim/surface/surface_io.hpp"

namespace microsim::cli {

namespace {
int run_convert(const std::string& input, const std::string& output, const GlobalOptions& g) {
  require_surface_extension(output);
  Microsurface s = load_surface(input);
  save_surface(s, output);
  if (!g.quiet) std::cout << "wrote " << output << " (" << s.num_facets() << " facets)\n";
  return 0;
}

// The areal texture parameters (ISO 25178-2 style) and slope-model fits of a heightfield.
// 4 significant digits: heights and lengths of any scale (nm to mm) stay readable.
std::string sig(double x) {
  std::ostringstream o;
  o << std::setprecision(4) << x;
  return o.str();
}

// The grid's resolution of the continuous surface against the converged levels of the study.
Json discretization_json(const Discretization& d) {
  Json j = {{"cells_per_correlation_length", d.cells_per_correlation_length},
            {"correlation_lengths_per_tile", d.correlation_lengths_per_tile},
            {"coarser_than_converged", Json::array()}};
  for (const ConvergedLevel& l : converged_levels())
    if (d.cells_per_correlation_length < l.cells_per_correlation_length * (1 - 1e-9) ||
        d.correlation_lengths_per_tile < l.correlation_lengths_per_tile * (1 - 1e-9))
      j["coarser_than_converged"].push_back(l.quantity);
  return j;
}

void print_discretization(const Json& j) {
  std::cout << "correlation  " << sig(j["cells_per_correlation_length"].get<double>())
            << " cells per correlation length l, " << sig(j["correlation_lengths_per_tile"].get<double>())
            << " correlation lengths per tile";
  const Json& c = j["coarser_than_converged"];
  if (c.empty()) {
    std::cout << " (converged for every quantity of the study)\n";
    return;
  }
  std::cout << "\n             coarser than the converged level (docs/theory/discretization.md) for:";
  for (const Json& q : c) {
    const auto l = converged_level(q.get<std::string>());
    std::cout << " " << q.get<std::string>() << " (" << sig(l->cells_per_correlation_length) << " cells per l, "
              << sig(l->correlation_lengths_per_tile) << " l per tile)";
  }
  std::cout << "\n";
}

void print_metrology(const Metrology& m, const Microsurface& s) {
  const std::string unit = s.description.value("length_unit", std::string());
  const std::string u = unit.empty() || unit == "unspecified" ? "" : " " + unit;
  std::cout << "metrology    Sq " << sig(m.sq) << u << ", Sa " << sig(m.sa) << u << ", Sz " << sig(m.sz)
            << u << ", Ssk " << fmt(m.skewness, 3) << ", Sku " << fmt(m.kurtosis, 3) << "\n";
  if (!m.textured) {
    std::cout << "             constant heights: no texture\n";
    return;
  }
  const SlopeStats& sl = m.slopes;
  std::cout << "slopes       Sdq (RMS slope) " << fmt(sl.sdq) << ", RMS x " << fmt(sl.rms_x) << ", y "
            << fmt(sl.rms_y) << "\n"
            << "alpha        Beckmann (sqrt 2 RMS slope) x " << fmt(sl.beckmann_alpha_x) << ", y "
            << fmt(sl.beckmann_alpha_y) << "; GGX (max. likelihood) "
            << (sl.ggx_alpha_x > 0 ? "x " + fmt(sl.ggx_alpha_x) + ", y " + fmt(sl.ggx_alpha_y) + ", isotropic " +
                                         fmt(sl.ggx_alpha)
                                   : std::string("n/a (slopes along one axis only)"))
            << "\n"
            << "ACF          Sal " << sig(m.acf.sal) << u << " (decay to " << m.acf.threshold << "), Str "
            << fmt(m.acf.str, 3) << ", slowest decay at " << fmt(m.acf.slowest_direction_deg, 3)
            << " deg" << (m.acf.decayed_in_every_direction ? "" : " (not reached within half the grid)")
            << "\n"
            << "grid         " << fmt(m.cells_per_correlation_length, 3) << " cells per Sal, "
            << fmt(m.cells_per_gaussian_length, 3)
            << " per Gaussian correlation length l = Sal / sqrt(ln 5)"
            << (!m.acf.decayed_in_every_direction ? ""
                : m.cells_per_gaussian_length < 3.5
                    ? "  WARNING: well under 4 cells per l: D, G1 and the "
                      "multiple scattering of the triangles are far from the continuous surface's"
                    : m.cells_per_gaussian_length < 13  // 16 cells per l, less one tile's ~10% spread
                          ? " (mirror orders 1-2 converge by 8, order 3 by 16 cells per l: docs/theory/discretization.md)"
                          : "")
            << "\n"
            << "fit chi2/dof heights vs Gaussian " << fmt(m.height_fit.chi2_per_dof(), 3)
            << "; slopes vs Beckmann "
            << (sl.beckmann_fit.model.empty() ? "n/a" : fmt(sl.beckmann_fit.chi2_per_dof(), 3)) << ", vs GGX "
            << (sl.ggx_fit.model.empty() ? "n/a" : fmt(sl.ggx_fit.chi2_per_dof(), 3)) << " (" << m.height_fit.observed.size()
            << " equal-probability bins; neighbouring pixels are correlated, so compare models "
               "rather than read absolute values)\n";
}

int print_window_info(const std::string& path, const std::string& json_out, const Microsurface& s,
                      const GlobalOptions& g) {
  Metrology m = measure_metrology(grid_view(s));
  Json j = run_header("info", g);
  j["file"] = path;
  j["surface"] = s.description;
  j["kind"] = "heightfield";
  j["macrosurface"] = {{"area", s.macro().area}, {"periodic", false},
                       {"size_x", s.macro().size_x}, {"size_y", s.macro().size_y}};
  j["metrology"] = metrology_to_json(m);
  if (!g.quiet) {
    std::cout << "surface      " << path << " (heightfield, non-periodic measured window "
              << s.nx() << " x " << s.ny() << ")\n"
              << "description  " << s.description.dump() << "\n"
              << "window       " << s.macro().size_x << " x " << s.macro().size_y
              << "; the estimators (measure, validate) need a periodic tile\n";
    print_metrology(m, s);
  }
  if (!json_out.empty()) write_json(json_out, j);
  return 0;
}

int run_info(const std::string& path, const std::string& json_out, const GlobalOptions& g) {
  if (!json_out.empty() && extension_of(json_out) != "json")
    throw UsageError("--json " + json_out + ": unsupported output format (use .json)");
  Microsurface s = load_surface_or_window(path, /*allow_window=*/true);
  if (is_window(s)) return print_window_info(path, json_out, s, g);
  FacetSums f = facet_sums(s);
  Json j = run_header("info", g);
  j["file"] = path;
  j["surface"] = s.description;
  j["kind"] = s.kind() == Microsurface::Kind::Heightfield ? "heightfield" : "mesh";
  j["facets"] = s.num_facets();
  j["macrosurface"] = {{"area", s.macro().area}, {"periodic", s.macro().periodic},
                       {"size_x", s.macro().size_x}, {"size_y", s.macro().size_y}};
  j["checks"] = surface_checks_json(f, s);
  const auto disc = discretization_of(s.description);
  if (disc) j["discretization"] = discretization_json(*disc);
  Metrology m;
  if (s.kind() == Microsurface::Kind::Heightfield) {
    m = measure_metrology(grid_view(s));
    j["metrology"] = metrology_to_json(m);
  }
  if (!g.quiet) {
    const auto& c = j["checks"];
    std::cout << "surface      " << path << " (" << j["kind"].get<std::string>() << ", "
              << s.num_facets() << " facets)\n"
              << "description  " << s.description.dump() << "\n"
              << "macrosurface area " << s.macro().area << ", "
              << (s.macro().periodic ? "periodic tile " : "finite window ") << s.macro().size_x
              << " x " << s.macro().size_y << "\n"
              << "slope var    x " << c["slope_var_x"].get<double>() << ", y "
              << c["slope_var_y"].get<double>() << ", cov " << c["slope_cov_xy"].get<double>()
              << "\n"
              << "fitted alpha x " << fmt(c["fitted_alpha_x"].get<double>()) << ", y "
              << fmt(c["fitted_alpha_y"].get<double>());
    if (s.nominal)
      std::cout << "   (nominal " << models::to_string(s.nominal->kind) << " " << s.nominal->alpha_x
                << ", " << s.nominal->alpha_y << ")";
    std::cout << "\n[GeomBSDF24, eq. 1b]   sum A_f m_f / A = " << c["eq_1b_sum_area_normal_over_A"].dump()
              << "  |error| " << c["eq_1b_error"].get<double>() << "\n"
              << "[GeomBSDF24, eq. 1c]   sum A_f (n.m_f) / A = " << c["eq_1c_sum_area_cos_over_A"].get<double>()
              << "  |error| " << c["eq_1c_error"].get<double>() << "\n"
              << "area ratio   sum A_f / A = " << c["total_area_over_A"].get<double>() << "\n";
    if (disc) print_discretization(j["discretization"]);
    if (s.kind() == Microsurface::Kind::Heightfield) print_metrology(m, s);
  }
  if (!json_out.empty()) write_json(json_out, j);
  return 0;
}

}  // namespace

void register_info(CLI::App& app, const GlobalOptions& g) {
  auto* info = app.add_subcommand(
      "info", "Describe a surface: parameters, slope statistics, fitted alpha, [GeomBSDF24, eq. 1b/1c]");
  auto file = std::make_shared<std::string>(), json = std::make_shared<std::string>();
  info->add_option("surface", *file, "Surface file")->required();
  info->add_option("--json", *json, "Also write the description as JSON");
  info->callback([=, &g] { run_info(*file, *json, g); });
}

void register_convert(CLI::App& app, const GlobalOptions& g) {
  auto* conv = app.add_subcommand(
      "convert", "Save a surface in another format (.exr heightfield, .ply/.obj/.off mesh)");
  auto in = std::make_shared<std::string>(), out = std::make_shared<std::string>();
  conv->add_option("surface", *in, "Surface file")->required();
  conv->add_option("-o,--output", *out, "Output surface file")->required();
  conv->callback([=, &g] { run_convert(*in, *out, g); });
}

}  // namespace microsim::cli
