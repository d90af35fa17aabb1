#include "microsim/api/validate_request.hpp"

#include <chrono>
#include <filesystem>

#include "microsim/api/request_checks.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {

namespace {

namespace fs = std::filesystem;

const char* const kDefaultTheta = "0,30,60,80";

// The options the request gives the checks (the defaults where it gives none).
validation::Options given_options(const ValidateRequest& r, const RunContext& ctx) {
  validation::Options o;
  o.theta_deg = r.theta ? r.theta->degrees : angle_list(kDefaultTheta, "theta").degrees;
  o.phi_deg = r.phi ? r.phi->degrees : std::vector<double>{0};
  o.rays = static_cast<std::uint64_t>(r.rays.value_or(1000000));
  o.seed = r.seed.value_or(1);
  // An empty list would run every check: a list given is a list of at least one check.
  if (r.checks) o.checks = split_items(*r.checks, ',', "{checks}");
  o.split = ctx.split;  // shards and MPI ranks
  return o;
}

// A suite entry's options with the request's overrides (those given).
void apply_overrides(const ValidateRequest& r, const validation::Options& given, validation::Options& o) {
  if (r.theta) o.theta_deg = given.theta_deg;
  if (r.phi) o.phi_deg = given.phi_deg;
  if (r.rays) o.rays = given.rays;
  if (r.seed) o.seed = given.seed;
  if (r.checks) o.checks = given.checks;
}

// The one set of the request's surfaces (named after the first; labelled by file name when
// several).
validation::SurfaceSet surface_set(const ValidateRequest& r, const validation::Options& options) {
  validation::SurfaceSet set;
  set.name = fs::path(r.surfaces[0].name).stem().string();
  for (const SurfaceInput& s : r.surfaces) {
    set.surfaces.push_back(*s.get());
    set.labels.push_back(r.surfaces.size() > 1 ? fs::path(s.name).filename().string() : "");
  }
  set.options = options;
  return set;
}

// The folder a suite's surfaces are generated into: surfaces_dir, or a temporary one (`temp`).
fs::path generation_folder(const ValidateRequest& r, std::unique_ptr<TemporaryFolder>& temp) {
  if (!r.surfaces_dir.empty()) {
    if (!create_output_folder(r.surfaces_dir))
      throw ParameterError("{surfaces_dir} " + literal_text(r.surfaces_dir) + ": cannot create the folder");
    return r.surfaces_dir;
  }
  temp = std::make_unique<TemporaryFolder>("microsim-validate");
  return temp->path();
}

// One set of an entry: its surfaces generated into `dir`, one per seed; the files into
// `generated`.
validation::SurfaceSet entry_set(const validation::SuiteEntry& e, const std::string& suite_file, const fs::path& dir,
                                 const RunContext& ctx, Json& generated) {
  validation::SurfaceSet set;
  set.name = e.name;
  set.options = e.options;
  std::vector<std::optional<std::uint64_t>> seeds;
  for (auto s : e.seeds) seeds.emplace_back(s);
  if (seeds.empty()) seeds.emplace_back(std::nullopt);
  for (const auto& seed : seeds) {
    const std::string file =
        (dir / (e.name + (seed ? "-seed" + std::to_string(*seed) : "") + "." + e.format)).string();
    std::vector<std::string> warnings;
    set.surfaces.push_back(validation::generate_entry(e, suite_file, seed, file, &warnings));
    for (const auto& w : warnings)
      if (ctx.warning) ctx.warning(w);
    set.labels.push_back(seed ? "seed " + std::to_string(*seed) : "");
    generated.push_back({{"entry", e.name}, {"file", file}});
  }
  return set;
}

Json overrides_json(const ValidateRequest& r) {
  return {{"theta", r.theta ? Json(r.theta->text) : Json(nullptr)},
          {"phi", r.phi ? Json(r.phi->text) : Json(nullptr)},
          {"rays", r.rays ? Json(*r.rays) : Json(nullptr)},
          {"seed", r.seed ? Json(*r.seed) : Json(nullptr)},
          {"checks", r.checks ? Json(*r.checks) : Json(nullptr)}};
}

}  // namespace

std::vector<std::string> suite_search_dirs(const std::string& data_dir) {
  std::vector<std::string> dirs = {"surfaces/suites"};
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) dirs.push_back((exe.parent_path().parent_path() / "surfaces" / "suites").string());
  if (!data_dir.empty()) dirs.push_back(data_dir + "/suites");
  return dirs;
}

void require_surfaces_or_suite(bool surfaces, bool suite, const std::vector<std::string>& suite_dirs) {
  if (surfaces != suite) return;
  std::string known;
  for (const auto& d : suite_dirs)
    for (const auto& n : validation::list_suites(d))
      if (known.find(n) == std::string::npos) known += (known.empty() ? "" : ", ") + n;
  throw ParameterError("validate: give either surface FILE(s) or {suite} NAME (known suites: " +
                       literal_text(known.empty() ? std::string("none") : known) + ")");
}

void ValidateRequest::check() const {
  require_surfaces_or_suite(!surfaces.empty(), !suite.empty(), suite_dirs);
  if (significance && !(*significance > 0 && *significance < 1))
    throw ParameterError("{significance} must be in (0, 1) (got " + fixed_text(*significance, 4) + ")");
  if (rays) require_integer_in(*rays, 1, kMaxRays, "rays");
  if (theta) require_above_horizon(theta->degrees, "theta");
}

ValidateRun run_validate_request(const ValidateRequest& r, const RunContext& ctx) {
  r.check();
  const validation::Options given = given_options(r, ctx);
  const auto t0 = std::chrono::steady_clock::now();
  ValidateRun run;
  run.record = record_header("validate", ctx);
  run.significance = r.significance.value_or(0.01);
  std::vector<validation::SurfaceSet> sets;
  std::unique_ptr<TemporaryFolder> temp;  // removed at the end (or on interrupt) unless surfaces_dir
  run.generated_surfaces = std::make_unique<OutputTransaction>();
  if (!r.surfaces.empty()) {
    sets.push_back(surface_set(r, given));
    Json files = Json::array();
    for (const SurfaceInput& s : r.surfaces) files.push_back(s.name);
    run.record["files"] = files;
  } else {
    const std::string path = validation::find_suite(r.suite, r.suite_dirs);
    validation::Suite suite = validation::load_suite(path);
    validation::require_safe_entry_names(suite, path);
    if (!r.significance) run.significance = suite.significance;
    run.record["suite"] = {{"name", suite.name}, {"file", path}, {"description", suite.description}};
    const fs::path dir = generation_folder(r, temp);
    Json generated = Json::array();
    for (const auto& e : suite.entries) {
      sets.push_back(entry_set(e, path, dir, ctx, generated));
      apply_overrides(r, given, sets.back().options);
      sets.back().options.split = ctx.split;
    }
    if (!temp) run.record["surface_files"] = generated;
  }
  run.record["parameters"] = {{"significance", run.significance}, {"overrides", overrides_json(r)}};
  run.result = validation::run(sets, run.significance, ctx.progress);
  temp.reset();
  run.record.update(validation::result_to_json(run.result));
  run.record["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return run;
}

std::string validation_failure(const validation::Result& result, const std::string& output) {
  return std::to_string(result.count("FAIL")) + " exact identities FAILED (rows with verdict FAIL" +
         (output.empty() ? "" : " in " + output) + ")";
}

}  // namespace microsim
