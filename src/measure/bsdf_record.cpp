#include "microsim/measure/bsdf_record.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>

#include "microsim/measure/groove_models.hpp"
#include "microsim/measure/single_scattering_albedos.hpp"
#include "microsim/models/spectral_rgb.hpp"
#include "microsim/measure/smith_walk_budget.hpp"

namespace microsim {

namespace {

const char* const kSideName[2] = {"reflected", "transmitted"};

// Comparisons of one surface's row: the table's rule (compare in table.hpp) without p-values.
void compare_one(Json& row, Comparison c) {
  c.p.clear();
  compare(row, c, 1);
}

// The albedo rows' comparisons and the in-plane rows', in the order they stand in a row.
Comparison smith_multiple_albedo() {
  return {"albedo", "smith_multiple", ModelKind::Nominal, "z_smith_multiple", "rel_dev_smith_multiple",
          "p_smith_multiple", "smith_multiple_stderr"};
}
Comparison smith_single_albedo() {
  return {"albedo", "smith_single", ModelKind::Nominal, "z_smith_single", "rel_dev_smith_single", "p_smith_single"};
}
Comparison vcavity_single_albedo() {
  return {"albedo", "vcavity_single", ModelKind::Nominal, "z_vcavity_single", "", "p_vcavity_single"};
}
Comparison smooth_interface_albedo() {
  return {"albedo", "smooth_interface", ModelKind::Nominal, "z_smooth_interface", "", "p_smooth_interface"};
}

// Fresnel reflectance (and transmittance) of a flat interface at cos theta_i = ci [GeomBSDF24, eq. 7d, 10b].
Json smooth_interface_json(const models::Material& mat, double ci) {
  using namespace microsim::models;
  if (mat.kind == MaterialKind::Mirror) return {{"reflected", 1.0}, {"transmitted", 0.0}};
  if (mat.kind == MaterialKind::Conductor) {
    const auto F = fresnel_conductor(ci, mat.eta, mat.k);
    return {{"reflected", F.unpolarized()}, {"transmitted", 0.0}, {"rs", F.Rs}, {"rp", F.Rp}};
  }
  const auto F = fresnel_dielectric(ci, mat.eta);
  return {{"reflected", F.unpolarized()}, {"transmitted", 1.0 - F.unpolarized()}, {"rs", F.Rs}, {"rp", F.Rp}};
}

// The models of the nominal NDF, compared with one surface (bsdf_record.hpp).
const char* const kNominalZ[3] = {"z_smith_single", "z_smith_multiple", "z_vcavity_single"};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Tables of one incidence

Table bsdf_albedo_spec() {
  Table t;
  t.error = ErrorKind::Replicates;
  const ErrorKind R = ErrorKind::Replicates, N = ErrorKind::None;
  t.spec.columns = {
      {"side", Merge::Key, N, "", "reflected, or transmitted (the second side of a dielectric)"},
      {"order", Merge::Key, N, "",
       "slot of scattering orders: order_1 .. order_{K-1} alone, order_Kplus (K and above), total"},
      {"albedo", Merge::Measured, R, "1", "share of the incident power leaving on this side after the slot's orders"},
      {"smith_multiple", Merge::Sharpest, R, "1",
       "the same share for the Smith multiple-scattering random walk on the nominal NDF (null without one)"},
      {"smith_multiple_stderr", Merge::Sharpest, N, "1", "the Monte Carlo standard error of smith_multiple"},
      {"smith_single", Merge::Copy, N, "1",
       "single-scattering albedo of the nominal NDF's BSDF with height-correlated Smith G2 (order_1 rows)"},
      {"vcavity_single", Merge::Copy, N, "1",
       "single-scattering albedo of the nominal NDF's BSDF with V-cavity G2 (order_1 rows)"},
      {"single_quadrature_n", Merge::Copy, N, "",
       "smith_single and vcavity_single (order_1 rows): side n of their n x n quadrature of the visible normals, the "
       "first of 128, 256, 512, 1024 whose estimated error is at most a tenth of the order_1 albedo's standard error"},
      {"single_quadrature_error", Merge::Copy, N, "1",
       "smith_single and vcavity_single (order_1 rows): estimated quadrature error, 2 max(|A(n) - A(n/2)|, "
       "|A(n/2) - A(n/4)| / 2) over the four single-scattering albedos (Smith, V-cavity; reflected, transmitted)"},
      {"smooth_interface", Merge::Copy, N, "1",
       "Fresnel reflectance (transmittance) of a flat interface of the material at theta_i (total rows)"}};
  t.spec.comparisons = {smith_multiple_albedo(), smith_single_albedo(), vcavity_single_albedo(),
                        smooth_interface_albedo()};
  return t;
}

Table bsdf_in_plane_spec(int orders) {
  const int K = orders;
  Table t;
  t.error = ErrorKind::Replicates;
  const ErrorKind R = ErrorKind::Replicates, N = ErrorKind::None;
  t.spec.columns = {
      {"side", Merge::Key, N, "", "reflected, or transmitted (the second side of a dielectric)"},
      {"theta_o_deg", Merge::Key, N, "deg",
       "centre of the bin: outgoing zenith angle in the plane of incidence, positive on the specular side"},
      {"theta_o_range_deg", Merge::Copy, N, "deg", "[lo, hi] of the bin"}};
  for (int k = 0; k <= K; ++k) {
    const std::string slot = k == K       ? std::string("all orders")
                             : k == K - 1 ? "orders " + std::to_string(K) + " and above"
                                          : "order " + std::to_string(k + 1);
    t.spec.columns.push_back({"f_" + order_key(k, K), Merge::Measured, R, "1/sr",
                              "BSDF of " + slot + ", cosine-weighted average over the bin's band of directions"});
  }
  t.spec.columns.push_back({"smith_single", Merge::Copy, N, "1/sr",
                            "the nominal NDF's single-scattering BSDF (height-correlated Smith G2) averaged "
                            "like f (null without a nominal NDF)"});
  t.spec.columns.push_back({"vcavity_single", Merge::Copy, N, "1/sr", "the same with V-cavity G2"});
  t.spec.columns.push_back({"smith_multiple", Merge::Sharpest, R, "1/sr",
                            "the Smith multiple-scattering random walk's BSDF, all orders, averaged like f"});
  t.spec.columns.push_back({"smith_multiple_stderr", Merge::Sharpest, N, "1/sr", "the Monte Carlo standard error of smith_multiple"});
  for (int k = 0; k < K; ++k)
    t.spec.row_fields.push_back({"smith_multiple_" + order_key(k, K), Merge::Sharpest, R, "1/sr",
                                 "the Smith random walk's BSDF in the slot " + order_key(k, K) + ", averaged like f"});
  const std::string f1 = "f_" + order_key(0, K), f_total = "f_" + order_key(K, K);
  t.spec.comparisons = {
      {f1, "smith_single", ModelKind::Nominal, "z_smith_single", "", "p_smith_single"},
      {f1, "vcavity_single", ModelKind::Nominal, "z_vcavity_single", "", "p_vcavity_single"},
      {f_total, "smith_multiple", ModelKind::Nominal, "z_smith_multiple", "", "p_smith_multiple",
       "smith_multiple_stderr"}};
  return t;
}

namespace {
// The albedo's single-scattering models of the nominal NDF and the flat interface's, computed
// once for the table and the record.
struct AlbedoModels {
  std::optional<models::SingleScatteringAlbedo> smith, vcavity;
  AlbedoQuadrature quadrature;
  Json smooth;
};
// The single-scattering models are compared with the order_1 albedo: their quadrature error is held
// below this fraction of its standard error (the smallest over the sides that have one).
constexpr double kQuadratureErrorFraction = 0.1;
double single_quadrature_target(const BsdfResult& r) {
  double se = 0.0;
  for (int sd = 0; sd < 2; ++sd) {
    const double s = r.albedo(sd, 0).stderr_;
    if (std::isfinite(s) && s > 0.0 && (se == 0.0 || s < se)) se = s;
  }
  return kQuadratureErrorFraction * se;  // 0 (no measured error): the finest quadrature
}
AlbedoModels albedo_models(const BsdfResult& r) {
  AlbedoModels a;
  if (r.nominal) {
    a.quadrature = single_scattering_albedos_to_error(*r.nominal, r.options.material, r.wi, single_quadrature_target(r));
    a.smith = a.quadrature.albedos.smith;
    a.vcavity = a.quadrature.albedos.vcavity;
  }
  a.smooth = smooth_interface_json(r.options.material, std::cos(r.options.theta_i));
  return a;
}

Table albedo_table(const BsdfResult& r, const AlbedoModels& models) {
  const int K = r.options.orders;
  const bool transmits = r.options.material.transmits();
  Table t = bsdf_albedo_spec();
  for (int sd = 0; sd < (transmits ? 2 : 1); ++sd)
    for (int k = 0; k <= K; ++k) {
      Json row;
      row["side"] = kSideName[sd];
      row["order"] = order_key(k, K);
      const Estimate e = r.albedo(sd, k);
      row["albedo"] = e.mean;
      row["albedo_stderr"] = e.stderr_;
      if (r.smith_walk) {
        const Estimate m = r.model_albedo(sd, k);
        row["smith_multiple"] = m.mean;
        row["smith_multiple_stderr"] = m.stderr_;
        compare_one(row, smith_multiple_albedo());
      }
      if (models.smith && k == 0) {
        row["smith_single"] = sd == 0 ? models.smith->reflected : models.smith->transmitted;
        compare_one(row, smith_single_albedo());
        row["vcavity_single"] = sd == 0 ? models.vcavity->reflected : models.vcavity->transmitted;
        compare_one(row, vcavity_single_albedo());
        row["single_quadrature_n"] = models.quadrature.n;
        row["single_quadrature_error"] = models.quadrature.estimated_error;
      }
      if (k == K) {
        row["smooth_interface"] = models.smooth[kSideName[sd]];
        compare_one(row, smooth_interface_albedo());
      }
      t.rows.push_back(row);
    }
  return t;
}
}  // namespace

Table bsdf_albedo_table(const BsdfResult& r) { return albedo_table(r, albedo_models(r)); }

Table bsdf_in_plane_table(const BsdfResult& r) {
  using namespace microsim::models;
  const int K = r.options.orders;
  const bool transmits = r.options.material.transmits();
  Table t = bsdf_in_plane_spec(K);
  for (int sd = 0; sd < (transmits ? 2 : 1); ++sd) {
    const bool above = sd == 0;
    for (int b = 0; b < r.plane.size(); ++b) {
      Json row;
      row["side"] = kSideName[sd];
      row["theta_o_deg"] = deg(r.plane.psi_center(b));
      row["theta_o_range_deg"] = {deg(r.plane.psi_lo(b)), deg(r.plane.psi_hi(b))};
      for (int k = 0; k <= K; ++k) {
        const Estimate e = r.f_plane(sd, k, b);
        const std::string key = "f_" + order_key(k, K);
        row[key] = e.mean;
        row[key + "_stderr"] = e.stderr_;
      }
      if (r.nominal) {
        const MicrofacetBsdf hcb{*r.nominal, r.options.material, Masking::SmithHeightCorrelated};
        const MicrofacetBsdf vcb{*r.nominal, r.options.material, Masking::VCavity};
        const Vec3 wi = r.wi;
        row["smith_single"] = r.plane.cos_weighted_average(b, above, [&](const Vec3& o) { return hcb.eval(o, wi); });
        row["vcavity_single"] = r.plane.cos_weighted_average(b, above, [&](const Vec3& o) { return vcb.eval(o, wi); });
        compare_one(row, t.spec.comparisons[0]);
        compare_one(row, t.spec.comparisons[1]);
      } else {
        row["smith_single"] = nullptr;
        row["vcavity_single"] = nullptr;
      }
      if (r.smith_walk) {
        const Estimate m = r.model_f_plane(sd, K, b), m1 = r.model_f_plane(sd, 0, b);
        row["smith_multiple"] = m.mean;
        row["smith_multiple_stderr"] = m.stderr_;
        row["smith_multiple_order_1"] = m1.mean;
        row["smith_multiple_order_1_stderr"] = m1.stderr_;
        for (int k = 1; k < K; ++k) {  // the walk's lobe of every further order, beside the closed forms'
          const Estimate mk = r.model_f_plane(sd, k, b);
          row["smith_multiple_" + order_key(k, K)] = mk.mean;
          row["smith_multiple_" + order_key(k, K) + "_stderr"] = mk.stderr_;
        }
        compare_one(row, t.spec.comparisons[2]);
      } else {
        row["smith_multiple"] = nullptr;
      }
      t.rows.push_back(row);
    }
  }
  return t;
}

// ---------------------------------------------------------------------------------------------
// JSON record

namespace {
// A spectral run's per-wavelength values: the albedo per side and order with its error, the flat
// interface's Fresnel reflectance, and the colour of the reflected albedo (models/spectral_rgb.hpp).
Json spectral_albedo_json(const BsdfResult& r) {
  const int K = r.options.orders, L = r.wavelengths();
  Json j;
  j["wavelengths_nm"] = r.options.wavelengths_nm;
  Json eta = Json::array(), k = Json::array(), smooth = Json::array();
  for (const models::Material& m : r.options.spectral) {
    eta.push_back(m.eta);
    k.push_back(m.k);
    smooth.push_back(models::fresnel_conductor(std::cos(r.options.theta_i), m.eta, m.k).unpolarized());
  }
  j["eta"] = eta;
  j["k"] = k;
  j["smooth_interface_reflected"] = smooth;
  const models::SpectrumToRgb colour(r.options.wavelengths_nm);
  for (int sd = 0; sd < 2; ++sd) {
    Json a = Json::object(), se = Json::object();
    for (int o = 0; o <= K; ++o) {
      Json v = Json::array(), e = Json::array();
      for (int l = 0; l < L; ++l) {
        const Estimate x = r.albedo(sd, o, l);
        v.push_back(x.mean);
        e.push_back(x.stderr_);
      }
      a[order_key(o, K)] = v;
      se[order_key(o, K)] = e;
    }
    j["albedo"][kSideName[sd]] = a;
    j[std::string(kSideName[sd]) + "_stderr"] = se;
  }
  Json rgb = Json::object();
  for (int o = 0; o <= K; ++o) {
    std::vector<double> v(L);
    for (int l = 0; l < L; ++l) v[l] = r.albedo(0, o, l).mean;
    const auto c = colour.rgb(v);
    rgb[order_key(o, K)] = {c[0], c[1], c[2]};
  }
  j["reflected_rgb"] = rgb;
  return j;
}
}  // namespace

namespace {
// Albedos per side and order ({reflected: {order: value}, transmitted: ...}) into out, then the
// errors per side (reflected_stderr, transmitted_stderr).
void put_albedos(Json& out, int K, const std::function<Estimate(int, int)>& estimate) {
  Json se[2] = {Json::object(), Json::object()};
  for (int sd = 0; sd < 2; ++sd) {
    Json a = Json::object();
    for (int k = 0; k <= K; ++k) {
      const Estimate e = estimate(sd, k);
      a[order_key(k, K)] = e.mean;
      se[sd][order_key(k, K)] = e.stderr_;
    }
    out[kSideName[sd]] = a;
  }
  out["reflected_stderr"] = se[0];
  out["transmitted_stderr"] = se[1];
}

// The models of the albedo: smooth interface, the single-scattering models of the nominal NDF
// and the Smith random walk (null where the run has none).
Json albedo_models_json(const BsdfResult& r, const AlbedoModels& am) {
  Json models = Json::object();
  models["smooth_interface"] = am.smooth;
  if (am.smith) {
    models["smith_single"] = {{"reflected", am.smith->reflected}, {"transmitted", am.smith->transmitted}};
    models["vcavity_single"] = {{"reflected", am.vcavity->reflected}, {"transmitted", am.vcavity->transmitted}};
    models["single_quadrature"] = {{"n", am.quadrature.n},
                                   {"estimated_error", am.quadrature.estimated_error},
                                   {"target_error", am.quadrature.target_error}};
  } else {
    models["smith_single"] = nullptr;
    models["vcavity_single"] = nullptr;
    models["single_quadrature"] = nullptr;
  }
  if (r.smith_walk) {
    Json mw = Json::object();
    put_albedos(mw, r.options.orders, [&](int sd, int k) { return r.model_albedo(sd, k); });
    mw["walks"] = r.smith_walk->paths;
    mw["unterminated"] = r.smith_walk->unterminated;
    mw["error_target"] = smith_walk_error_json(r);
    models["smith_multiple"] = mw;
  } else {
    models["smith_multiple"] = nullptr;
  }
  return models;
}

// The run's bookkeeping: paths, losses, events, the tracer's counters and the times.
void put_bsdf_bookkeeping(Json& j, const BsdfResult& r) {
  const auto& m = r.measured;
  j["paths"] = m.paths;
  j["replicates"] = m.replicates;
  j["lost_paths"] = m.lost;
  j["unterminated_paths"] = m.unterminated;
  j["scattering_events"] = m.events;
  j["mean_events_per_path"] = m.paths ? static_cast<double>(m.events) / m.paths : 0.0;
  j["traced_rays"] = m.counters.rays;
  j["tracer"] = {{"lost_below", m.counters.lost_below},
                 {"unresolved", m.counters.unresolved},
                 {"wrong_side_hits", m.counters.backface_hits},
                 {"border_crossings", m.counters.border_crossings}};
  j["trace_counters"] = fields_json(m.counters);  // every counter, as TraceCounters declares them
  const double seconds = r.timing.wall_seconds, model_seconds = r.model_timing.wall_seconds;
  j["seconds"] = seconds;
  j["model_seconds"] = model_seconds;
  j["rays_per_second"] = (seconds - model_seconds) > 0 ? m.counters.rays / (seconds - model_seconds) : 0.0;
}
}  // namespace

Json bsdf_summary_json(const BsdfResult& r, const Microsurface& s) {
  const int K = r.options.orders;
  Json j;
  // --- albedos: {reflected: {order: value}, transmitted: ...}, then the errors per side
  Json measured = Json::object();
  put_albedos(measured, K, [&](int sd, int k) { return r.albedo(sd, k); });
  j["albedo"] = {{"reflected", measured["reflected"]}, {"transmitted", measured["transmitted"]}};
  j["reflected_stderr"] = measured["reflected_stderr"];
  j["transmitted_stderr"] = measured["transmitted_stderr"];
  {
    // R + T per path is the path's weight when it leaves: its own standard error.
    const auto& m = r.measured;
    const double sum = m.albedo[m.a_index(0, K)] + m.albedo[m.a_index(1, K)];
    const Estimate RT = m.estimate(sum, m.both2);
    j["reflected_plus_transmitted"] = RT.mean;
    j["reflected_plus_transmitted_stderr"] = RT.stderr_;
  }
  const AlbedoModels am = albedo_models(r);
  j["albedo_models"] = albedo_models_json(r, am);
  if (!r.spectral.empty()) j["spectral"] = spectral_albedo_json(r);
  if (r.polarization) j["polarization"] = polarization_json(*r.polarization, r.options.wavelengths_nm);

  // --- the tables: measured beside the models per side and order, and the in-plane lobe
  j["rows"] = albedo_table(r, am).rows;
  j["in_plane"] = bsdf_in_plane_table(r).rows;
  if (r.options.models) add_groove_models(j, r, s);  // closed-form V-groove / V-cavity models beside rows and lobes
  add_macro_normalization(j, r, s);
  for (const char* table : {"rows", "in_plane"})
    for (Json& row : j[table])
      for (const char* z : kNominalZ) one_surface_nominal_z(row, z);
  put_bsdf_bookkeeping(j, r);
  return j;
}

Json bsdf_incidences_json(const BsdfTable& t, const Microsurface& s) {
  Json out = Json::array();
  for (std::size_t p = 0; p < t.phi_i.size(); ++p)
    for (std::size_t q = 0; q < t.theta_i.size(); ++q) {
      Json j = {{"theta_i_deg", deg(t.theta_i[q])}, {"phi_i_deg", deg(t.phi_i[p])}};
      const Json summary = bsdf_summary_json(t.at(static_cast<int>(p), static_cast<int>(q)), s);
      for (auto it = summary.begin(); it != summary.end(); ++it) j[it.key()] = it.value();
      out.push_back(j);
    }
  return out;
}

Json bsdf_definitions_json(const BsdfResult& r, bool polarized) {
  Json definitions = {
      {"albedo", "fraction of the incident power leaving on each side after exactly n scattering "
                 "events (order_Kplus: K or more; total: all); a conductor's paths carry the "
                 "product of their Fresnel factors, a dielectric chooses reflection with "
                 "probability F (unpolarized light); *_stderr: standard error of the mean of "
                 "`replicates` independent stratified replicates of the rays (the Smith walk's: "
                 "over its replicates of walks driven by shifted Sobol points, or its independent walks with "
                 "albedo_models.smith_multiple.error_target null)"},
      {"in_plane", "f = p / int_B |cos theta_o| d omega (exact), p the fraction of power leaving "
                   "through bin B: a band |beta| <= half width around the plane of incidence, "
                   "theta_o_deg signed, positive on the specular side (azimuth phi_i + 180); "
                   "transmitted rows measure theta_o from -n; the radiance BSDF of [GeomBSDF24, eq. 4a]"},
      {"smith_single", "single-scattering BRDF/BTDF of the nominal NDF, [GeomBSDF24, eq. 21d] / [Heitz14, eq. 18] "
                       "with Fresnel and the height-correlated Smith G2 ([Heitz14, eq. 21]; "
                       "transmission B(1+Lo, 1+Li)), averaged over the bin"},
      {"vcavity_single", "the same with the V-cavity G2 [Heitz14, Sec. 6]"},
      {"smith_multiple", "all orders of the Smith random-walk model of the nominal NDF (Monte "
                         "Carlo, smith_multiple_walks walks, same bins)"},
      {"smooth_interface", "Fresnel reflectance of a flat interface at theta_i [GeomBSDF24, eq. 7d, 10b]"},
      {"z_smith_single", "null: smith_single, smith_multiple and vcavity_single are models of the "
                         "nominal NDF, a statistic of the generated surfaces; one surface's ray-count "
                         "error misses the surface-to-surface variation, so its z is no verdict on "
                         "the model (microsim validate compares them over an ensemble of surfaces). "
                         "The same holds for z_smith_multiple and z_vcavity_single"},
      {"z_smith_single_rays", "(albedo - model) / stderr with this surface's ray-count error "
                              "(and the walks' error for z_smith_multiple_rays): the distance in "
                              "units of this run's noise, not a test of the model"},
      {"incidences", "one object per incidence (theta_i_deg, phi_i_deg and the single-incidence "
                     "fields), phi_i outer, theta_i inner; with one incidence the same fields "
                     "also stand at the top level"}};
  if (!r.spectral.empty())
    definitions["spectral"] =
        "a spectral conductor (metal or ior_file): every path traced once with one weight per "
        "wavelength (the product of that wavelength's unpolarized Fresnel reflectances), each "
        "wavelength's tallies those of a run with its index alone; the scalar fields (albedo, rows, "
        "in_plane, albedo_models) hold the first wavelength's values and the models use its index. "
        "spectral.albedo.<side>.<order>: one value per wavelengths_nm (errors in <side>_stderr); "
        "smooth_interface_reflected: a flat interface's Fresnel reflectance per wavelength; "
        "reflected_rgb: linear sRGB of the reflected albedo spectrum (CIE 1931 2-degree observer "
        "by the fit of [Wyman13], equal-energy illuminant, each channel divided by a constant "
        "spectrum's: a mirror is (1, 1, 1)); n and k linear in the wavelength between table rows";
  if (polarized)
    definitions["polarization"] =
        "Mueller matrices of the reflected paths (row-major 4 x 4, Stokes vectors with s3 = -2 Im(Ex Ey*) "
        "for exp(-i omega t)); input frame: the light travelling along -l with reference axis "
        "normalize(z x l); output frame: each path's exit direction o with axis normalize(z x o) "
        "(0, 1, 0 on the normal). reflected.<order>: the Mueller albedo per wavelength. bins: the "
        "Mueller BSDF f = sum of the paths' matrices / (paths * int_pixel |cos theta_o| d omega) per "
        "pixel of the equal-area hemisphere map of bins.resolution = min(resolution, 32) (all orders; "
        "pixel j * R + i, the map of the EXR tables), f[wavelength][pixel]; in_plane.<order>: the same "
        "per in-plane bin (the bins of in_plane), f[wavelength][bin]; *_stderr: the spread of the "
        "replicate means. M00 is the BSDF of unpolarized light";
  return definitions;
}

void put_bsdf_incidences(Json& j, const BsdfTable& t, const Microsurface& s) {
  const Json incidences = bsdf_incidences_json(t, s);
  if (t.results.size() == 1)
    for (auto it = incidences[0].begin(); it != incidences[0].end(); ++it)
      if (it.key() != "theta_i_deg" && it.key() != "phi_i_deg") j[it.key()] = it.value();
  j["incidences"] = incidences;
}

}  // namespace microsim
