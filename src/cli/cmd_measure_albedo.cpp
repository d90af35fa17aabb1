// microsim measure albedo SURFACE... --material ... -o OUT.json|OUT.csv|OUT.exr: the directional
// albedo E(mu) per scattering order and in total at the nodes of a quadrature in mu, and
// E_avg = 2 int E(mu) mu dmu with its statistical and quadrature errors, per surface; .exr is the
// lookup table E(mu, alpha) (rows: surfaces, columns: mu) with its error map. The library's
// AlbedoRequest does the work; this is the command line's adapter.
#include <iomanip>
#include <iostream>

#include "cli_common.hpp"
#include "option_checks.hpp"
#include "microsim/api/albedo_run.hpp"
#include "microsim/api/bsdf_run.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/albedo_measure.hpp"

namespace microsim::cli {

namespace {

struct AlbedoCliOptions {
  std::vector<std::string> surfaces;
  std::string output, theta_i;
  double eta = 0.0, k = 0.0;
  AlbedoRequest request;
};

void print_albedo(const Json& j, const std::string& written) {
  std::cout << "directional albedo E(mu), " << j["parameters"]["material"].get<std::string>() << ", "
            << j["quadrature"]["description"].get<std::string>() << "; "
            << j["parameters"]["rays_per_node"].get<long long>() << " rays per node\n";
  std::cout << std::setw(28) << "surface" << std::setw(8) << "alpha" << std::setw(11) << "E_avg"
            << std::setw(11) << "stderr" << std::setw(11) << "quad_err" << std::setw(11) << "min E"
            << std::setw(11) << "max se" << std::setw(10) << "lost" << "\n";
  for (const Json& s : j["surfaces"]) {
    const std::string file = s["file"].get<std::string>();
    double min_e = 1e300, max_se = 0;
    for (const Json& row : j["rows"])
      if (row["surface"] == file) {
        min_e = std::min(min_e, row["albedo"].get<double>());
        max_se = std::max(max_se, row["albedo_stderr"].get<double>());
      }
    for (const Json& a : j["averages"])
      if (a["surface"] == file && a["series"] == "albedo") {
        const std::string name = file.size() > 26 ? "..." + file.substr(file.size() - 23) : file;
        std::cout << std::setw(28) << name << std::setw(8) << fmt(s["alpha"], 3) << std::setw(11)
                  << fmt(a["average"], 6) << std::setw(11) << fmt(a["average_stderr"], 6) << std::setw(11)
                  << fmt(a["quadrature_error"], 6) << std::setw(11) << fmt(min_e, 6) << std::setw(11)
                  << fmt(max_se, 6) << std::setw(10) << s["lost_paths"].get<std::uint64_t>() << "\n";
      }
  }
  std::cout << "wrote " << written << "\n";
}

int run_measure_albedo(AlbedoCliOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv", "exr"});
  AlbedoRequest& r = o.request;
  r.format = extension_of(o.output);
  r.surfaces = input_surface_sources(g, o.surfaces);
  if (!o.theta_i.empty()) r.theta_i_deg = parse_angle_list(o.theta_i, "--theta-i");
  Progress progress("measure albedo (" + std::to_string(o.surfaces.size()) + " surfaces)", g.quiet);
  RunContext ctx = run_context(g);
  ctx.progress = [&](double f) { progress.update(f); };
  const AlbedoRun run = run_albedo_request(r, ctx);
  progress.finish();
  const std::string written = write_albedo_outputs(o.output, r, run);
  if (!g.quiet) print_albedo(run.record, written);
  return 0;
}

}  // namespace

void register_measure_albedo(CLI::App& measure, const GlobalOptions& g) {
  auto* cmd = measure.add_subcommand(
      "albedo", "Directional albedo E(mu) per scattering order and in total, E_avg = 2 int E mu dmu with "
                "its errors, and the lookup table E(mu, alpha) for energy compensation");
  auto o = std::make_shared<AlbedoCliOptions>();
  cmd->add_option("surfaces", o->surfaces,
                  "Surface file(s): each is measured on its own; with -o .exr each is a row of the lookup "
                  "table (give them in increasing alpha)")
      ->required();
  cmd->add_option("-o,--output", o->output,
                  "Output: .json (record), .csv (one row per surface and mu node; the record beside, .json) "
                  "or .exr (the lookup table: rows surfaces, columns mu, channels E, E_stderr, E_avg... ; "
                  "the rows beside, .csv, and the record, .json)")
      ->required();
  cmd->add_option("--material", o->request.material, "mirror, conductor or dielectric")->required();
  cmd->add_option("--eta", o->eta,
                  "Conductor: real part of the complex index; dielectric: index of the material below "
                  "relative to the medium above (e.g. 1.5)")
      ->check(number_in(positive()));
  cmd->add_option("--k", o->k, "Conductor: extinction coefficient (index eta + i k)")
      ->check(number_in(closed(0, 1000)));
  cmd->add_option("--metal", o->request.metal,
                  "Conductor: a shipped table of optical constants (Au, Ag, Cu, Al) at --wavelength-nm");
  cmd->add_option("--wavelength-nm", o->request.wavelength_nm, "With --metal: the wavelength in nm")
      ->capture_default_str()
      ->check(number_in(positive()));
  cmd->add_option("--mu-nodes", o->request.mu_nodes,
                  "Gauss-Legendre nodes in mu = cos theta_i on [0, 1]: E is measured at the nodes and E_avg "
                  "is the rule's sum; the quadrature error is estimated against the interpolating "
                  "polynomial of every other node")
      ->capture_default_str()
      ->check(integer_in(kMinMuNodes, kMaxMuNodes));
  cmd->add_option("--theta-i", o->theta_i,
                  "Instead of --mu-nodes: incidence zenith angles in degrees, [0, 90) (a, a,b,c or "
                  "start:stop:step); E_avg then integrates E linear in mu between them (constant beyond)");
  cmd->add_option("--phi-i", o->request.phi_i_deg, "Incidence azimuth in degrees (the first of --azimuths)")
      ->capture_default_str()
      ->check(finite_number());
  cmd->add_option("--azimuths", o->request.azimuths,
                  "Incidence azimuths averaged at each node (phi_i + 360 a / N; rays split evenly); "
                  "0: 1 on an isotropic surface, 8 on an anisotropic one")
      ->capture_default_str()
      ->check(integer_in(0, kMaxAlbedoAzimuths));
  cmd->add_option("--orders", o->request.orders, "Scattering orders tallied: 1 .. K-1 separately, K+ together")
      ->capture_default_str()
      ->check(integer_in(1, kMaxBsdfOrders));
  cmd->add_option("--rays", o->request.rays, "Rays (random walks) per mu node and surface")
      ->capture_default_str()
      ->check(integer_in(1, kMaxRays));
  cmd->add_option("--seed", o->request.seed, "Random seed")->capture_default_str()->check(seed_value());
  add_replicates_option(*cmd, o->request.replicates);
  cmd->callback([o, cmd, &g] {
    o->request.eta = cmd->count("--eta") > 0 ? std::optional<double>(o->eta) : std::nullopt;
    o->request.k = cmd->count("--k") > 0 ? std::optional<double>(o->k) : std::nullopt;
    run_measure_albedo(*o, g);
  });
}

}  // namespace microsim::cli
