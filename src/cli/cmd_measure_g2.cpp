// microsim measure g2 FILE... : masking-shadowing by area sampling with two occlusion rays,
// beside the four Smith forms [Heitz14, eq. 20-23] and the V-cavity model.
#include <iomanip>
#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "measure_options.hpp"
#include "option_checks.hpp"
#include "ensemble.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/measure/vcavity_measure.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim::cli {

namespace {

struct G2CliOptions {
  std::vector<std::string> files;
  std::string output;
  std::string theta_o, phi_o = "0", theta_i, phi_i = "0";
  long long rays = 1000000;
  std::uint64_t seed = 1;
  int replicates = 32;
};

const char* const kGrooveByGroove =
    "true for a V-cavity ensemble: [Heitz14, Sec. 6.1] made explicit, each groove (normals m, m' drawn "
    "from (n.m) D(m)) traced on its own as an infinite periodic V-groove, the points drawn over "
    "the whole ensemble with the weights w_f; `vcavity` [Heitz14, eq. 24 and Sec. 6] is then exact";

const char* kForms[] = {"separable", "height_correlated", "direction_correlated",
                        "height_direction_correlated"};

void print_g2_table(const Json& rows, bool ensemble) {
  std::cout << std::setw(6) << "th_o" << std::setw(6) << "ph_o" << std::setw(6) << "th_i"
            << std::setw(6) << "ph_i" << std::setw(9) << "g2" << std::setw(9) << "stderr"
            << std::setw(9) << "g1o*g1i" << std::setw(9) << "separ" << std::setw(9) << "height"
            << std::setw(9) << "dir" << std::setw(9) << "ht-dir" << std::setw(9) << "vcavity"
            << " |" << std::setw(8) << "sep" << std::setw(8) << "height" << std::setw(8) << "dir"
            << std::setw(8) << "ht-dir" << "\n"
            << "  Smith forms with Lambda from " << (ensemble ? "each surface's" : "the surface's")
            << " facets | z of the forms built per normal bin from the measured G1s\n";
  for (const auto& row : rows) {
    std::cout << std::setw(6) << fmt(row["theta_o_deg"].get<double>(), 1) << std::setw(6)
              << fmt(row["phi_o_deg"].get<double>(), 0) << std::setw(6)
              << fmt(row["theta_i_deg"].get<double>(), 1) << std::setw(6)
              << fmt(row["phi_i_deg"].get<double>(), 0) << std::setw(9)
              << fmt(row["g2"].get<double>()) << std::setw(9)
              << fmt(row["g2_stderr"].get<double>(), 5) << std::setw(9)
              << fmt(row["g1_o"].get<double>() * row["g1_i"].get<double>());
    for (const char* f : kForms)
      std::cout << std::setw(9) << fmt(row[std::string("smith_") + f].get<double>());
    std::cout << std::setw(9) << fmt(row["vcavity"].get<double>()) << " |";
    for (const char* f : kForms)
      std::cout << std::setw(8) << fmt(row[std::string("z_") + f + "_from_g1"], 1);
    std::cout << "\n";
  }
}

int run_measure_g2(const G2CliOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv"});
  const std::vector<double> to = parse_angle_list(o.theta_o, "--theta-o");
  const std::vector<double> po = parse_azimuth_list(o.phi_o, "--phi-o");
  const std::vector<double> ti = parse_angle_list(o.theta_i, "--theta-i");
  const std::vector<double> pi = parse_azimuth_list(o.phi_i, "--phi-i");
  require_above_horizon(to, "--theta-o");
  require_above_horizon(ti, "--theta-i");
  if (o.rays <= 0)
    throw UsageError("--rays must be a positive integer (got " + std::to_string(o.rays) + ")");
  auto t0 = std::chrono::steady_clock::now();

  G2Options go = estimator_options<G2Options>(o.rays, o.seed, g);
  go.replicates = o.replicates;
  Json j = measure_record("measure g2", o.files, g);
  j["parameters"] = {{"theta_o", o.theta_o}, {"phi_o", o.phi_o},     {"theta_i", o.theta_i},
                     {"phi_i", o.phi_i},     {"rays", o.rays},       {"seed", o.seed},
                     {"replicates", go.replicates},
                     {"normal_bins", {{"theta", go.normal_theta_bins}, {"phi", go.normal_phi_bins}}}};
  j["definitions"] = {
      {"g2", "fraction of the facets facing both o and i (o.m_f > 0, i.m_f > 0) unoccluded "
             "toward o and toward i, weighted by w_f = A_f (o.m_f + i.m_f) / 2 (points drawn "
             "with that density, two occlusion rays per point; [GeomBSDF24, eq. 16a]): "
             "symmetric in o and i, G1's projected-area weight at o = i (g2 = g1 there, [GeomBSDF24, "
             "eq. 16]) and the BRDF's A_f (i.m) at the half vector"},
      {"g1_o", "fraction of the same points and weights unoccluded toward o (g1_i: toward i)"},
      {"g2_half", "g2 of the normal bin holding the half vector (o+i)/|o+i| (half_bin_*_range_deg): "
                  "the G2(o, h, i) of a specular microfacet BRDF, to compare with the Smith forms "
                  "as they are (null when the bin holds fewer than 100 samples)"},
      {"bins", "per normal bin, the same ratios over the bin's facets facing both; front_fraction = "
               "their area / the bin's area; weight_fraction = the bin's share of sum w_f"},
      {"smith_*", "[Heitz14, eq. 20] (separable), 21 (height correlated), 22 (direction correlated), 23 "
                  "(height-direction correlated) with the van Ginneken lambda(phi) = 4.41 phi / "
                  "(4.41 phi + 1) and Lambda from the surface's facets, sum_f A_f max(0,-v.m_f) / "
                  "((v.n) A); they do not depend on m, so they equal their own area average"},
      {"smith_*_nominal", "the same with the closed-form Lambda of the surface's nominal NDF"},
      {"*_from_g1", "the four forms built in each normal bin from the bin's measured g1_o and g1_i "
                    "(Lambda = 1/G1 - 1, [Heitz14, eq. 10]), averaged over bins with the bins' weights "
                    "sum w_f; *_from_g1_diff = average of (g2 - form), *_diff_stderr its standard "
                    "error (delete-one-replicate jackknife); they "
                    "test the correlation each form assumes, free of the m-dependence of G1"},
      {"vcavity", "V-cavity G2 (Cook-Torrance) averaged over the surface's facets facing both, "
                  "weighted by w_f like the measurement"},
      {"z_*", "(g2 - model) / stderr; for models from the facets the ray-count error "
              "(g2_stderr, or g2_stderr_rays for ensembles), for nominal models the between-"
              "surface error g2_stderr of an ensemble"},
      {"stderr", o.files.size() == 1
                     ? "ray-count standard error of this one surface: the rays are split into `replicates` "
                       "independent randomized replicates (each a stratified pass with its own random "
                       "stream) and the error is that of the replicate means, sqrt(var / replicates)"
                     : "between-surface standard error (sd over surfaces / sqrt(K)); the ray-count "
                       "one is *_stderr_rays; per_surface holds each surface's own rows"}};
  Progress progress("measure g2", g.quiet);
  const std::size_t total = o.files.size() * to.size() * po.size() * ti.size() * pi.size();
  std::size_t done = 0;
  go.progress = [&](double f) { progress.update((done + f) / total); };
  TraceCounters counters;
  double build_seconds = 0;
  std::vector<Table> per_surface = measure_over_surfaces(g, o.files, [&](const Microsurface& s, std::size_t k) {
    // A V-cavity ensemble is measured groove by groove [Heitz14, Sec. 6.1], each groove an infinite
    // periodic V-groove of its own; its stored strips traced together would mask each other.
    const bool grooves = is_vcavity(s);
    if (k == 0) {
      j["surface"] = s.description;
      j["groove_by_groove"] = grooves;
      if (grooves) j["definitions"]["groove_by_groove"] = kGrooveByGroove;
    }
    std::unique_ptr<Tracer> tracer;
    FacetTable table;
    if (!grooves) {
      tracer = std::make_unique<Tracer>(s);
      build_seconds += tracer->build_seconds();
      table = build_facet_table(s, g2_normal_binning(go));
    }
    Table rows = g2_table();
    for (double p_o : po)
      for (double t_o : to)
        for (double p_i : pi)
          for (double t_i : ti) {
            const Vec3 vo = direction_from_angles(rad(t_o), rad(p_o)), vi = direction_from_angles(rad(t_i), rad(p_i));
            G2Result r = grooves ? measure_vcavity_g2(s, vo, vi, go) : measure_g2(*tracer, vo, vi, go, &table);
            counters += r.counters;
            Json& row = add_row(rows, r, s);
            row["theta_o_deg"] = t_o;  // exactly as requested
            row["phi_o_deg"] = p_o;
            row["theta_i_deg"] = t_i;
            row["phi_i_deg"] = p_i;
            ++done;
          }
    return rows;
  });
  progress.finish();
  j["build_seconds"] = build_seconds;
  put_rows(j, o.files, per_surface);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  j["wall_seconds"] = wall;
  j["total_rays"] = counters.rays;
  j["rays_per_second"] = counters.rays / wall;
  j["lost_rays"] = counters.lost_below + counters.unresolved;
  j["backface_hits"] = counters.backface_hits;
  write_record(g, o.output, j);
  if (!g.quiet) {
    std::cout << "G2 of "
              << (o.files.size() == 1 ? o.files[0] : std::to_string(o.files.size()) + " surfaces")
              << "  (" << go.rays << " area samples per direction pair"
              << (o.files.size() > 1 ? "; stderr between surfaces" : "") << ")\n";
    print_g2_table(j["rows"], o.files.size() > 1);
    std::cout << "rays lost " << counters.lost_below + counters.unresolved << ", back-face hits "
              << counters.backface_hits << ", " << fmt(counters.rays / wall / 1e6, 2)
              << " Mrays/s; wrote " << o.output << "\n";
  }
  return 0;
}

}  // namespace

