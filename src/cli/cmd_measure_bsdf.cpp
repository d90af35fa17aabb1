// microsim measure bsdf FILE --material ... -o OUT.exr|OUT.json|OUT.bsdf|OUT.binary: the BSDF per
// scattering order by random walks on the explicit surface, beside the single-scattering models
// and the Smith random-walk multiple-scattering model, at every incidence of --theta-i x --phi-i;
// .bsdf (RGL tensor file) and .binary (MERL) are tables renderers load.
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <iomanip>
#include <iostream>

#include "cli_common.hpp"
#include "option_checks.hpp"
#include "microsim/io/output.hpp"
#include "microsim/io/merl.hpp"
#include "microsim/io/rgl_bsdf.hpp"
#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/bsdf_table.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim::cli {

namespace {

struct BsdfCliOptions {
  std::string surface, output, material;
  double eta = 0.0, k = 0.0;
  bool eta_given = false, k_given = false;
  std::string theta_i, phi_i = "0";
  int orders = 4;
  int table_resolution = 64;
  long long rays = 1000000;
  std::uint64_t seed = 1;
  int replicates = 32;
  bool no_models = false;
  int resolution = 64;
};

std::string replace_extension(const std::string& path, const std::string& ext) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return path + "." + ext;
  return path.substr(0, dot + 1) + ext;
}

models::Material parse_material(const BsdfCliOptions& o) {
  if (o.material == "mirror") {
    if (o.eta_given || o.k_given)
      throw UsageError("--eta and --k apply to --material conductor or dielectric, not mirror");
    return models::Material::mirror();
  }
  if (o.material == "conductor") {
    if (!o.eta_given || !o.k_given)
      throw UsageError("--material conductor needs --eta E and --k K (complex index eta + ik)");
    if (!(std::isfinite(o.eta) && o.eta > 0 && o.eta <= 100))
      throw UsageError("--eta must be in (0, 100] (got " + fmt(o.eta, 4) + ")");
    if (!(std::isfinite(o.k) && o.k >= 0 && o.k <= 100))
      throw UsageError("--k must be in [0, 100] (got " + fmt(o.k, 4) + ")");
    return models::Material::conductor(o.eta, o.k);
  }
  if (o.material == "dielectric") {
    if (!o.eta_given) throw UsageError("--material dielectric needs --eta E (index below / index above)");
    if (o.k_given) throw UsageError("--k applies to --material conductor only");
    if (!(std::isfinite(o.eta) && o.eta >= 0.01 && o.eta <= 100))
      throw UsageError("--eta must be in [0.01, 100] (got " + fmt(o.eta, 4) + ")");
    return models::Material::dielectric(o.eta);
  }
  throw UsageError("--material must be mirror, conductor or dielectric (got '" + o.material + "')");
}

// The models of the nominal NDF (Smith single and multiple scattering, V-cavity single) are
// statistics of the generated surfaces: compared with one surface, the ray-count error misses
// the surface-to-surface variation (DESIGN.md "Two kinds of error bar"), so no z is a verdict
// on the model. The z with the ray-count error is kept as z_*_rays; z_* is null.
void nominal_z_are_ray_count_only(Json& j) {
  for (const char* table : {"rows", "in_plane"}) {
    if (!j.contains(table)) continue;
    for (Json& row : j[table])
      for (const char* key : {"z_smith_single", "z_smith_multiple", "z_vcavity_single"})
        if (row.contains(key)) {
          row[std::string(key) + "_rays"] = row[key];
          row[key] = nullptr;
        }
  }
}

