// validate as a request of the library: every applicable check of a surface, an ensemble or a
// suite of presets, measured against the models with verdicts, and its record.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "microsim/api/angle_list.hpp"
#include "microsim/api/run_context.hpp"
#include "microsim/api/surface_input.hpp"
#include "microsim/io/output.hpp"
#include "microsim/validate/validate.hpp"

namespace microsim {

struct ValidateRequest {
  // The surfaces (several: independent surfaces with the same statistics), or a suite.
  std::vector<SurfaceInput> surfaces;
  std::string suite;                    // a suite NAME (looked up in suite_dirs) or a suite file
  std::vector<std::string> suite_dirs;  // where a suite NAME is looked up, in order
  std::string surfaces_dir;             // keeps a suite's generated surfaces ("": a temporary folder)
  // The checks' options: for surfaces always (the defaults when not given), for a suite only
  // when given (its entries' own otherwise).
  std::optional<AngleList> theta, phi;
  std::optional<long long> rays;
  std::optional<std::uint64_t> seed;
  std::optional<std::string> checks;  // comma-separated check names
  std::optional<double> significance;  // family-wise (the suite's own, or 0.01, when not given)
  // ParameterError naming what is missing, contradictory or out of range.
  void check() const;
};

// Where a suite NAME is looked up: ./surfaces/suites, then beside the executable
// (BUILD/../surfaces/suites), then data_dir/suites (the source tree's surfaces/ of the build).
std::vector<std::string> suite_search_dirs(const std::string& data_dir);

// UsageError unless exactly one of surfaces and suite is given; it lists the suites found.
void require_surfaces_or_suite(bool surfaces, bool suite, const std::vector<std::string>& suite_dirs);

struct ValidateRun {
  Json record;  // command "validate"
  validation::Result result;
  double significance = 0.01;
  // The surfaces generated into surfaces_dir: placed, kept once this is committed (after the
  // record is written), removed if it ends uncommitted.
  std::unique_ptr<OutputTransaction> generated_surfaces;
};

// Checks the request, loads or generates the surfaces and runs the checks.
ValidateRun run_validate_request(const ValidateRequest& r, const RunContext& ctx);

// "N exact identities FAILED (rows with verdict FAIL in OUTPUT)" (without " in" when the record
// is not written).
std::string validation_failure(const validation::Result& result, const std::string& output);

}  // namespace microsim
