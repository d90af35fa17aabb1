// microsim render TABLE.bsdf -o sphere.png|.exr|.json: sphere previews of a measured RGL table
// beside the analytic single-scattering BRDF and the Smith random walk of the same NDF and
// material (render/sphere_preview.hpp), under a directional light and a uniform white
// environment, with the difference image.
#include <chrono>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "cli_common.hpp"
#include "option_checks.hpp"
#include "microsim/io/oiio_module.hpp"
#include "microsim/io/output.hpp"
#include "microsim/io/rgl_reader.hpp"
#include "microsim/render/sphere_preview.hpp"

namespace microsim::cli {

namespace {

struct RenderCliOptions {
  std::string table;
  std::vector<std::string> outputs;
  int size = 256, samples = 64;
  std::uint64_t seed = 1;
  double light_theta = 45.0, light_phi = 135.0;
  std::string distribution, material, against = "walk";
  double alpha = 0, alpha_x = 0, alpha_y = 0, eta = 0, k = 0;
  double white = 1.0, range = 0.1;
};

// The models' parameters from the description microsim writes into its tables:
// "... microsurface ({surface JSON}), material NAME [eta E] [k K]; ...".
struct TableModel {
  std::string distribution, material;
  double alpha_x = 0, alpha_y = 0, eta = 0, k = 0;
  bool has_alpha = false, has_eta = false, has_k = false;
};

TableModel model_from_description(const std::string& d) {
  TableModel m;
  // The surface JSON: from the brace after "microsurface (" to its matching brace.
  const auto open = d.find("microsurface ({");
  std::size_t end = std::string::npos;
  if (open != std::string::npos) {
    int depth = 0;
    for (std::size_t p = open + 14; p < d.size() && end == std::string::npos; ++p) {
      if (d[p] == '"') {  // skip strings
        for (++p; p < d.size() && d[p] != '"'; ++p)
          if (d[p] == '\\') ++p;
      } else if (d[p] == '{') {
        ++depth;
      } else if (d[p] == '}' && --depth == 0) {
        end = p;
      }
    }
  }
  if (end != std::string::npos) {
    const Json s = Json::parse(d.substr(open + 14, end - open - 13), nullptr, false);
    if (s.is_object()) {
      if (s.contains("alpha_x") && s.contains("alpha_y") && s["alpha_x"].is_number() && s["alpha_y"].is_number()) {
        m.alpha_x = s["alpha_x"].get<double>();
        m.alpha_y = s["alpha_y"].get<double>();
        m.has_alpha = true;
      }
      const std::string kind = s.value("kind", std::string()), nominal = s.value("nominal_ndf", std::string());
      if (nominal == "beckmann" || kind == "gaussian") m.distribution = "beckmann";
      if (nominal == "ggx" || kind == "gaussian-ggx") m.distribution = "ggx";
    }
  }
  const auto mat = d.find("material ");
  if (mat != std::string::npos) {
    std::istringstream in(d.substr(mat + 9, d.find(';', mat) - mat - 9));
    in >> m.material;
    std::string key;
    double value;
    while (in >> key >> value) {
      if (key == "eta") m.eta = value, m.has_eta = true;
      if (key == "k") m.k = value, m.has_k = true;
    }
  }
  return m;
}

struct Stats {
  double mean = 0, rms = 0, max_abs = 0, mean_stderr = 0;
};
Stats stats(const render::PreviewImage& im) {
  Stats s;
  int n = 0;
  for (std::size_t k = 0; k < im.radiance.size(); ++k) {
    if (!im.on_sphere[k]) continue;
    const double x = im.radiance[k];
    s.mean += x;
    s.rms += x * x;
    s.max_abs = std::max(s.max_abs, std::abs(x));
    s.mean_stderr += im.stderr_[k];
    ++n;
  }
  if (n) {
    s.mean /= n;
    s.rms = std::sqrt(s.rms / n);
    s.mean_stderr /= n;
  }
  return s;
}

int run_render(const RenderCliOptions& o, const GlobalOptions& g) {
  for (const auto& out : o.outputs) require_extension(out, {"png", "exr", "json"});
  if (extension_of(o.table) != "bsdf")
    throw UsageError(o.table + ": render reads an RGL .bsdf table (write one with measure bsdf -o TABLE.bsdf)");
  if (!(o.light_theta >= 0 && o.light_theta < 90))
    throw UsageError("--light-theta must be in [0, 90) degrees (got " + fmt(o.light_theta, 3) + ")");
  if (o.against != "walk" && o.against != "single")
    throw UsageError("--difference must be walk or single (got '" + o.against + "')");
  const RglMaterial table(o.table);
  const TableModel tm = model_from_description(table.description());

  // Models: options win over the table's description.
  const std::string dist = !o.distribution.empty() ? o.distribution : tm.distribution;
  if (dist != "beckmann" && dist != "ggx")
    throw UsageError("--distribution must be beckmann or ggx" +
                     std::string(dist.empty() ? " (the table's description names none)" : " (got '" + dist + "')"));
  double ax = tm.alpha_x, ay = tm.alpha_y;
  if (o.alpha > 0) ax = ay = o.alpha;
  if (o.alpha_x > 0) ax = o.alpha_x;
  if (o.alpha_y > 0) ay = o.alpha_y;
  if (!(ax > 0 && ay > 0))
    throw UsageError("--alpha (or --alpha-x and --alpha-y) is needed: the table's description gives no roughness");
  const std::string mname = !o.material.empty() ? o.material : tm.material;
  double eta = o.eta > 0 ? o.eta : tm.eta, k = o.k > 0 ? o.k : (o.eta > 0 ? 0.0 : tm.k);
  models::Material material;
  if (mname == "mirror") material = models::Material::mirror();
  else if (mname == "conductor" && eta > 0) material = models::Material::conductor(eta, k);
  else if (mname == "dielectric" && eta > 0) material = models::Material::dielectric(eta);
  else
    throw UsageError("--material must be mirror, conductor (with --eta, --k) or dielectric (with --eta); the "
                     "table's description gives '" + mname + "'");
  const models::Ndf ndf = dist == "ggx" ? models::Ndf::ggx(ax, ay) : models::Ndf::beckmann(ax, ay);

  render::PreviewOptions po;
  po.size = o.size;
  po.samples = o.samples;
  po.seed = o.seed;
  render::Lighting directional, environment;
  directional.light = direction_from_angles(rad(o.light_theta), rad(o.light_phi));  // camera frame
  environment.environment = true;

  const render::TablePreview measured(table, &ndf);
  const render::SingleScatteringPreview single(models::MicrofacetBsdf{ndf, material, models::Masking::SmithHeightCorrelated});
  const render::SmithWalkPreview walk(models::SmithRandomWalk(ndf, material));
  const render::PreviewBsdf* bsdfs[3] = {&measured, &single, &walk};
  const auto t0 = std::chrono::steady_clock::now();
  Progress progress("render (6 images)", g.quiet);
  std::vector<render::PreviewImage> images[2];  // [light][measured, single, walk, difference]
  for (int L = 0; L < 2; ++L) {
    for (int m = 0; m < 3; ++m) {
      images[L].push_back(render::render_sphere(*bsdfs[m], L ? environment : directional, po,
                                                static_cast<std::uint64_t>(2 * m + L)));
      progress.update((3.0 * L + m + 1) / 6.0);
    }
    images[L].push_back(render::difference(images[L][0], images[L][o.against == "walk" ? 2 : 1]));
  }
  progress.finish();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  const char* lights[2] = {"directional", "environment"};
  const char* columns[4] = {"measured", "single", "walk", "difference"};
  Json summary = Json::object();
  for (int L = 0; L < 2; ++L)
    for (int c = 0; c < 4; ++c) {
      const Stats s = stats(images[L][c]);
      summary[lights[L]][columns[c]] = {{"mean", s.mean}, {"rms", s.rms}, {"max_abs", s.max_abs},
                                        {"mean_stderr", s.mean_stderr}};
    }
  Json parameters = {{"table", o.table},
                     {"size", o.size},
                     {"samples", o.samples},
                     {"seed", o.seed},
                     {"light_theta_deg", o.light_theta},
                     {"light_phi_deg", o.light_phi},
                     {"light_irradiance", directional.irradiance},
                     {"distribution", dist},
                     {"alpha_x", ax},
                     {"alpha_y", ay},
                     {"material", mname},
                     {"eta", mname == "mirror" ? Json(nullptr) : Json(eta)},
                     {"k", mname == "conductor" ? Json(k) : Json(nullptr)},
                     {"difference", std::string("measured - ") + o.against},
                     {"white", o.white},
                     {"difference_range", o.range}};
  const char* layout =
      "orthographic view of a unit sphere along -z (x right, y up); surface frame of a globe whose axis is the "
      "image's vertical (tangent along the parallels); directional light from (light_theta_deg from the view "
      "axis, light_phi_deg from the image's x axis) with irradiance pi (a white Lambertian surface facing it has "
      "radiance 1); uniform white environment of radiance 1 (radiance = directional albedo); "
      "measured: the RGL table evaluated as Mitsuba 3's measured plugin does; single: microfacet BRDF with the "
      "height-correlated Smith G2; walk: Smith random walk (all orders); difference: measured minus the model "
      "named in `difference`; *_stderr: standard error of each pixel's Monte Carlo mean";

  for (const auto& out : o.outputs) {
    const std::string ext = extension_of(out);
    if (ext == "exr") {
      ExrTable t;
      t.width = t.height = o.size;
      for (int L = 0; L < 2; ++L)
        for (int c = 0; c < 4; ++c) {
          t.channel_names.push_back(std::string(lights[L]) + "." + columns[c]);
          t.channels.push_back(images[L][c].radiance);
          t.channel_names.push_back(std::string(lights[L]) + "." + columns[c] + "_stderr");
          t.channels.push_back(images[L][c].stderr_);
        }
      t.attributes = {{"microsim_command", "render"}, {"layout", layout}, {"parameters", parameters.dump()},
                      {"table_description", table.description()}, {"summary", summary.dump()}};
      write_exr(out, t);
    } else if (ext == "png") {
      std::vector<std::vector<render::PanelTile>> rows(2);
      for (int L = 0; L < 2; ++L)
        for (int c = 0; c < 4; ++c) rows[L].push_back({&images[L][c], c == 3});
      int w = 0, h = 0;
      const auto rgb = render::panel_rgb8(rows, o.white, o.range, &w, &h);
      write_png_rgb8(out, w, h, rgb);
    } else {
      Json j = run_header("render", g);
      j["parameters"] = parameters;
      j["table_description"] = table.description();
      j["layout"] = layout;
      j["seconds"] = seconds;
      j["summary"] = summary;
      write_record(out, j);
    }
  }
  if (!g.quiet) {
    std::cout << "sphere previews of " << o.table << " (" << dist << " alpha " << fmt(ax, 3)
              << (ax != ay ? "/" + fmt(ay, 3) : "") << ", " << mname << "), " << o.size << "^2 pixels, "
              << o.samples << " samples, " << fmt(seconds, 1) << " s\n";
    std::cout << std::setw(12) << "light" << std::setw(11) << "measured" << std::setw(11) << "single" << std::setw(11)
              << "walk" << std::setw(16) << "rms difference" << "   (means over the sphere)\n";
    for (int L = 0; L < 2; ++L)
      std::cout << std::setw(12) << lights[L] << std::setw(11) << fmt(summary[lights[L]]["measured"]["mean"].get<double>())
                << std::setw(11) << fmt(summary[lights[L]]["single"]["mean"].get<double>()) << std::setw(11)
                << fmt(summary[lights[L]]["walk"]["mean"].get<double>()) << std::setw(16)
                << fmt(summary[lights[L]]["difference"]["rms"].get<double>()) << "\n";
    for (const auto& out : o.outputs) std::cout << "wrote " << out << "\n";
  }
  return 0;
}

}  // namespace

void register_render(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand(
      "render", "Sphere previews of a measured .bsdf table beside the single-scattering and Smith random-walk "
                "models: directional light and uniform white environment, with a difference image");
  auto o = std::make_shared<RenderCliOptions>();
  cmd->add_option("table", o->table, "RGL table (.bsdf) written by measure bsdf")->required();
  cmd->add_option("-o,--output", o->outputs,
                  "Outputs (repeatable): .png (panel: rows directional, environment; columns measured, single "
                  "scattering, Smith walk, difference), .exr (linear radiance of every image and its standard "
                  "error), .json (parameters and means)")
      ->required();
  cmd->add_option("--size", o->size, "Pixels per side of each sphere image")->capture_default_str()->check(integer_in(8, 4096));
  cmd->add_option("--samples", o->samples,
                  "Samples per pixel: environment directions, or walk estimates under the directional light")
      ->capture_default_str()
      ->check(integer_in(1, 1000000));
  cmd->add_option("--seed", o->seed, "Random seed")->capture_default_str()->check(seed_value());
  cmd->add_option("--light-theta", o->light_theta, "Directional light: angle from the view axis, degrees [0, 90)")
      ->capture_default_str()
      ->check(number_in(closed(0, 90)));
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
  cmd->callback([o, &g] { run_render(*o, g); });
}

}  // namespace microsim::cli
