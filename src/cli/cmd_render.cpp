// microsim render TABLE.bsdf -o sphere.png|.exr|.json: sphere previews of a measured RGL table
// beside the single-scattering and Smith random-walk models (render/table_previews.hpp).
#include <iomanip>
#include <iostream>

#include "cli_common.hpp"
#include "option_checks.hpp"
#include "microsim/io/output.hpp"
#include "microsim/render/table_previews.hpp"

namespace microsim::cli {

namespace {

int run_render(const render::TablePreviewOptions& o, const std::vector<std::string>& outputs, const GlobalOptions& g) {
  for (const auto& out : outputs) require_extension(out, {"png", "exr", "json"});
  Progress progress("render (6 images)", g.quiet);
  const render::TablePreviews p = render::render_table_previews(o, [&](double f) { progress.update(f); });
  progress.finish();
  for (const auto& out : outputs) {
    const std::string ext = extension_of(out);
    if (ext == "exr") {
      render::write_previews_exr(out, p);
    } else if (ext == "png") {
      render::write_previews_png(out, p, o.white, o.range);
    } else {
      Json j = run_header("render", g);
      j["parameters"] = p.parameters;
      j["table_description"] = p.table_description;
      j["layout"] = p.layout;
      j["seconds"] = p.seconds;
      j["summary"] = p.summary;
      write_record(out, j);
    }
  }
  if (g.quiet) return 0;
  std::cout << "sphere previews of " << o.table << " (" << p.distribution << " alpha " << fmt(p.alpha_x, 3)
            << (p.alpha_x != p.alpha_y ? "/" + fmt(p.alpha_y, 3) : "") << ", " << p.material << "), "
            << o.preview.size << "^2 pixels, " << o.preview.samples << " samples, " << fmt(p.seconds, 1) << " s\n";
  std::cout << std::setw(12) << "light" << std::setw(11) << "measured" << std::setw(11) << "single" << std::setw(11)
            << "walk" << std::setw(16) << "rms difference" << "   (means over the sphere)\n";
  for (const char* light : {"directional", "environment"}) {
    const Json& s = p.summary[light];
    std::cout << std::setw(12) << light << std::setw(11) << fmt(s["measured"]["mean"]) << std::setw(11)
              << fmt(s["single"]["mean"]) << std::setw(11) << fmt(s["walk"]["mean"]) << std::setw(16)
              << fmt(s["difference"]["rms"]) << "\n";
  }
  for (const auto& out : outputs) std::cout << "wrote " << out << "\n";
  return 0;
}

}  // namespace

void register_render(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand(
      "render", "Sphere previews of a measured .bsdf table beside the single-scattering and Smith random-walk "
                "models: directional light and uniform white environment, with a difference image");
  auto o = std::make_shared<render::TablePreviewOptions>();
  auto outputs = std::make_shared<std::vector<std::string>>();
  cmd->add_option("table", o->table, "RGL table (.bsdf) written by measure bsdf")->required();
  cmd->add_option("-o,--output", *outputs,
                  "Outputs (repeatable): .png (panel: rows directional, environment; columns measured, single "
                  "scattering, Smith walk, difference), .exr (linear radiance of every image and its standard "
                  "error), .json (parameters and means)")
      ->required();
  cmd->add_option("--size", o->preview.size, "Pixels per side of each sphere image")->capture_default_str()->check(integer_in(8, 4096));
  cmd->add_option("--samples", o->preview.samples,
                  "Samples per pixel: environment directions, or walk estimates under the directional light")
      ->capture_default_str()
      ->check(integer_in(1, 1000000));
  cmd->add_option("--seed", o->preview.seed, "Random seed")->capture_default_str()->check(seed_value());
  cmd->add_option("--light-theta", o->light_theta, "Directional light: angle from the view axis, degrees [0, 90)")
      ->capture_default_str()
      ->check(number_in(Range{0, 90, false, true}));  // [0, 90): the check of table_previews
  cmd->add_option("--light-phi", o->light_phi, "Directional light: azimuth in the image plane from +x (right), degrees")
      ->capture_default_str()
      ->check(number_in(closed(-360, 360)));
  cmd->add_option("--distribution", o->distribution, "Models' NDF: beckmann or ggx (default: the table's surface)");
  cmd->add_option("--alpha", o->alpha, "Models' roughness (default: the table's surface)")->check(number_in(open_closed(0, 10)));
  cmd->add_option("--alpha-x", o->alpha_x, "Models' roughness along the tangent")->check(number_in(open_closed(0, 10)));
  cmd->add_option("--alpha-y", o->alpha_y, "Models' roughness along the bitangent")->check(number_in(open_closed(0, 10)));
  cmd->add_option("--material", o->material, "Models' material: mirror, conductor, dielectric (default: the table's)");
  cmd->add_option("--eta", o->eta, "Models' index (conductor: real part; dielectric: below / above)")
      ->check(number_in(open_closed(0, 100)));
  cmd->add_option("--k", o->k, "Models' extinction coefficient (conductor)")->check(number_in(closed(0, 100)));
  cmd->add_option("--difference", o->against, "Difference image: measured minus walk or single")->capture_default_str();
  cmd->add_option("--white", o->white, "PNG: radiance shown as white (linear, then sRGB)")
      ->capture_default_str()
      ->check(number_in(positive()));
  cmd->add_option("--difference-range", o->range, "PNG: difference shown as full red (+) or blue (-)")
      ->capture_default_str()
      ->check(number_in(positive()));
  cmd->callback([o, outputs, &g] { run_render(*o, *outputs, g); });
}

}  // namespace microsim::cli
