// microsim measure vndf FILE... : histogram of first-hit normals of rays along -v against the
// analytic distribution of visible normals [Heitz14, eq. 13], and a chi-square test of the VNDF
// sampler of the surface's nominal NDF.
#include <iomanip>
#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "measure_options.hpp"
#include "option_checks.hpp"
#include "ensemble.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/stats.hpp"
#include "microsim/measure/vcavity_measure.hpp"
#include "microsim/measure/vndf_measure.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim::cli {

namespace {

struct VndfCliOptions {
  std::vector<std::string> files;
  std::string output;
  std::string theta = "0:80:20", phi = "0";
  long long rays = 1000000;
  long long sampler_samples = 1000000;
  std::uint64_t seed = 1;
  int theta_bins = 18, phi_bins = 16;
};

const char* const kGrooveByGroove =
    "true for a V-cavity ensemble: [Heitz14, Sec. 6.1] made explicit, every ray picks a groove uniformly "
    "(equal macro areas) and a uniform origin on its tile and is traced on that groove alone, an "
    "infinite periodic V-groove";
const char* const kChi2Vcavity =
    "*_vcavity: the chi-square test of the hit histogram against the V-cavity model's bin "
    "probabilities over the ensemble's facets, sum_f A_f (v.m_f)+ G1_vcavity(v, m_f) ([Heitz14, eq. 13] "
    "with eq. 24), exact for separate grooves";

void print_vndf_table(const Json& rows, bool ensemble) {
  std::cout << std::setw(7) << "theta" << std::setw(6) << "phi" << std::setw(11) << "chi2/dof"
            << std::setw(10) << "p" << std::setw(9) << "max|z|" << std::setw(8) << "sidak"
            << std::setw(9) << "tv_dist" << std::setw(14) << "smith_num p" << std::setw(14)
            << "sampler p" << "\n";
  for (const auto& row : rows) {
    std::cout << cell(row["theta_deg"], 1, 7) << cell(row["phi_deg"], 0, 6);
    if (!ensemble && row["chi2"].is_number())
      std::cout << std::setw(11)
                << (fmt(row["chi2"].get<double>(), 0) + "/" + std::to_string(row["dof"].get<int>()))
                << cell(row["p_value"], 4, 10);
    else
      std::cout << std::setw(11) << "-" << std::setw(10) << "-";
    // Ensembles' z divide by the between-surface error, which can be tiny: max|z| of 10^6 and
    // more happen, and must not push the columns after it.
    std::cout << cell(row.value("max_abs_z", Json()), 2, 9) << cell(row.value("sidak_z", Json()), 2, 8)
              << cell(row.value("tv_distance", Json()), 4, 9) << cell(row.value("p_value_smith_numeric", Json()), 4, 14)
              << cell(row.value("sampler_p_value", Json()), 4, 14) << "\n";
  }
}

int run_measure_vndf(const VndfCliOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv"});
  const std::vector<double> thetas = parse_angle_list(o.theta, "--theta");
  const std::vector<double> phis = parse_azimuth_list(o.phi, "--phi");
  require_above_horizon(thetas, "--theta");
  if (o.rays <= 0)
    throw UsageError("--rays must be a positive integer (got " + std::to_string(o.rays) + ")");
  if (o.sampler_samples < 0)
    throw UsageError("--sampler-samples must be >= 0 (got " + std::to_string(o.sampler_samples) + ")");
  if (o.theta_bins < 1 || o.theta_bins > 360)
    throw UsageError("--theta-bins must be in [1, 360] (got " + std::to_string(o.theta_bins) + ")");
  if (o.phi_bins < 1 || o.phi_bins > 720)
    throw UsageError("--phi-bins must be in [1, 720] (got " + std::to_string(o.phi_bins) + ")");
  auto t0 = std::chrono::steady_clock::now();

  VndfOptions vo = estimator_options<VndfOptions>(o.rays, o.seed, g);
  vo.theta_bins = o.theta_bins;
  vo.phi_bins = o.phi_bins;
  vo.sampler_samples = static_cast<std::uint64_t>(o.sampler_samples);
  Json j = measure_record("measure vndf", o.files, g);
  j["parameters"] = {{"theta", o.theta},
                     {"phi", o.phi},
                     {"rays", o.rays},
                     {"sampler_samples", o.sampler_samples},
                     {"seed", o.seed},
                     {"replicates", nullptr},
                     {"normal_bins", {{"theta", o.theta_bins}, {"phi", o.phi_bins}, {"theta_max_deg", 90}}},
                     {"family_alpha", vo.family_alpha}};
  j["definitions"] = {
      {"dv", "histogram of the normals of front-face first hits of parallel rays along -v: "
             "(hits in bin / hits) / solid angle of the bin ([GeomBSDF24, eq. 3b], [Heitz14, eq. 13])"},
      {"dv_model", "bin average of the nominal NDF's D_v(m) = G1(v) max(0,v.m) D(m) / (v.n) "
                   "[Heitz14, eq. 13], by quadrature"},
      {"dv_smith_numeric", "Smith's D_v with the surface's own facets: sum_f in bin A_f "
                           "max(0,v.m_f) / sum_f A_f max(0,v.m_f) / solid angle"},
      {"z", "per bin (dv - dv_model) / stderr, the binomial stderr under the model (ensembles: "
            "the between-surface stderr); max_abs_z over bins holding >= 5 expected hits "
            "(ensembles: >= 0.2% of the visible normals) against sidak_z, the two-sided threshold "
            "for family_alpha Sidak-corrected over bins_tested (ensembles of K surfaces: the "
            "Student t quantile with K - 1 degrees of freedom)"},
      {"chi2", "Pearson chi-square of the hit histogram against the nominal bin probabilities "
               "(bins with >= 5 expected hits, the rest pooled), p_value its upper tail; "
               "*_smith_numeric the same against dv_smith_numeric"},
      {"sampler_*", "the same chi-square test for sampler_samples normals drawn by the nominal "
                    "NDF's VNDF sampler (models/ndf.hpp sample_visible_normal)"},
      {"replicates", "null: the ray origins are i.i.d. uniform (not stratified), so the bin "
                     "counts are multinomial and the binomial standard error is exact"},
      {"stderr", o.files.size() == 1 ? "ray-count (binomial) standard error of this one surface"
                                     : "between-surface standard error (sd / sqrt(K)); "
                                       "per_surface holds each surface's rows"}};
  Progress progress("measure vndf", g.quiet);
  const std::size_t total = o.files.size() * thetas.size() * phis.size();
  std::size_t done = 0;
  vo.progress = [&](double f) { progress.update((done + f) / total); };
  TraceCounters counters;
  std::uint64_t lost = 0;
  std::vector<Table> per_surface = measure_over_surfaces(g, o.files, [&](const Microsurface& s, std::size_t k) {
    // A V-cavity ensemble is measured groove by groove [Heitz14, Sec. 6.1], each groove an infinite
    // periodic V-groove of its own; its stored strips traced together would mask each other.
    const bool grooves = is_vcavity(s);
    if (k == 0) {
      j["surface"] = s.description;
      j["groove_by_groove"] = grooves;
      if (grooves) {
        j["definitions"]["groove_by_groove"] = kGrooveByGroove;
        j["definitions"]["chi2_vcavity"] = kChi2Vcavity;
      }
    }
    const DirectionBinning bins = vndf_binning(vo);
    std::unique_ptr<Tracer> tracer;
    FacetTable table;
    if (!grooves) {
      tracer = std::make_unique<Tracer>(s);
      table = build_facet_table(s, bins);
    }
    Table rows = vndf_table(vo.family_alpha);
    for (double p : phis)
      for (double t : thetas) {
        const Vec3 v = direction_from_angles(rad(t), rad(p));
        VndfResult r = grooves ? measure_vcavity_vndf(s, v, vo) : measure_vndf(*tracer, v, vo, &table);
        counters += r.counters;
        lost += !s.macro().finite_object() ? r.counters.lost_below + r.counters.unresolved : r.counters.unresolved;
        std::optional<SamplerTest> sampler;
        // The sampler does not depend on the surface: tested once, with the first one.
        if (s.nominal && vo.sampler_samples > 0 && k == 0)
          sampler = test_vndf_sampler(*s.nominal, v, vo.sampler_samples, bins, vo.seed,
                                      vo.family_alpha);
        Json& row = add_row(rows, r, s, vo, sampler);
        if (grooves) {  // the V-cavity model's VNDF over the ensemble's own facets (exact here)
          const GofResult gof =
              histogram_gof(r.bin_hits, r.hits, vcavity_vndf_probabilities(s, r.v, r.binning), vo.family_alpha);
          row["chi2_vcavity"] = gof.chi2;
          row["dof_vcavity"] = gof.dof;
          row["p_value_vcavity"] = gof.p_value;
          row["max_abs_z_vcavity"] = gof.max_abs_z;
          row["pass_vcavity"] = gof.pass();
        }
        row["theta_deg"] = t;
        row["phi_deg"] = p;
        ++done;
      }
    return rows;
  });
  progress.finish();
  put_rows(j, o.files, per_surface);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  j["wall_seconds"] = wall;
  j["total_rays"] = counters.rays;
  j["lost_rays"] = lost;
  j["backface_hits"] = counters.backface_hits;
  write_record(g, o.output, j);
  if (!g.quiet) {
    std::cout << "VNDF of "
              << (o.files.size() == 1 ? o.files[0] : std::to_string(o.files.size()) + " surfaces")
              << "  (" << vo.rays << " rays per direction; " << o.theta_bins << " x "
              << o.phi_bins << " normal bins)\n";
    print_vndf_table(j["rows"], o.files.size() > 1);
    std::cout << "rays lost " << lost << ", back-face hits "
              << counters.backface_hits << "; wrote " << o.output << "\n";
  }
  return 0;
}

}  // namespace