void print_summary(const Json& j, const std::string& out) {
  std::cout << std::setw(12) << "side" << std::setw(14) << "order" << std::setw(11) << "albedo"
            << std::setw(10) << "stderr" << std::setw(11) << "smith_mult" << std::setw(8) << "z_rays"
            << std::setw(11) << "smith_1" << std::setw(8) << "z_rays" << std::setw(11) << "vcavity_1"
            << "\n";
  auto num = [](const Json& x, int p) { return x.is_number() ? fmt(x.get<double>(), p) : std::string("-"); };
  for (const auto& row : j["rows"]) {
    std::cout << std::setw(12) << row["side"].get<std::string>() << std::setw(14)
              << row["order"].get<std::string>() << std::setw(11) << num(row["albedo"], 5)
              << std::setw(10) << num(row["albedo_stderr"], 5) << std::setw(11)
              << num(row.value("smith_multiple", Json()), 5) << std::setw(8)
              << num(row.value("z_smith_multiple_rays", Json()), 2) << std::setw(11)
              << num(row.value("smith_single", Json()), 5) << std::setw(8)
              << num(row.value("z_smith_single_rays", Json()), 2) << std::setw(11)
              << num(row.value("vcavity_single", Json()), 5) << "\n";
  }
  std::cout << "R + T = " << fmt(j["reflected_plus_transmitted"].get<double>(), 6) << " +- "
            << fmt(j["reflected_plus_transmitted_stderr"].get<double>(), 6) << "; lost paths "
            << j["lost_paths"].get<std::uint64_t>() << ", unterminated "
            << j["unterminated_paths"].get<std::uint64_t>() << ", "
            << fmt(j["rays_per_second"].get<double>() / 1e6, 2) << " Mrays/s; wrote " << out << "\n";
}

// Sorted, without repeats (a table's axes must increase).
std::vector<double> sorted_unique(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }), v.end());
  return v;
}

std::string table_description(const BsdfCliOptions& o, const Microsurface& s, const BsdfTable& t) {
  std::string d = "microsim measured BSDF of an explicit microsurface (" + s.description.dump() +
                  "), material " + o.material;
  if (o.eta_given) d += " eta " + fmt(o.eta, 4);
  if (o.k_given) d += " k " + fmt(o.k, 4);
  d += "; reflection, all scattering orders; " + std::to_string(t.results[0].measured.paths) +
       " random walks per incidence, seed " + std::to_string(o.seed);
  if (o.material == "dielectric") d += "; the reflected part only (transmission is not in this table)";
  return d;
}

