// microsim validate [FILE... | --suite NAME] [-o OUT.json]: every applicable check of a surface
// (several files: an ensemble with the same statistics) or of a suite of presets, printed as a
// table of measured vs model with z-scores and verdicts. Exit 1 only when an exact identity fails.
#include <unistd.h>

#include <filesystem>
#include <optional>
#include <sstream>
#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "option_checks.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/validate/validate.hpp"

#ifndef MICROSIM_DATA_DIR
#define MICROSIM_DATA_DIR ""
#endif

namespace microsim::cli {

namespace {

namespace fs = std::filesystem;

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

// Where `--suite NAME` is looked up: ./surfaces/suites, then beside the executable
// (BUILD/../surfaces/suites), then the source tree the binary was built from.
std::vector<std::string> suite_dirs() {
  std::vector<std::string> dirs = {"surfaces/suites"};
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) dirs.push_back((exe.parent_path().parent_path() / "surfaces" / "suites").string());
  if (std::string(MICROSIM_DATA_DIR).size() > 0) dirs.push_back(std::string(MICROSIM_DATA_DIR) + "/suites");
  return dirs;
}


int run_validate(ValidateOptions o, const GlobalOptions& g) {
  if (o.files.empty() == o.suite.empty())
    throw UsageError("validate: give either surface FILE(s) or --suite NAME (known suites: " +
                     [] {
                       std::string s;
                       for (const auto& d : suite_dirs())
                         for (const auto& n : validation::list_suites(d))
                           if (s.find(n) == std::string::npos) s += (s.empty() ? "" : ", ") + n;
                       return s.empty() ? std::string("none") : s;
                     }() + ")");
  if (!o.output.empty()) require_extension(o.output, {"json", "csv"});
  if (!(o.significance > 0 && o.significance < 1))
    throw UsageError("--significance must be in (0, 1) (got " + fmt(o.significance, 4) + ")");
  if (o.rays <= 0) throw UsageError("--rays must be a positive integer (got " + std::to_string(o.rays) + ")");
  // Command-line overrides of the checks' options (for FILE always; for a suite when given).
  validation::Options cli_options;
  cli_options.theta_deg = parse_angle_list(o.theta, "--theta");
  require_above_horizon(cli_options.theta_deg, "--theta");
  cli_options.phi_deg = parse_azimuth_list(o.phi, "--phi");
  cli_options.rays = static_cast<std::uint64_t>(o.rays);
  cli_options.seed = o.seed;
  // An empty --checks would run every check: a list given is a list of at least one check.
  if (o.checks_given) cli_options.checks = split_items(o.checks, ',', "--checks");
  auto apply_overrides = [&](validation::Options& opt) {
    if (o.theta_given) opt.theta_deg = cli_options.theta_deg;
    if (o.phi_given) opt.phi_deg = cli_options.phi_deg;
    if (o.rays_given) opt.rays = cli_options.rays;
    if (o.seed_given) opt.seed = cli_options.seed;
    if (o.checks_given) opt.checks = cli_options.checks;
  };

  auto t0 = std::chrono::steady_clock::now();
  Json j = run_header("validate", g);
  std::vector<validation::SurfaceSet> sets;
  double significance = o.significance;
  std::unique_ptr<TemporaryFolder> temp_dir;  // removed at the end (or on interrupt) unless --surfaces-dir
  // The surfaces generated into --surfaces-dir (and the folders created for them) are placed as
  // they are generated and kept once the run has ended; a failure or an interrupt before that
  // removes them.
  OutputTransaction generated_surfaces;
  if (!o.files.empty()) {
    validation::SurfaceSet set;
    set.name = fs::path(o.files[0]).stem().string();
    for (const auto& f : o.files) {
      set.surfaces.push_back(input_surface(g, f));
      set.labels.push_back(o.files.size() > 1 ? fs::path(f).filename().string() : "");
    }
    set.options = cli_options;
    set.options.split = g.split;  // shards and MPI ranks (scaleout.hpp)
    sets.push_back(std::move(set));
    j["files"] = o.files;
  } else {
    const std::string path = validation::find_suite(o.suite, suite_dirs());
    validation::Suite suite = validation::load_suite(path);
    validation::require_safe_entry_names(suite, path);
    if (!o.significance_given) significance = suite.significance;
    j["suite"] = {{"name", suite.name}, {"file", path}, {"description", suite.description}};
    fs::path dir;
    if (!o.surfaces_dir.empty()) {
      dir = o.surfaces_dir;
      if (!create_output_folder(o.surfaces_dir))
        throw UsageError("--surfaces-dir " + o.surfaces_dir + ": cannot create the folder");
    } else {
      temp_dir = std::make_unique<TemporaryFolder>("microsim-validate");
      dir = temp_dir->path();
    }
    Json generated = Json::array();
    {
      for (const auto& e : suite.entries) {
        validation::SurfaceSet set;
        set.name = e.name;
        set.options = e.options;
        apply_overrides(set.options);
        set.options.split = g.split;  // shards and MPI ranks (scaleout.hpp)
        const std::string ext = e.format;
        std::vector<std::optional<std::uint64_t>> seeds;
        for (auto s : e.seeds) seeds.emplace_back(s);
        if (seeds.empty()) seeds.emplace_back(std::nullopt);
        for (const auto& seed : seeds) {
          const std::string file =
              (dir / (e.name + (seed ? "-seed" + std::to_string(*seed) : "") + "." + ext)).string();
          std::vector<std::string> warnings;
          set.surfaces.push_back(validation::generate_entry(e, path, seed, file, &warnings));
          for (const auto& w : warnings) std::cerr << "microsim: warning: " << w << "\n";
          set.labels.push_back(seed ? "seed " + std::to_string(*seed) : "");
          generated.push_back({{"entry", e.name}, {"file", file}});
        }
        sets.push_back(std::move(set));
      }
    }
    if (!temp_dir) j["surface_files"] = generated;
  }
  j["parameters"] = {{"significance", significance},
                     {"overrides", {{"theta", o.theta_given ? Json(o.theta) : Json(nullptr)},
                                    {"phi", o.phi_given ? Json(o.phi) : Json(nullptr)},
                                    {"rays", o.rays_given ? Json(o.rays) : Json(nullptr)},
                                    {"seed", o.seed_given ? Json(o.seed) : Json(nullptr)},
                                    {"checks", o.checks_given ? Json(o.checks) : Json(nullptr)}}}};

  Progress progress("validate", g.quiet);
  validation::Result result = validation::run(sets, significance, [&](double f) { progress.update(f); });
  progress.finish();
  temp_dir.reset();
  j.update(validation::result_to_json(result));
  j["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.output.empty()) {
    // The record is kept even when an identity FAILED below (exit 1 with the evidence).
    OutputTransaction record;
    write_record(g, o.output, j);
    if (!g.partial) record.commit();
  }
  generated_surfaces.commit();
  if (!g.quiet) {
    std::cout << "validate " << (o.suite.empty() ? o.files[0] : "--suite " + o.suite) << ": "
              << result.rows.size() << " rows (groups of per-bin rows shown by their worst row)\n"
              << validation::format_table(result) << result.count("pass") << " pass, "
              << result.count("FAIL") << " FAIL, " << result.count("agrees") << " agree, "
              << result.count("deviates (finding)") << " deviate (finding), "
              << result.count("measured") << " measured only; |z| threshold "
              << fmt(result.z_threshold, 2) << " (Sidak over " << j["comparisons"].get<std::size_t>()
              << " z-tests, family-wise significance " << significance
              << "; rows with the spread of K surfaces: Student t, K - 1 dof, column |z|max)\n";
    if (!o.output.empty()) std::cout << "wrote " << o.output << "\n";
  }
  if (result.any_failure() && !g.partial)
    throw RuntimeFailure(std::to_string(result.count("FAIL")) +
                         " exact identities FAILED (rows with verdict FAIL" +
                         (o.output.empty() ? "" : " in " + o.output) + ")");
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
