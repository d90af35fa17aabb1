// microsim measure g1 FILE... : masking by ray casting and area sampling, beside Smith.
#include <iomanip>
#include <memory>
#include <iostream>

#include "cli_common.hpp"
#include "measure_options.hpp"
#include "option_checks.hpp"
#include "commands.hpp"
#include "ensemble.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/g1_views.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim::cli {

namespace {

const char* const kVcavityDefinition =
    "[Heitz14, Sec. 6.1] made explicit: each groove of the ensemble (normals m, m' drawn from "
    "(n.m) D(m)) is traced on its own as an infinite periodic V-groove; ray casting uses the "
    "same number of rays per groove (equal macro areas), area sampling draws points over the "
    "whole ensemble by front-facing projected area; counts are pooled per normal bin. "
    "vcavity_numeric is [Heitz14, eq. 24] on the same normals";

void print_g1_table(const Json& rows, bool ensemble) {
  std::cout << std::setw(7) << "theta" << std::setw(6) << "phi" << std::setw(10) << "g1"
            << std::setw(10) << "stderr" << std::setw(10) << "raycast" << std::setw(10)
            << "smith_num" << std::setw(8) << "z_num" << std::setw(10) << "smith_nom"
            << std::setw(10) << "rel_dev" << std::setw(9) << (ensemble ? "z_nom" : "vis_ar")
            << std::setw(8) << (ensemble ? "" : "max|z|") << "\n";
  for (const auto& row : rows) {
    std::cout << std::setw(7) << fmt(row["theta_deg"].get<double>(), 1) << std::setw(6)
              << fmt(row["phi_deg"].get<double>(), 0) << std::setw(10)
              << fmt(row["g1"].get<double>()) << std::setw(10)
              << fmt(row["g1_stderr"].get<double>(), 5) << std::setw(10)
              << fmt(row["g1_raycast"].get<double>()) << std::setw(10)
              << fmt(row["smith_numeric"].get<double>()) << std::setw(8)
              << fmt(row["z_numeric"], 2);
    if (!row["smith_nominal"].is_null())
      std::cout << std::setw(10) << fmt(row["smith_nominal"].get<double>()) << std::setw(9)
                << fmt(100 * row["rel_dev_nominal"].get<double>(), 2) << "%";
    else
      std::cout << std::setw(10) << "-" << std::setw(10) << "-";
    if (ensemble)
      std::cout << std::setw(9)
                << (row["z_nominal"].is_null() ? std::string("-") : fmt(row["z_nominal"].get<double>(), 2));
    else
      std::cout << std::setw(9) << fmt(row["visible_area_ratio"].get<double>()) << std::setw(8)
                << fmt(row["max_abs_z_estimators"].get<double>(), 2);
    std::cout << "\n";
  }
}

}  // namespace