int run_measure_bsdf(const BsdfCliOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"exr", "json", "bsdf", "binary"});
  const std::string ext = extension_of(o.output);
  const models::Material material = parse_material(o);
  const std::vector<double> thetas = sorted_unique(parse_angle_list(o.theta_i, "--theta-i"));
  require_above_horizon(thetas, "--theta-i");
  const std::vector<double> phis = sorted_unique(parse_angle_list(o.phi_i, "--phi-i"));
  for (double p : phis)
    if (!std::isfinite(p) || std::abs(p) > 3600)
      throw UsageError("--phi-i must be finite angles in degrees, |phi| <= 3600");
  if (o.orders < 1 || o.orders > 16)
    throw UsageError("--orders must be in [1, 16] (got " + std::to_string(o.orders) + ")");
  if (o.rays <= 0 || o.rays > 1000000000000LL)
    throw UsageError("--rays must be in [1, 1e12] (got " + std::to_string(o.rays) + ")");
  if (o.resolution < 1 || o.resolution > 1024)
    throw UsageError("--resolution must be in [1, 1024] (got " + std::to_string(o.resolution) + ")");
  if (o.table_resolution < 2 || o.table_resolution > 512)
    throw UsageError("--table-resolution must be in [2, 512] (got " + std::to_string(o.table_resolution) + ")");
  const std::size_t n_inc = thetas.size() * phis.size();
  if (n_inc > 100000) throw UsageError("--theta-i x --phi-i: more than 100000 incidences");
  if (ext == "binary" && phis.size() > 1)
    throw UsageError("-o .binary: MERL tables are isotropic; give one --phi-i (got " +
                     std::to_string(phis.size()) + " azimuths)");
  if (ext == "bsdf" && phis.size() > 1 && (std::abs(phis.front() + 180) > 1e-9 || std::abs(phis.back() - 180) > 1e-9))
    throw UsageError("--phi-i: an anisotropic .bsdf needs azimuths over the full circle from -180 to 180 "
                     "(e.g. --phi-i -180:180:30), or one azimuth for an isotropic table");
  {
    // Tallies: f and f^2 per side, slot and pixel, one per worker plus the merge tree, and the
    // finished results of every incidence.
    const double tally = 2.0 * (o.orders + 1) * (static_cast<double>(o.resolution) * o.resolution + o.resolution) * 2 * 8;
    const int threads = g.threads > 0 ? g.threads : tbb::this_task_arena::max_concurrency();
    const double need = tally * (3.0 * threads + 4.0 + 2.0 * n_inc);
    const double have = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE);
    if (need > 0.5 * have)
      throw UsageError("--resolution " + std::to_string(o.resolution) + " with --orders " +
                       std::to_string(o.orders) + " and " + std::to_string(n_inc) + " incidences needs about " +
                       fmt(need / (1 << 30), 1) + " GiB of tallies, more than half of this machine's memory");
  }
  Microsurface s = input_surface(g, o.surface);
  if (s.macro().finite_object() && (ext == "bsdf" || ext == "binary"))
    throw UsageError(o.surface + ": -o ." + ext + " tables need a periodic tile (this surface is a finite object)");
  const bool anisotropic_surface = s.nominal && std::abs(s.nominal->alpha_x - s.nominal->alpha_y) > 1e-12;
  if (ext == "binary" && anisotropic_surface)
    throw UsageError(o.surface + ": -o .binary needs an isotropic surface (MERL tables are isotropic; nominal "
                     "alpha_x != alpha_y); write a .bsdf with --phi-i -180:180:STEP instead");
  if (ext == "bsdf" && anisotropic_surface && phis.size() == 1)
    throw UsageError(o.surface + ": an anisotropic surface (alpha_x != alpha_y) needs --phi-i over the full "
                     "circle for a .bsdf (e.g. --phi-i -180:180:30)");
  const auto t0 = std::chrono::steady_clock::now();

  BsdfTableOptions to;
  to.base.material = material;
  to.base.orders = o.orders;
  to.base.rays = static_cast<std::uint64_t>(o.rays);
  to.base.split = g.split;  // shards and MPI ranks (scaleout.hpp)
  to.base.seed = o.seed;
  to.base.resolution = o.resolution;
  to.base.replicates = o.replicates;
  to.base.models = !o.no_models;
  to.base.model_walks = s.nominal && !o.no_models ? to.base.rays : 0;
  for (double t : thetas) to.theta_i.push_back(rad(t));
  for (double p : phis) to.phi_i.push_back(rad(p));
  Progress progress(n_inc > 1 ? "measure bsdf (" + std::to_string(n_inc) + " incidences)" : "measure bsdf", g.quiet);
  to.progress = [&](double f) { progress.update(f); };

  Tracer tracer(s);
  const BsdfTable table = measure_bsdf_table(tracer, to);
  progress.finish();
  const BsdfResult& r = table.results[0];
  const bool single = n_inc == 1;

  Json parameters = {{"material", o.material},
                     {"eta", o.eta_given ? Json(o.eta) : Json(nullptr)},
                     {"k", o.k_given ? Json(o.k) : Json(nullptr)},
                     {"theta_i_deg", single ? Json(thetas[0]) : Json(thetas)},
                     {"phi_i_deg", single ? Json(phis[0]) : Json(phis)},
                     {"orders", o.orders},
                     {"rays", r.measured.paths},
                     {"rays_requested", o.rays},
                     {"seed", o.seed},
                     {"replicates", to.base.replicates},
                     {"resolution", o.resolution},
                     {"in_plane_bins", r.plane.size()},
                     {"in_plane_band_half_width_deg", deg(r.plane.half_width())},
                     {"max_events", to.base.max_events},
                     {"smith_multiple_walks", to.base.model_walks},
                     {"models", !o.no_models}};
  if (ext == "bsdf") parameters["table_resolution"] = o.table_resolution;
  Json j = run_header("measure bsdf", g);
  j["file"] = o.surface;
  j["surface"] = s.description;
  j["parameters"] = parameters;
  j["definitions"] = {
      {"albedo", "fraction of the incident power leaving on each side after exactly n scattering "
                 "events (order_Kplus: K or more; total: all); a conductor's paths carry the "
                 "product of their Fresnel factors, a dielectric chooses reflection with "
                 "probability F (unpolarized light); *_stderr: standard error of the mean of "
                 "`replicates` independent stratified replicates of the rays (the Smith walk's: "
                 "over its independent walks)"},
      {"in_plane", "f = p / int_B |cos theta_o| d omega (exact), p the fraction of power leaving "
                   "through bin B: a band |beta| <= half width around the plane of incidence, "
                   "theta_o_deg signed, positive on the specular side (azimuth phi_i + 180); "
                   "transmitted rows measure theta_o from -n; the radiance BSDF of 000 eq. 4a"},
      {"smith_single", "single-scattering BRDF/BTDF of the nominal NDF, 000 eq. 21d / 001 eq. 18 "
                       "with Fresnel and the height-correlated Smith G2 (001 eq. 21; "
                       "transmission B(1+Lo, 1+Li)), averaged over the bin"},
      {"vcavity_single", "the same with the V-cavity G2 (001 sec. 6)"},
      {"smith_multiple", "all orders of the Smith random-walk model of the nominal NDF (Monte "
                         "Carlo, smith_multiple_walks walks, same bins)"},
      {"smooth_interface", "Fresnel reflectance of a flat interface at theta_i (000 eq. 7d, 10b)"},
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
  Json incidences = bsdf_incidences_json(table, s);
  for (Json& incidence : incidences) nominal_z_are_ray_count_only(incidence);
  if (single) {
    for (auto it = incidences[0].begin(); it != incidences[0].end(); ++it)
      if (it.key() != "theta_i_deg" && it.key() != "phi_i_deg") j[it.key()] = it.value();
  }
  j["incidences"] = incidences;

  std::string json_path = o.output;
  std::string written = o.output;
  if (ext != "json") {
    json_path = replace_extension(o.output, "json");
    written = o.output + " and " + json_path;
  }
  if (ext == "exr") {
    Json attrs = {{"microsim_command", "measure bsdf"},
                  {"microsim_version", "0.1.0"},
                  {"file", o.surface},
                  {"surface", s.description.dump()},
                  {"parameters", parameters.dump()},
                  {"summary_json", json_path}};
    if (single) {
      attrs["albedo"] = j["albedo"].dump();
      attrs["reflected_stderr"] = j["reflected_stderr"].dump();
      attrs["transmitted_stderr"] = j["transmitted_stderr"].dump();
    }
    write_exr(o.output, bsdf_table_exr(table, attrs));
  } else if (ext == "bsdf") {
    const auto tb = std::chrono::steady_clock::now();
    RglOptions ro;
    ro.resolution = o.table_resolution;
    ro.description = table_description(o, s, table);
    const RglTable rgl = build_rgl_table(table, s, ro);
    write_rgl_bsdf(o.output, rgl);
    j["table"] = {{"format", "RGL tensor file (Dupuy and Jakob 2018)"},
                  {"isotropic", rgl.isotropic},
                  {"resolution", rgl.resolution},
                  {"ndf_shape", {rgl.ndf_phi, rgl.ndf_theta}},
                  {"sigma_shape", {rgl.sigma_phi, rgl.sigma_theta}},
                  {"description", rgl.description},
                  {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - tb).count()}};
  } else if (ext == "binary") {
    const auto tb = std::chrono::steady_clock::now();
    write_merl(o.output, table);
    j["table"] = {{"format", "MERL isotropic BRDF (90 x 90 x 180 doubles per channel)"},
                  {"filling", "measured f (reflected, all orders) at cell centres, bilinear on the "
                              "hemisphere maps, linear in theta_i between measured incidences, held "
                              "constant outside them; 0 below the horizon"},
                  {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - tb).count()}};
  }
  j["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_record(g, json_path, j);
  if (!g.quiet) {
    if (single) {
      std::cout << "BSDF of " << o.surface << ", " << o.material << ", theta_i " << thetas[0]
                << " deg, phi_i " << phis[0] << " deg, " << r.measured.paths << " rays"
                << (s.nominal ? "" : " (no nominal NDF: no microfacet models)") << "\n";
      print_summary(j, written);
    } else {
      std::cout << "BSDF of " << o.surface << ", " << o.material << ", " << n_inc << " incidences, "
                << r.measured.paths << " rays each, " << fmt(table.seconds, 1) << " s\n";
      std::cout << std::setw(10) << "theta_i" << std::setw(10) << "phi_i" << std::setw(12) << "R total"
                << std::setw(10) << "stderr" << std::setw(12) << "smith_mult" << "\n";
      for (const auto& inc : incidences) {
        const Json& m = inc["albedo_models"]["smith_multiple"];
        std::cout << std::setw(10) << fmt(inc["theta_i_deg"].get<double>(), 1) << std::setw(10)
                  << fmt(inc["phi_i_deg"].get<double>(), 1) << std::setw(12)
                  << fmt(inc["albedo"]["reflected"]["total"].get<double>(), 5) << std::setw(10)
                  << fmt(inc["reflected_stderr"]["total"].get<double>(), 5) << std::setw(12)
                  << (m.is_null() ? std::string("-") : fmt(m["reflected"]["total"].get<double>(), 5)) << "\n";
      }
      std::cout << "wrote " << written << "\n";
    }
  }
  return 0;
}

}  // namespace

