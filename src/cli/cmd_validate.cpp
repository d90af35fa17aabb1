// microsim validate [FILE... | --suite NAME] [-o OUT.json]: every applicable check of a surface
// (several files: an ensemble with the same statistics) or of a suite of presets, printed as a
// table of measured vs model with z-scores and verdicts. Exit 1 only when an exact identity fails.
#include <unistd.h>

#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "option_checks.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/api/validate_request.hpp"

#ifndef MICROSIM_DATA_DIR
#define MICROSIM_DATA_DIR ""
#endif

namespace microsim::cli {

namespace {

struct ValidateOptions {
  std::vector<std::string> files;
  std::string suite, output, surfaces_dir;
  std::string theta = "0,30,60,80", phi = "0", checks;
  long long rays = 1000000;
  std::uint64_t seed = 1;
  double significance = 0.01;
  bool theta_given = false, phi_given = false, rays_given = false, seed_given = false,
       checks_given = false, significance_given = false;
};

// Where `--suite NAME` is looked up (the library's list, with the source tree of this build).
std::vector<std::string> suite_dirs() { return suite_search_dirs(MICROSIM_DATA_DIR); }

// The options given as the library's request (the defaults of the checks where none is given).
ValidateRequest validate_request(const ValidateOptions& o, const GlobalOptions& g) {
  ValidateRequest r;
  r.surfaces = input_surface_sources(g, o.files);
  r.suite = o.suite;
  r.suite_dirs = suite_dirs();
  r.surfaces_dir = o.surfaces_dir;
  // Parsed (and checked) whether given or not, as the defaults are used for surfaces.
  AngleList theta = angle_list(o.theta, "theta");
  require_above_horizon(theta.degrees, "theta");
  AngleList phi = azimuth_list(o.phi, "phi");
  if (o.theta_given) r.theta = theta;
  if (o.phi_given) r.phi = phi;
  if (o.rays_given) r.rays = o.rays;
  if (o.seed_given) r.seed = o.seed;
  if (o.checks_given) r.checks = o.checks;
  if (o.significance_given) r.significance = o.significance;
  return r;
}

void print_validation(const ValidateOptions& o, const ValidateRun& run) {
  const validation::Result& result = run.result;
  std::cout << "validate " << (o.suite.empty() ? o.files[0] : "--suite " + o.suite) << ": "
            << result.rows.size() << " rows (groups of per-bin rows shown by their worst row)\n"
            << validation::format_table(result) << result.count("pass") << " pass, "
            << result.count("FAIL") << " FAIL, " << result.count("agrees") << " agree, "
            << result.count("deviates (finding)") << " deviate (finding), "
            << result.count("measured") << " measured only; |z| threshold "
            << fmt(result.z_threshold, 2) << " (Sidak over " << run.record["comparisons"].get<std::size_t>()
            << " z-tests, family-wise significance " << run.significance
            << "; rows with the spread of K surfaces: Student t, K - 1 dof, column |z|max)\n";
  if (!o.output.empty()) std::cout << "wrote " << o.output << "\n";
}

int run_validate(const ValidateOptions& o, const GlobalOptions& g) {
  require_surfaces_or_suite(!o.files.empty(), !o.suite.empty(), suite_dirs());
  if (!o.output.empty()) require_extension(o.output, {"json", "csv"});
  const ValidateRequest request = validate_request(o, g);
  Progress progress("validate", g.quiet);
  RunContext ctx = run_context(g);
  ctx.progress = [&](double f) { progress.update(f); };
  ctx.warning = [](const std::string& w) { std::cerr << "microsim: warning: " << w << "\n"; };
  ValidateRun run = run_validate_request(request, ctx);
  progress.finish();
  if (!o.output.empty()) {
    // The record is kept even when an identity FAILED below (exit 1 with the evidence).
    OutputTransaction record;
    write_record(g, o.output, run.record);
    if (!g.partial) record.commit();
  }
  run.generated_surfaces->commit();
  if (!g.quiet) print_validation(o, run);
  if (run.result.any_failure() && !g.partial) throw RuntimeFailure(validation_failure(run.result, o.output));
  return 0;
}

}  // namespace

void register_validate(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand(
      "validate",
      "Every applicable check of a surface (or of a suite of presets): measured vs model with "
      "z-scores and verdicts. Exit 1 only when an exact identity fails");
  auto o = std::make_shared<ValidateOptions>();
  cmd->add_option("surfaces", o->files,
                  "Surface file(s); several files = independent surfaces with the same statistics "
                  "(nominal models are then compared with the between-surface error)");
  cmd->add_option("--suite", o->suite,
                  "A suite: NAME (surfaces/suites/NAME.json) or a path to a suite file");
  cmd->add_option("-o,--output", o->output, "Write the record (.json, or .csv rows)");
  cmd->add_option("--theta", o->theta, "View zenith angles of the G1 checks (deg): a, a,b,c or start:stop:step")
      ->capture_default_str();
  cmd->add_option("--phi", o->phi, "View azimuths (deg), same syntax")->capture_default_str();
  cmd->add_option("--rays", o->rays, "Rays per estimator and direction")->capture_default_str()
      ->check(integer_in(1, kMaxRays));
  cmd->add_option("--seed", o->seed, "Random seed of the estimators")->capture_default_str()
      ->check(seed_value());
  cmd->add_option("--significance", o->significance,
                  "Family-wise false-alarm rate of the z tests (Sidak over all of them)")
      ->capture_default_str()
      ->check(number_in({0, 1, true, true}));
  cmd->add_option("--checks", o->checks, "Comma-separated checks to run (default: all applicable: "
                                         "d_identities, d_nominal, g1, g2, vndf (nominal NDF), "
                                         "bsdf_albedo (periodic))");
  cmd->add_option("--surfaces-dir", o->surfaces_dir,
                  "With --suite: keep the generated surfaces in this folder (default: a temporary "
                  "folder, removed)");
  cmd->callback([o, cmd, &g] {
    o->theta_given = cmd->count("--theta") > 0;
    o->phi_given = cmd->count("--phi") > 0;
    o->rays_given = cmd->count("--rays") > 0;
    o->seed_given = cmd->count("--seed") > 0;
    o->checks_given = cmd->count("--checks") > 0;
    o->significance_given = cmd->count("--significance") > 0;
    run_validate(*o, g);
  });
}

}  // namespace microsim::cli