int run_measure_g1(const MeasureOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv"});
  std::vector<double> thetas = parse_angle_list(o.theta, "--theta");
  std::vector<double> phis = parse_azimuth_list(o.phi, "--phi");
  for (double t : thetas)
    if (!(t >= 0 && t <= 180) || t == 90)
      throw UsageError("--theta must be in [0, 90) degrees, or (90, 180] for the undersurface of a "
                       "mesh (got " + fmt(t, 2) + ")");
  if (o.rays <= 0) throw UsageError("--rays must be a positive integer (got " + std::to_string(o.rays) + ")");
  std::vector<std::string> files = {o.surface};
  files.insert(files.end(), o.extra_surfaces.begin(), o.extra_surfaces.end());
  auto t0 = std::chrono::steady_clock::now();
  G1Options go = estimator_options<G1Options>(o.rays, o.seed, g);
  go.replicates = o.replicates;
  Json j = measure_record("measure g1", files, g);
  j["surface"] = nullptr;  // the first surface's description (filled below, kept in this place)
  j["parameters"] = {{"theta", o.theta}, {"phi", o.phi}, {"rays", o.rays}, {"seed", o.seed},
                     {"replicates", go.replicates},
                     {"normal_bins", {{"theta", go.normal_theta_bins}, {"phi", go.normal_phi_bins}}}};
  j["definitions"] = {
      {"g1", "area sampling: fraction of points, drawn by projected area A_f max(0,v.m_f), "
             "unoccluded toward v (estimator b of docs/theory/masking.md)"},
      {"g1_raycast", "visible projected area of first hits along -v / sum_f A_f max(0,v.m_f) "
                     "(estimator a)"},
      {"visible_area_ratio", "visible projected area / ((v.n) A); visible_projected_area is the "
                             "same in absolute units, macro_projected_area = |v.n| A"},
      {"smith_numeric", "1/(1+Lambda), Lambda = sum_f A_f max(0,-v.m_f) / ((v.n) A)"},
      {"smith_nominal", "Smith G1 of the generator's nominal NDF ([Heitz14, eq. 11] with alpha_o); "
                        "undersurface rows: at -v"},
      {"bins", "per normal bin: g1, g1_raycast, smith_numeric (1/(1+lambda_numeric) for "
               "front-facing bins) and vcavity_numeric ([Heitz14, eq. 24] averaged over the bin's facets "
               "by front-facing projected area); bins_mad_* and bins_chi2_* summarise the "
               "deviation of g1 from each model over the bins"},
      {"undersurface", "theta > 90 (meshes): g1 is the explicit measurement of the undersurface "
                       "(the sheet with reversed normals seen from v); g1_reverse_v and "
                       "g1_reflect_v are the surface's own G1 at -v and at v reflected across the "
                       "macrosurface, the two approximations of [GeomBSDF24, 'Inherent Assumptions']"},
      {"eq_2b", "the visible_area_ratio at theta = 0 is [GeomBSDF24, eq. 2b], int (n.m) G1(n,m) D(m) dm; "
                "1 for a valid periodic microsurface"},
      {"z_numeric", "(g1 - smith_numeric) / the ray-count error (g1_stderr; ensembles: "
                    "g1_stderr_rays), since the model comes from each surface's own facets; "
                    "z_nominal and p_nominal (ensembles) use the between-surface error and "
                    "Student t with K - 1 degrees of freedom; a zero error gives a null z"},
      {"stderr", files.size() == 1
                     ? "ray-count standard error of this one surface: the rays are split into `replicates` "
                       "independent randomized replicates (each a stratified pass with its own random "
                       "stream) and the error is that of the replicate means, sqrt(var / replicates)"
                     : "between-surface standard error (sd over surfaces / sqrt(K)); the ray-count "
                       "one is *_stderr_rays; per_surface holds each surface's own rows"}};
  Progress progress("measure g1", g.quiet);
  const std::size_t total = files.size() * thetas.size() * phis.size();
  TraceCounters counters;
  double build_seconds = 0;
  bool periodic = true;  // every ray from above meets the surface (not a finite object)
  std::vector<Vec3> views;
  for (double p : phis)
    for (double t : thetas) views.push_back(direction_from_angles(rad(t), rad(p)));
  std::vector<Table> per_surface = measure_over_surfaces(g, files, [&](const Microsurface& s, std::size_t k) {
    const double before = static_cast<double>(k * views.size());
    G1Views m = measure_g1_views(s, views, go, [&](double done) { progress.update((before + done) / total); });
    if (k == 0) {
      j["surface"] = s.description;
      periodic = !s.macro().finite_object();
      if (m.vcavity) j["definitions"]["vcavity"] = kVcavityDefinition;
    }
    counters += m.counters;
    build_seconds += m.build_seconds;
    std::size_t i = 0;
    for (double p : phis)
      for (double t : thetas) {
        m.table.rows[i]["theta_deg"] = t;  // exactly as requested (no round trip through radians)
        m.table.rows[i++]["phi_deg"] = p;
      }
    return std::move(m.table);
  });
  progress.finish();
  j["build_seconds"] = build_seconds;
  put_rows(j, files, per_surface);
  double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  j["wall_seconds"] = wall;
  j["total_rays"] = counters.rays;
  j["rays_per_second"] = counters.rays / wall;
  // Finite objects: window rays passing beside the object are misses, not losses.
  j["lost_rays"] = periodic ? counters.lost_below + counters.unresolved : counters.unresolved;
  if (!periodic) j["missed_rays"] = counters.lost_below;
  j["backface_hits"] = counters.backface_hits;
  write_record(g, o.output, j);
  if (!g.quiet) {
    std::cout << "G1 of " << (files.size() == 1 ? files[0] : std::to_string(files.size()) + " surfaces")
              << "  (" << go.rays << " rays per estimator and direction"
              << (files.size() > 1 ? "; stderr between surfaces" : "") << ")\n";
    print_g1_table(j["rows"], files.size() > 1);
    std::cout << "rays lost " << (periodic ? counters.lost_below + counters.unresolved : counters.unresolved)
              << (periodic ? std::string() : ", rays missing the object " + std::to_string(counters.lost_below))
              << ", back-face hits "
              << counters.backface_hits << ", " << fmt(counters.rays / wall / 1e6, 2)
              << " Mrays/s; wrote " << o.output << "\n";
  }
  return 0;
}

void register_measure_g1(CLI::App& measure, const GlobalOptions& g) {
  auto* g1 = measure.add_subcommand("g1", "Masking G1 per direction: ray casting and area sampling, beside Smith");
  auto mo = std::make_shared<MeasureOptions>();
  auto files = std::make_shared<std::vector<std::string>>();
  g1->add_option("surfaces", *files,
                 "Surface file(s). Several independent surfaces of the same statistics (e.g. "
                 "seeds) give rows averaged over them with the between-surface standard error")
      ->required();
  g1->add_option("-o,--output", mo->output, "Output (.json or .csv)")->required();
  g1->add_option("--theta", mo->theta, "View zenith angles in degrees: a, a,b,c or start:stop:step")->capture_default_str();
  g1->add_option("--phi", mo->phi, "View azimuths in degrees, same syntax")->capture_default_str();
  add_rays_seed_options(*g1, mo->rays, mo->seed, "Rays per estimator and direction");
  add_replicates_option(*g1, mo->replicates);
  g1->callback([mo, files, &g] {
    mo->surface = files->front();
    mo->extra_surfaces.assign(files->begin() + 1, files->end());
    run_measure_g1(*mo, g);
  });
}

}  // namespace microsim::cli