void register_measure_bsdf(CLI::App& measure, const GlobalOptions& g) {
  auto* cmd = measure.add_subcommand(
      "bsdf", "BSDF per scattering order by random walks on the surface (mirror, conductor, "
              "dielectric), beside the single-scattering models and the Smith random walk");
  auto o = std::make_shared<BsdfCliOptions>();
  cmd->add_option("surface", o->surface, "Surface file (a periodic tile, a finite object or a vcavity ensemble)")->required();
  cmd->add_option("-o,--output", o->output,
                  "Output: .exr (hemisphere tables of every incidence), .bsdf (RGL tensor file for "
                  "Mitsuba 3 / pbrt-v4), .binary (MERL, isotropic) -- the JSON record goes beside "
                  "them, same name .json -- or .json (record only)")
      ->required();
  cmd->add_option("--material", o->material, "mirror, conductor or dielectric")->required();
  cmd->add_option("--eta", o->eta,
                  "Conductor: real part of the complex index; dielectric: index of the material "
                  "below relative to the medium above (e.g. 1.5, or 0.6667 for light inside glass)")
      ->check(number_in(positive()));
  cmd->add_option("--k", o->k, "Conductor: extinction coefficient (index eta + i k)")
      ->check(number_in(closed(0, 1000)));
  cmd->add_option("--theta-i", o->theta_i,
                  "Incidence zenith angles in degrees, [0, 90): a, a,b,c or start:stop:step")
      ->required();
  cmd->add_option("--phi-i", o->phi_i,
                  "Incidence azimuths in degrees (same syntax); every theta_i x phi_i is measured")
      ->capture_default_str();
  cmd->add_option("--table-resolution", o->table_resolution,
                  "-o .bsdf: vertices per side of the per-incidence sample grid (vndf, spectra)")
      ->capture_default_str()
      ->check(integer_in(2, 512));
  cmd->add_option("--orders", o->orders, "Scattering orders tallied: 1 .. K-1 separately, K+ together")
      ->capture_default_str()
      ->check(integer_in(1, 64));
  cmd->add_option("--rays", o->rays, "Rays (random walks)")->capture_default_str()
      ->check(integer_in(1, kMaxRays));
  cmd->add_option("--seed", o->seed, "Random seed")->capture_default_str()
      ->check(seed_value());
  add_replicates_option(*cmd, o->replicates);
  cmd->add_flag("--no-models", o->no_models,
                "Measure only: no analytic model beside the measurement (single-scattering "
                "integrals, Smith random walk, V-groove closed forms), which cost time on tables");
  cmd->add_option("--resolution", o->resolution,
                  "Hemisphere map resolution R (R x R equal-area pixels); also the number of "
                  "in-plane bins over [-90, 90] degrees")
      ->capture_default_str()
      ->check(integer_in(1, 4096));
  cmd->callback([o, cmd, &g] {
    o->eta_given = cmd->count("--eta") > 0;
    o->k_given = cmd->count("--k") > 0;
    run_measure_bsdf(*o, g);
  });
}

}  // namespace microsim::cli
