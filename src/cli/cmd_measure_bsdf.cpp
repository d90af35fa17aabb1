// microsim measure bsdf FILE --material ... -o OUT.exr|OUT.json|OUT.bsdf|OUT.binary|OUT.pbsdf: the BSDF per
// scattering order by random walks on the explicit surface, beside the single-scattering models
// and the Smith random-walk multiple-scattering model, at every incidence of --theta-i x --phi-i;
// .bsdf (RGL tensor file), .binary (MERL) and .pbsdf (polarized) are tables renderers load. The
// library's BsdfRequest does the work; this is the command line's adapter.
#include <iomanip>
#include <iostream>

#include "cli_common.hpp"
#include "option_checks.hpp"
#include "microsim/api/bsdf_run.hpp"
#include "microsim/io/output.hpp"

namespace microsim::cli {

namespace {

struct BsdfCliOptions {
  std::string surface, output, theta_i, phi_i = "0", wavelengths;
  double eta = 0.0, k = 0.0;
  bool no_models = false;
  BsdfRequest request;
};

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

// A spectral run: the reflected albedo (all orders) per wavelength and its colour.
void print_spectral(const Json& sp) {
  std::cout << "spectral (the rows above: " << fmt(sp["wavelengths_nm"][0].get<double>(), 1)
            << " nm)\n" << std::setw(12) << "lambda_nm" << std::setw(11) << "R total" << std::setw(10) << "stderr"
            << std::setw(11) << "R order 1" << std::setw(11) << "smooth" << "\n";
  for (std::size_t l = 0; l < sp["wavelengths_nm"].size(); ++l)
    std::cout << std::setw(12) << fmt(sp["wavelengths_nm"][l].get<double>(), 1) << std::setw(11)
              << fmt(sp["albedo"]["reflected"]["total"][l].get<double>(), 5) << std::setw(10)
              << fmt(sp["reflected_stderr"]["total"][l].get<double>(), 5) << std::setw(11)
              << fmt(sp["albedo"]["reflected"].begin().value()[l].get<double>(), 5) << std::setw(11)
              << fmt(sp["smooth_interface_reflected"][l].get<double>(), 5) << "\n";
  const Json& c = sp["reflected_rgb"]["total"];
  std::cout << "linear sRGB of R total: " << fmt(c[0].get<double>(), 4) << " " << fmt(c[1].get<double>(), 4) << " "
            << fmt(c[2].get<double>(), 4) << "\n";
}

void print_incidences(const Json& j, const BsdfRequest& o, bool nominal, double seconds,
                      const std::string& written) {
  const std::size_t n_inc = j["incidences"].size();
  const auto paths = j["parameters"]["rays"].get<std::uint64_t>();
  if (n_inc == 1) {
    std::cout << "BSDF of " << j["file"].get<std::string>() << ", " << o.material << ", theta_i "
              << o.theta_i_deg[0] << " deg, phi_i " << o.phi_i_deg[0] << " deg, " << paths << " rays"
              << (nominal ? "" : " (no nominal NDF: no microfacet models)")
              << "\n";
    print_summary(j, written);
    if (j.contains("spectral")) print_spectral(j["spectral"]);
    return;
  }
  std::cout << "BSDF of " << j["file"].get<std::string>() << ", " << o.material << ", " << n_inc
            << " incidences, " << paths << " rays each, " << fmt(seconds, 1) << " s\n";
  std::cout << std::setw(10) << "theta_i" << std::setw(10) << "phi_i" << std::setw(12) << "R total"
            << std::setw(10) << "stderr" << std::setw(12) << "smith_mult" << "\n";
  for (const auto& inc : j["incidences"]) {
    const Json& m = inc["albedo_models"]["smith_multiple"];
    std::cout << std::setw(10) << fmt(inc["theta_i_deg"].get<double>(), 1) << std::setw(10)
              << fmt(inc["phi_i_deg"].get<double>(), 1) << std::setw(12)
              << fmt(inc["albedo"]["reflected"]["total"].get<double>(), 5) << std::setw(10)
              << fmt(inc["reflected_stderr"]["total"].get<double>(), 5) << std::setw(12)
              << (m.is_null() ? std::string("-") : fmt(m["reflected"]["total"].get<double>(), 5)) << "\n";
  }
  std::cout << "wrote " << written << "\n";
}

int run_measure_bsdf(BsdfCliOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"exr", "json", "bsdf", "binary", "pbsdf"});
  BsdfRequest& r = o.request;
  r.format = extension_of(o.output);
  r.surface = input_surface_source(g, o.surface);
  r.theta_i_deg = parse_angle_list(o.theta_i, "--theta-i");
  r.phi_i_deg = parse_angle_list(o.phi_i, "--phi-i");
  if (!o.wavelengths.empty()) r.wavelengths_nm = parse_angle_list(o.wavelengths, "--wavelengths");
  const std::size_t n_inc = r.theta_i_deg.size() * r.phi_i_deg.size();
  Progress progress(n_inc > 1 ? "measure bsdf (" + std::to_string(n_inc) + " incidences)" : "measure bsdf", g.quiet);
  RunContext ctx = run_context(g);
  ctx.progress = [&](double f) { progress.update(f); };
  const BsdfRun run = run_bsdf_request(r, ctx, o.output);
  progress.finish();
  const std::string json_path = bsdf_record_path(o.output);
  write_record(g, json_path, run.record);
  if (!g.quiet)
    print_incidences(run.record, r, run.nominal_ndf, run.seconds,
                     r.format == "json" ? o.output : o.output + " and " + json_path);
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
                  "Mitsuba 3 / pbrt-v4), .binary (MERL, isotropic), .pbsdf (Mitsuba 3 measured_polarized, "
                  "with --polarized; conductor or mirror, isotropic) -- the JSON record goes beside "
                  "them, same name .json -- or .json (record only)")
      ->required();
  cmd->add_option("--material", o->request.material, "mirror, conductor or dielectric")->required();
  cmd->add_option("--eta", o->eta,
                  "Conductor: real part of the complex index; dielectric: index of the material "
                  "below relative to the medium above (e.g. 1.5, or 0.6667 for light inside glass)")
      ->check(number_in(positive()));
  cmd->add_option("--k", o->k, "Conductor: extinction coefficient (index eta + i k)")
      ->check(number_in(closed(0, 1000)));
  cmd->add_option("--metal", o->request.metal,
                  "Conductor: a shipped table of measured optical constants n(lambda), k(lambda): "
                  "Au, Ag, Cu (Johnson and Christy 1972) or Al (McPeak et al. 2015); a spectral run");
  cmd->add_option("--ior-file", o->request.ior_file,
                  "Conductor: a CSV file of rows 'wavelength_nm, n, k' (increasing wavelength; one header "
                  "line allowed; linear interpolation); a spectral run");
  cmd->add_option("--wavelengths", o->wavelengths,
                  "Spectral run (with --metal or --ior-file): wavelengths in nm, increasing, inside the "
                  "table (a, a,b,c or start:stop:step; default 450:650:50). Paths are traced once and "
                  "weighted per wavelength");
  cmd->add_option("--theta-i", o->theta_i,
                  "Incidence zenith angles in degrees, [0, 90): a, a,b,c or start:stop:step")
      ->required();
  cmd->add_option("--phi-i", o->phi_i,
                  "Incidence azimuths in degrees (same syntax); every theta_i x phi_i is measured")
      ->capture_default_str();
  cmd->add_option("--table-resolution", o->request.table_resolution,
                  "-o .bsdf: vertices per side of the per-incidence sample grid (vndf, spectra); -o .pbsdf: "
                  "N gives N/2 + 1 theta_h and theta_d nodes and N + 1 phi_d nodes")
      ->capture_default_str()
      ->check(integer_in(kMinTableResolution, kMaxTableResolution));
  cmd->add_option("--table-azimuths", o->request.table_azimuths,
                  "-o .bsdf / .binary / .pbsdf with one --phi-i: incidence azimuths the isotropic table averages "
                  "(phi_i + 360 k / N degrees, --rays split evenly, outgoing directions turned back "
                  "to phi_i), so it holds the surface's statistics rather than one azimuth's lobe; "
                  "the record's rows are the run at phi_i (rays / N walks). 1: phi_i alone")
      ->capture_default_str()
      ->check(integer_in(1, kMaxTableAzimuths));
  cmd->add_option("--orders", o->request.orders, "Scattering orders tallied: 1 .. K-1 separately, K+ together")
      ->capture_default_str()
      ->check(integer_in(1, kMaxBsdfOrders));
  cmd->add_option("--rays", o->request.rays, "Rays (random walks)")->capture_default_str()
      ->check(integer_in(1, kMaxRays));
  cmd->add_option("--seed", o->request.seed, "Random seed")->capture_default_str()
      ->check(seed_value());
  add_replicates_option(*cmd, o->request.replicates);
  cmd->add_flag("--polarized", o->request.polarized,
                "Also carry each reflected path's Mueller matrix (Stokes frames of the incident and "
                "exit directions) and record per incidence, order and wavelength the Mueller albedo, "
                "its errors and the degree of polarization (from the same paths as the unpolarized tally)");
  cmd->add_flag("--no-models", o->no_models,
                "Measure only: no analytic model beside the measurement (single-scattering "
                "integrals, Smith random walk, V-groove closed forms), which cost time on tables");
  cmd->add_option("--resolution", o->request.resolution,
                  "Hemisphere map resolution R (R x R equal-area pixels); also the number of "
                  "in-plane bins over [-90, 90] degrees")
      ->capture_default_str()
      ->check(integer_in(1, kMaxBsdfResolution));
  cmd->callback([o, cmd, &g] {
    o->request.eta = cmd->count("--eta") > 0 ? std::optional<double>(o->eta) : std::nullopt;
    o->request.k = cmd->count("--k") > 0 ? std::optional<double>(o->k) : std::nullopt;
    o->request.models = !o->no_models;
    run_measure_bsdf(*o, g);
  });
}

}  // namespace microsim::cli
