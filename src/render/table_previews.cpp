#include "microsim/render/table_previews.hpp"

#include <chrono>
#include <cmath>
#include <sstream>

#include "microsim/io/checks.hpp"
#include "microsim/io/json_input.hpp"
#include "microsim/io/oiio_module.hpp"
#include "microsim/io/output.hpp"
#include "microsim/io/rgl_reader.hpp"

namespace microsim::render {

namespace {

const char* const kLights[2] = {"directional", "environment"};
const char* const kColumns[4] = {"measured", "single", "walk", "difference"};

// The models' parameters from the description microsim writes into its tables:
// "... microsurface ({surface JSON}), material NAME [eta E] [k K]; ...".
struct TableModel {
  std::string distribution, material;
  double alpha_x = 0, alpha_y = 0, eta = 0, k = 0;
};

// The surface JSON of a description: from the brace after "microsurface (" to its matching
// brace (strings skipped); empty when there is none.
std::string surface_json_of(const std::string& d) {
  const auto open = d.find("microsurface ({");
  if (open == std::string::npos) return "";
  int depth = 0;
  for (std::size_t p = open + 14; p < d.size(); ++p) {
    if (d[p] == '"') {  // skip strings
      for (++p; p < d.size() && d[p] != '"'; ++p)
        if (d[p] == '\\') ++p;
    } else if (d[p] == '{') {
      ++depth;
    } else if (d[p] == '}' && --depth == 0) {
      return d.substr(open + 14, p - open - 13);
    }
  }
  return "";
}

TableModel model_from_description(const std::string& d) {
  TableModel m;
  const std::string surface = surface_json_of(d);
  if (!surface.empty()) {
    Json s;
    try {
      s = parse_json_input(surface, "the table's description");
    } catch (const Json::exception&) {
      // Not JSON: no model parameters (the preview shows the table alone).
    }
    if (s.is_object()) {
      if (s.contains("alpha_x") && s.contains("alpha_y") && s["alpha_x"].is_number() && s["alpha_y"].is_number()) {
        m.alpha_x = s["alpha_x"].get<double>();
        m.alpha_y = s["alpha_y"].get<double>();
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
      if (key == "eta") m.eta = value;
      if (key == "k") m.k = value;
    }
  }
  return m;
}

// Mean, RMS, largest |value| and mean standard error over the sphere's pixels.
Json image_summary(const PreviewImage& im) {
  double mean = 0, rms = 0, max_abs = 0, mean_stderr = 0;
  int n = 0;
  for (std::size_t k = 0; k < im.radiance.size(); ++k) {
    if (!im.on_sphere[k]) continue;
    const double x = im.radiance[k];
    mean += x;
    rms += x * x;
    max_abs = std::max(max_abs, std::abs(x));
    mean_stderr += im.stderr_[k];
    ++n;
  }
  if (n) {
    mean /= n;
    rms = std::sqrt(rms / n);
    mean_stderr /= n;
  }
  return {{"mean", mean}, {"rms", rms}, {"max_abs", max_abs}, {"mean_stderr", mean_stderr}};
}

std::string fixed3(double x) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(3);
  os << x;
  return os.str();
}

void check_preview_options(const TablePreviewOptions& o) {
  if (extension_of(o.table) != "bsdf")
    throw ParameterError(literal_text(o.table) + ": render reads an RGL .bsdf table (write one with measure bsdf {output} TABLE.bsdf)");
  if (!(o.light_theta >= 0 && o.light_theta < 90))
    throw ParameterError("{light_theta} must be in [0, 90) degrees (got " + fixed3(o.light_theta) + ")");
  if (o.against != "walk" && o.against != "single")
    throw ParameterError("{difference} must be walk or single (got '" + literal_text(o.against) + "')");
}

// The models' parameters of the previews: options win over the table's description.
struct PreviewModel {
  std::string distribution, material_name;
  double alpha_x = 0, alpha_y = 0, eta = 0, k = 0;
  models::Material material;
};

PreviewModel preview_model(const TablePreviewOptions& o, const TableModel& tm) {
  PreviewModel pm;
  const std::string dist = !o.distribution.empty() ? o.distribution : tm.distribution;
  if (dist != "beckmann" && dist != "ggx")
    throw ParameterError("{distribution} must be beckmann or ggx" +
                         std::string(dist.empty() ? " (the table's description names none)" : " (got '" + literal_text(dist) + "')"));
  pm.distribution = dist;
  double ax = tm.alpha_x, ay = tm.alpha_y;
  if (o.alpha > 0) ax = ay = o.alpha;
  if (o.alpha_x > 0) ax = o.alpha_x;
  if (o.alpha_y > 0) ay = o.alpha_y;
  if (!(ax > 0 && ay > 0))
    throw ParameterError("{alpha} (or {alpha_x} and {alpha_y}) is needed: the table's description gives no roughness");
  pm.alpha_x = ax;
  pm.alpha_y = ay;
  const std::string mname = !o.material.empty() ? o.material : tm.material;
  const double eta = o.eta > 0 ? o.eta : tm.eta, k = o.k > 0 ? o.k : (o.eta > 0 ? 0.0 : tm.k);
  if (mname == "mirror") pm.material = models::Material::mirror();
  else if (mname == "conductor" && eta > 0) pm.material = models::Material::conductor(eta, k);
  else if (mname == "dielectric" && eta > 0) pm.material = models::Material::dielectric(eta);
  else
    throw ParameterError("{material} must be mirror, conductor (with {eta}, {k}) or dielectric (with {eta}); the "
                         "table's description gives '" + literal_text(mname) + "'");
  pm.material_name = mname;
  pm.eta = eta;
  pm.k = k;
  return pm;
}

Json preview_parameters(const TablePreviewOptions& o, const PreviewModel& pm, double irradiance) {
  const std::string& mname = pm.material_name;
  return {{"table", o.table},
          {"size", o.preview.size},
          {"samples", o.preview.samples},
          {"seed", o.preview.seed},
          {"light_theta_deg", o.light_theta},
          {"light_phi_deg", o.light_phi},
          {"light_irradiance", irradiance},
          {"distribution", pm.distribution},
          {"alpha_x", pm.alpha_x},
          {"alpha_y", pm.alpha_y},
          {"material", mname},
          {"eta", mname == "mirror" ? Json(nullptr) : Json(pm.eta)},
          {"k", mname == "conductor" ? Json(pm.k) : Json(nullptr)},
          {"difference", std::string("measured - ") + o.against},
          {"white", o.white},
          {"difference_range", o.range}};
}

const char* const kPreviewLayout =
    "orthographic view of a unit sphere along -z (x right, y up); surface frame of a globe whose axis is the "
    "image's vertical (tangent along the parallels); directional light from (light_theta_deg from the view "
    "axis, light_phi_deg from the image's x axis) with irradiance pi (a white Lambertian surface facing it has "
    "radiance 1); uniform white environment of radiance 1 (radiance = directional albedo); "
    "measured: the RGL table evaluated as Mitsuba 3's measured plugin does; single: microfacet BRDF with the "
    "height-correlated Smith G2; walk: Smith random walk (all orders); difference: measured minus the model "
    "named in `difference`; *_stderr: standard error of each pixel's Monte Carlo mean";

}  // namespace

TablePreviews render_table_previews(const TablePreviewOptions& o, const std::function<void(double)>& progress) {
  check_preview_options(o);
  const RglMaterial table(o.table);
  const PreviewModel pm = preview_model(o, model_from_description(table.description()));
  const models::Ndf ndf = pm.distribution == "ggx" ? models::Ndf::ggx(pm.alpha_x, pm.alpha_y)
                                                   : models::Ndf::beckmann(pm.alpha_x, pm.alpha_y);

  TablePreviews out;
  Lighting directional, environment;
  directional.light = direction_from_angles(rad(o.light_theta), rad(o.light_phi));  // camera frame
  environment.environment = true;
  const TablePreview measured(table, &ndf);
  const SingleScatteringPreview single(models::MicrofacetBsdf{ndf, pm.material, models::Masking::SmithHeightCorrelated});
  const SmithWalkPreview walk(models::SmithRandomWalk(ndf, pm.material));
  const PreviewBsdf* bsdfs[3] = {&measured, &single, &walk};
  const auto t0 = std::chrono::steady_clock::now();
  for (int L = 0; L < 2; ++L) {
    for (int m = 0; m < 3; ++m) {
      out.images[L].push_back(render_sphere(*bsdfs[m], L ? environment : directional, o.preview,
                                            static_cast<std::uint64_t>(2 * m + L)));
      if (progress) progress((3.0 * L + m + 1) / 6.0);
    }
    out.images[L].push_back(difference(out.images[L][0], out.images[L][o.against == "walk" ? 2 : 1]));
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  out.summary = Json::object();
  for (int L = 0; L < 2; ++L)
    for (int c = 0; c < 4; ++c) out.summary[kLights[L]][kColumns[c]] = image_summary(out.images[L][c]);
  out.parameters = preview_parameters(o, pm, directional.irradiance);
  out.layout = kPreviewLayout;
  out.table_description = table.description();
  out.distribution = pm.distribution;
  out.material = pm.material_name;
  out.alpha_x = pm.alpha_x;
  out.alpha_y = pm.alpha_y;
  return out;
}

void write_previews_exr(const std::string& path, const TablePreviews& p) {
  ExrTable t;
  t.width = t.height = p.images[0][0].size;
  for (int L = 0; L < 2; ++L)
    for (int c = 0; c < 4; ++c) {
      t.channel_names.push_back(std::string(kLights[L]) + "." + kColumns[c]);
      t.channels.push_back(p.images[L][c].radiance);
      t.channel_names.push_back(std::string(kLights[L]) + "." + kColumns[c] + "_stderr");
      t.channels.push_back(p.images[L][c].stderr_);
    }
  t.attributes = {{"microsim_command", "render"}, {"layout", p.layout}, {"parameters", p.parameters.dump()},
                  {"table_description", p.table_description}, {"summary", p.summary.dump()}};
  write_exr(path, t);
}

void write_previews_png(const std::string& path, const TablePreviews& p, double white, double range) {
  std::vector<std::vector<PanelTile>> rows(2);
  for (int L = 0; L < 2; ++L)
    for (int c = 0; c < 4; ++c) rows[L].push_back({&p.images[L][c], c == 3});
  int w = 0, h = 0;
  const auto rgb = panel_rgb8(rows, white, range, &w, &h);
  write_png_rgb8(path, w, h, rgb);
}

}  // namespace microsim::render