void register_measure_g2(CLI::App& measure, const GlobalOptions& g) {
  auto* cmd = measure.add_subcommand(
      "g2", "Masking-shadowing G2(o, m, i) by area sampling with two occlusion rays, beside the "
            "four Smith forms and the V-cavity model");
  auto o = std::make_shared<G2CliOptions>();
  cmd->add_option("surfaces", o->files,
                  "Surface file(s). Several independent surfaces of the same statistics give rows "
                  "averaged over them with the between-surface standard error")
      ->required();
  cmd->add_option("-o,--output", o->output, "Output (.json or .csv)")->required();
  cmd->add_option("--theta-o", o->theta_o,
                  "View (outgoing) zenith angles in degrees, [0, 90): a, a,b,c or start:stop:step")
      ->required();
  cmd->add_option("--phi-o", o->phi_o, "View azimuths in degrees, same syntax")->capture_default_str();
  cmd->add_option("--theta-i", o->theta_i, "Light (incoming) zenith angles in degrees, [0, 90)")
      ->required();
  cmd->add_option("--phi-i", o->phi_i, "Light azimuths in degrees")->capture_default_str();
  add_rays_seed_options(*cmd, o->rays, o->seed, "Area samples per direction pair (two occlusion rays each)");
  add_replicates_option(*cmd, o->replicates);
  cmd->callback([o, &g] { run_measure_g2(*o, g); });
}

}  // namespace microsim::cli