void register_measure_vndf(CLI::App& measure, const GlobalOptions& g) {
  auto* cmd = measure.add_subcommand(
      "vndf", "Distribution of visible normals: first-hit normals of rays along -v against the "
              "analytic D_v, and a chi-square test of the nominal NDF's VNDF sampler");
  auto o = std::make_shared<VndfCliOptions>();
  cmd->add_option("surfaces", o->files,
                  "Surface file(s); several independent surfaces give between-surface errors")
      ->required();
  cmd->add_option("-o,--output", o->output, "Output (.json or .csv)")->required();
  cmd->add_option("--theta", o->theta, "View zenith angles in degrees, [0, 90): a, a,b,c or start:stop:step")
      ->capture_default_str();
  cmd->add_option("--phi", o->phi, "View azimuths in degrees, same syntax")->capture_default_str();
  add_rays_seed_options(*cmd, o->rays, o->seed, "Rays per direction");
  cmd->add_option("--sampler-samples", o->sampler_samples,
                  "Samples for the chi-square test of the nominal NDF's VNDF sampler (0: skip)")
      ->capture_default_str()
      ->check(integer_in(0, kMaxRays));
  cmd->add_option("--theta-bins", o->theta_bins, "Normal bins in theta_m over [0, 90] degrees")
      ->capture_default_str()
      ->check(integer_in(1, 360));
  cmd->add_option("--phi-bins", o->phi_bins, "Normal bins in phi_m over [0, 360) degrees")
      ->capture_default_str()
      ->check(integer_in(1, 720));
  cmd->callback([o, &g] { run_measure_vndf(*o, g); });
}

}  // namespace microsim::cli
