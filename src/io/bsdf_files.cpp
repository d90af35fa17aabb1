#include "microsim/io/bsdf_files.hpp"

#include <chrono>

#include "microsim/io/merl.hpp"
#include "microsim/io/pbsdf.hpp"
#include "microsim/io/rgl_bsdf.hpp"
#include "microsim/version.hpp"

namespace microsim {

Json bsdf_exr_attributes(const Json& j, const std::string& json_path) {
  Json attrs = {{"microsim_command", "measure bsdf"},
                {"microsim_version", version()},
                {"file", j["file"]},
                {"surface", j["surface"].dump()},
                {"parameters", j["parameters"].dump()},
                {"summary_json", json_path}};
  if (j["incidences"].size() == 1) {
    attrs["albedo"] = j["albedo"].dump();
    attrs["reflected_stderr"] = j["reflected_stderr"].dump();
    attrs["transmitted_stderr"] = j["transmitted_stderr"].dump();
  }
  return attrs;
}

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

void write_bsdf_table_file(const std::string& path, const BsdfTableFile& o, const BsdfTable& t,
                           const Microsurface& s, Json& j, const std::string& json_path) {
  const auto tb = std::chrono::steady_clock::now();
  if (o.format == "exr") {
    write_exr(path, bsdf_table_exr(t, bsdf_exr_attributes(j, json_path)));
  } else if (o.format == "bsdf") {
    RglOptions ro;
    ro.resolution = o.table_resolution;
    ro.description = o.rgl_description;
    const RglTable rgl = build_rgl_table(t, s, ro);
    write_rgl_bsdf(path, rgl);
    j["table"] = {{"format", "RGL tensor file (Dupuy and Jakob 2018)"},
                  {"isotropic", rgl.isotropic},
                  {"resolution", rgl.resolution},
                  {"ndf_shape", {rgl.ndf_phi, rgl.ndf_theta}},
                  {"sigma_shape", {rgl.sigma_phi, rgl.sigma_theta}},
                  {"description", rgl.description},
                  {"azimuths", t.azimuths()},
                  {"seconds", seconds_since(tb)}};
  } else if (o.format == "pbsdf") {
    const PolarizedTable pt = measured_pbsdf(t, o.table_resolution);
    write_pbsdf(path, pt);
    Json nm = Json::array();
    for (std::uint16_t w : pt.wavelengths) nm.push_back(w);
    j["table"] = {{"format", "Mitsuba 3 measured_polarized polarized BRDF (RGL tensor file: theta_h, theta_d, "
                             "phi_d, wvls, M)"},
                  {"shape", {pt.phi_d.size(), pt.theta_d.size(), pt.theta_h.size(), pt.wavelengths.size(), 4, 4}},
                  {"wavelengths_nm", nm},
                  {"filling", "the Mueller BRDF f (reflected, all orders; no cosine factor: the plugin multiplies "
                              "by the light's cosine) of polarization.bins: bilinear between pixel centres, linear "
                              "in theta_i between measured incidences, held constant outside them; the mean over "
                              "the incidence azimuths; NaN where the light or the view is below the horizon"},
                  {"frames", "both beams of a node (light l, view v) with the reference axis normalize(l x v), the "
                             "s axis of the half vector h (the plugin's frames before its own rotation)"},
                  {"azimuths", t.azimuths()},
                  {"seconds", seconds_since(tb)}};
    if (t.results[0].wavelengths() == 0)
      j["table"]["single_index"] = "one index: the same matrix at each of the five wavelengths";
  } else if (o.format == "binary") {
    write_merl(path, t);
    j["table"] = {{"format", "MERL isotropic BRDF (90 x 90 x 180 doubles per channel)"},
                  {"filling", "measured f (reflected, all orders) at cell centres, bilinear on the "
                              "hemisphere maps, linear in theta_i between measured incidences, held "
                              "constant outside them; 0 below the horizon"},
                  {"azimuths", t.azimuths()},
                  {"seconds", seconds_since(tb)}};
    if (t.results[0].wavelengths() > 0)
      j["table"]["channels"] = "R, G, B: linear sRGB of the per-wavelength f (CIE 1931 2-degree "
                               "observer, equal-energy illuminant, white balanced: a mirror's are equal)";
  }
}

// ---------------------------------------------------------------------------------------------
// EXR

ExrTable bsdf_exr_table(const BsdfResult& r, const Json& attributes) {
  const int R = r.map.resolution(), K = r.options.orders;
  ExrTable t;
  t.width = R;
  t.height = R;
  const char* side_name[2] = {"reflected", "transmitted"};
  const int sides = r.options.material.transmits() ? 2 : 1;
  for (int sd = 0; sd < sides; ++sd)
    for (int k = 0; k <= K; ++k) {
      std::vector<float> f(static_cast<std::size_t>(R) * R), se(f.size());
      for (int px = 0; px < R * R; ++px) {
        const Estimate e = r.f_pixel(sd, k, px);
        // EXR rows run top to bottom: row y holds square row j = R - 1 - y (b increases upward).
        const int i = px % R, jrow = px / R;
        const std::size_t out = static_cast<std::size_t>(R - 1 - jrow) * R + i;
        f[out] = static_cast<float>(e.mean);
        se[out] = static_cast<float>(e.stderr_);
      }
      const std::string base = std::string(side_name[sd]) + ".f_" + order_key(k, K);
      t.channel_names.push_back(base);
      t.channels.push_back(std::move(f));
      t.channel_names.push_back(base + "_stderr");
      t.channels.push_back(std::move(se));
    }
  t.attributes = attributes;
  t.attributes["parameterization"] =
      "equal-area hemisphere map: pixel (x, y) covers square coordinates a in [-1 + 2x/R, -1 + 2(x+1)/R], "
      "b in [1 - 2(y+1)/R, 1 - 2y/R] (y = 0 is the top row, b = +1); (a, b) -> unit disk by the "
      "Shirley-Chiu concentric map (r = max(|a|,|b|), phi = pi/4 b/a if |a| >= |b| else pi/2 - pi/4 "
      "a/b), disk -> hemisphere by Lambert's equal-area map: |cos theta_o| = 1 - r^2, direction "
      "(r sqrt(2 - r^2) cos phi, r sqrt(2 - r^2) sin phi, +-(1 - r^2)); phi = 0 is +x of the tile. "
      "Every pixel subtends 2 pi / R^2 sr. Channels reflected.* are the upper hemisphere, "
      "transmitted.* the lower one (z -> -z).";
  t.attributes["value"] =
      "f = p / int_pixel |cos theta_o| d omega (exact pixel integral): p = fraction of the incident "
      "power leaving through the pixel after the channel's scattering orders; the radiance BSDF of "
      "[GeomBSDF24, eq. 4a]; *_stderr its standard error";
  return t;
}


ExrTable bsdf_table_exr(const BsdfTable& t, const Json& attributes) {
  if (t.results.size() == 1) return bsdf_exr_table(t.results[0], attributes);
  ExrTable out;
  Json incidences = Json::array();
  for (std::size_t k = 0; k < t.results.size(); ++k) {
    const BsdfResult& r = t.results[k];
    ExrTable one = bsdf_exr_table(r, Json::object());
    if (k == 0) {
      out = one;
      out.channel_names.clear();
      out.channels.clear();
    }
    for (std::size_t c = 0; c < one.channels.size(); ++c) {
      out.channel_names.push_back("incidence_" + std::to_string(k) + "." + one.channel_names[c]);
      out.channels.push_back(std::move(one.channels[c]));
    }
    incidences.push_back({deg(r.options.theta_i), deg(r.options.phi_i)});
  }
  for (auto it = attributes.begin(); it != attributes.end(); ++it) out.attributes[it.key()] = it.value();
  out.attributes["incidences"] = incidences.dump();
  out.attributes["incidence_layout"] =
      "channel incidence_<k>.<side>.f_<order>[_stderr] holds incidence k = p * n_theta + t for "
      "theta_i_deg[t], phi_i_deg[p] of the parameters; `incidences` lists [theta_i_deg, "
      "phi_i_deg] per k; each incidence's table follows `parameterization` and `value`";
  return out;
}


}  // namespace microsim
