// microsim info FILE and microsim convert FILE -o OUT.
#include <iostream>

#include "cli_common.hpp"
#include "commands.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/ndf_measure.hpp"
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

int run_info(const std::string& path, const std::string& json_out, const GlobalOptions& g) {
  if (!json_out.empty() && extension_of(json_out) != "json")
    throw UsageError("--json " + json_out + ": unsupported output format (use .json)");
  Microsurface s = load_surface(path);
  FacetSums f = facet_sums(s);
  Json j = run_header("info", g);
  j["file"] = path;
  j["surface"] = s.description;
  j["kind"] = s.kind() == Microsurface::Kind::Heightfield ? "heightfield" : "mesh";
  j["facets"] = s.num_facets();
  j["macrosurface"] = {{"area", s.macro().area}, {"periodic", s.macro().periodic},
                       {"size_x", s.macro().size_x}, {"size_y", s.macro().size_y}};
  j["checks"] = surface_checks_json(f, s);
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
    std::cout << "\n000 eq. 1b   sum A_f m_f / A = " << c["eq_1b_sum_area_normal_over_A"].dump()
              << "  |error| " << c["eq_1b_error"].get<double>() << "\n"
              << "000 eq. 1c   sum A_f (n.m_f) / A = " << c["eq_1c_sum_area_cos_over_A"].get<double>()
              << "  |error| " << c["eq_1c_error"].get<double>() << "\n"
              << "area ratio   sum A_f / A = " << c["total_area_over_A"].get<double>() << "\n";
  }
  if (!json_out.empty()) write_json(json_out, j);
  return 0;
}

}  // namespace

void register_info(CLI::App& app, const GlobalOptions& g) {
  auto* info = app.add_subcommand(
      "info", "Describe a surface: parameters, slope statistics, fitted alpha, 000 eq. 1b/1c");
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
