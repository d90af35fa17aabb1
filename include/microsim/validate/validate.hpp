// Validation: every applicable check of a surface (or of an ensemble of surfaces with the same
// statistics), as rows of measured vs model with standard errors, z-scores and verdicts.
//
// A check is one function that appends rows (see `checks()`): d_identities, d_nominal, g1, g2,
// vndf, bsdf_albedo; adding a quantity is adding one Check to the registry in
// src/validate/checks.cpp.
//
// Kinds of rows and verdict rules (also written into every JSON record, "verdict_rules"):
//   identity       an exact identity measured by Monte Carlo (two estimators of the same quantity,
//                  or a consequence of geometry such as "a periodic tile is hit by every ray").
//                  z = (measured - model) / stderr; verdict "pass" when |z| <= z_threshold,
//                  "FAIL" otherwise. z_threshold is Sidak-corrected over every z-tested row of
//                  the run: a family-wise false-alarm rate `significance` (default 1%). Rows
//                  whose error is the spread of K surfaces (`dof` = K - 1) use the Student t
//                  quantile with K - 1 degrees of freedom at the same per-row rate, the others
//                  the normal quantile.
//   deterministic  an exact identity computed without sampling ([GeomBSDF24, eq. 1b, 1c] from the facets):
//                  "pass" when |measured - model| <= tolerance (a bound on double rounding of the
//                  facet sums), "FAIL" otherwise; z is null.
//   model          an approximate model (Smith, V-cavity, the nominal NDF the generator aimed
//                  at): "agrees" when |z| <= z_threshold, "deviates (finding)" otherwise. A
//                  deviation is a result about the model, never an error. A nominal model (the
//                  statistics the generator aimed at) is a model row only over an ensemble of
//                  surfaces with the between-surface error; for one surface it is an info row.
//                  Each z-tested row is counted once: on a periodic tile `g1 vs g1_raycast`
//                  repeats `g1 vs smith_numeric` (every ray hits once) and is an info row.
//   info           a measurement without a model or without an error bar: verdict "measured".
// `microsim validate` exits 1 only when a row says "FAIL".
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/measure/shards.hpp"
#include "microsim/surface/microsurface.hpp"
#include "microsim/surface/surface_spec.hpp"

namespace microsim::validation {

enum class Kind { Identity, Deterministic, Model, Info };
const char* to_string(Kind k);

struct Row {
  std::string quantity;    // what is measured: "g1", "g1_bin", "d_ring", "eq_1b_x"...
  std::string model_name;  // what it is compared with: "smith_numeric", "g1_raycast", "one"...
  std::string condition;   // human readable: "beckmann-0.5 seed 2, theta 60 deg"
  std::string entry;       // suite entry (or file) the row belongs to
  std::string group;       // rows of one group are collapsed into one line of the printed table
  std::string reference;   // where the identity or model comes from: "[GeomBSDF24, eq. 1b]"
  std::string error;       // kind of standard error: rays, surfaces, blocks, rounding
  Kind kind = Kind::Info;
  double measured = 0;
  std::optional<double> stderr_;  // none: no error bar
  std::optional<double> model;    // none: nothing to compare with
  double tolerance = 0;           // deterministic rows: accepted |measured - model|
  std::optional<int> dof;         // error from K surfaces: K - 1 (Student t); none: normal
  // Filled by assign_verdicts.
  std::optional<double> z, rel_dev;
  std::optional<double> threshold;  // |z| threshold of this row (z-tested rows)
  std::string verdict;
  Json extra = Json::object();  // fields for plots (theta_deg, theta_m_range_deg, ...)
};

// Two-sided normal quantile with a Sidak correction: |z| above it has probability `alpha`
// that any of `k` independent null comparisons crosses it.
double sidak_z(double alpha, std::size_t k);

// Computes z, rel_dev, thresholds and verdicts for all rows; returns the normal z threshold
// (rows with `dof` use the Student t threshold at the same per-row rate).
double assign_verdicts(std::vector<Row>& rows, double significance);

// Binomial proportion k/n with the standard error of p~ = (k + 1/2)/(n + 1): never zero, so
// a bin where all n samples were visible still carries an error of order 1/n (the plain
// binomial error is 0 there and would turn any model difference into an infinite z).
Estimate proportion(std::uint64_t k, std::uint64_t n);

// The energy-conservation row of a mirror BSDF run: every path leaves up or down, so the
// fraction that left, (paths - lost - unterminated) / paths, is exactly 1; a lost path is a
// tracer leak (rays slipping through at rounding level, measured at most 1 in 10^6).
// Deterministic: pass when at most max(1, kMaxLostFraction paths) paths did not leave (no error
// bar made from the lost count itself, whose z ~ sqrt(lost) passes almost any loss).
constexpr double kMaxLostFraction = 1e-5;
Row albedo_total_row(std::uint64_t paths, std::uint64_t lost, std::uint64_t unterminated,
                     double albedo_up, double albedo_down);

// A chi-square goodness of fit as a z-tested row: measured chi2/dof, model 1, stderr
// sqrt(2/dof) (normal approximation of chi2/dof under the null; large dof).
void set_chi2(Row& r, double chi2, int dof);

struct Options {
  std::vector<double> theta_deg{0, 30, 60, 80};  // view zenith angles of the G1 checks
  std::vector<double> phi_deg{0};
  std::uint64_t rays = 1000000;  // per estimator and direction
  std::uint64_t seed = 1;
  int ndf_theta_bins = 36;       // D rings over [0, 180] deg: 5 degrees
  int ndf_phi_bins = 8;
  double min_ring_mass = 1e-4;   // D rings tested where the model holds this much area or more
  std::uint64_t min_bin_count = 100;  // per-bin G1 tests need this many samples and hits
  std::vector<std::string> checks;  // names to run (empty: every applicable check)
  // Other processes sharing the estimators' work (measure/shards.hpp); nullptr: all here.
  TallySplit* split = nullptr;
};

// One entry of a validation: a surface, or several independent surfaces with the same
// statistics (seeds of one generator), compared with nominal models by the between-surface
// standard error (docs/theory/error-bars.md).
struct SurfaceSet {
  std::string name;
  std::vector<std::string> labels;  // one per surface ("seed 3", a file name)
  std::vector<Microsurface> surfaces;
  Options options;
};

// Progress of a run: `add_work` before, `done` after each unit of work (for a progress bar).
struct Progress {
  std::function<void(double)> report;  // fraction done
  double total = 0, completed = 0;
  void update(double partial_of_current = 0) const {
    if (report && total > 0) report(std::min(1.0, (completed + partial_of_current) / total));
  }
};

// What a check adds: rows, and measurements for plots under measurements[name].
struct CheckOutput {
  std::vector<Row> rows;
  Json measurements = Json::object();
};

struct Check {
  std::string name;
  std::string description;
  std::function<bool(const SurfaceSet&)> applies;
  std::function<double(const SurfaceSet&)> work;  // units for the progress bar
  std::function<void(const SurfaceSet&, Progress&, CheckOutput&)> run;
};
// The registry, in the order the checks run.
const std::vector<Check>& checks();

struct EntryResult {
  std::string name;
  Json surfaces = Json::array();  // label and description of each surface
  Json parameters;
  Json measurements = Json::object();
};

struct Result {
  std::vector<Row> rows;
  std::vector<EntryResult> entries;
  double z_threshold = 0;
  double significance = 0.01;
  double seconds = 0;
  std::size_t count(const std::string& verdict) const;
  bool any_failure() const { return count("FAIL") > 0; }
};

// Runs every applicable check of every set (or those named in its options.checks; an unknown
// name is a UsageError), then assigns verdicts over the whole run.
Result run(const std::vector<SurfaceSet>& sets, double significance,
           const std::function<void(double)>& progress = {});

Json row_to_json(const Row& r);
Json verdict_rules_json(double significance, double z_threshold, std::size_t comparisons);
// The record written by `microsim validate`, without the run header.
Json result_to_json(const Result& r);
// The aligned table printed on stdout (groups collapsed to their worst row).
std::string format_table(const Result& r);

// ---------------------------------------------------------------------------------------------
// Suites: surfaces/suites/NAME.json (comments allowed). Documented in surfaces/suites/README.md.
struct SuiteEntry {
  std::string name;
  std::string generate;                 // generator kind: `microsim generate KIND`
  std::string preset;                   // absolute path of the TOML preset ("" = none)
  std::vector<std::pair<std::string, std::string>> args;  // extra --key value (override preset)
  std::vector<std::uint64_t> seeds;     // one surface per seed (empty: one surface, no --seed)
  std::string format = "exr";           // file format of the generated surface: exr (heightfields)
                                        // or ply/obj/off (meshes)
  Options options;
};
struct Suite {
  std::string name, file, description;
  double significance = 0.01;
  std::vector<SuiteEntry> entries;
};
// The surface of an entry: its preset, then its args (which win), then `seed` when given.
// UsageError for an unknown kind, option or value (surface/surface_spec.hpp).
SurfaceRequest surface_request(const SuiteEntry& e, std::optional<std::uint64_t> seed);
// Generates an entry's surface (one seed) at `path` and loads it back (the checks measure the
// saved surface, as they would a file); UsageError "--suite FILE: entry NAME: ..." when refused.
// `warnings`: what `microsim generate` would warn about (e.g. a heightmap that is not periodic).
Microsurface generate_entry(const SuiteEntry& e, const std::string& suite_file, std::optional<std::uint64_t> seed,
                            const std::string& path, std::vector<std::string>* warnings = nullptr);
// Entry names become file names: UsageError unless each is 1-100 characters without path
// separators, control characters or a leading '.' or '-', and unique within the suite.
void require_safe_entry_names(const Suite& suite, const std::string& suite_file);
// Reads a suite file; UsageError naming the file and the field for anything malformed.
Suite load_suite(const std::string& path);
// NAME -> path: NAME itself if it is a file, else NAME.json in each of `dirs`, in order.
std::string find_suite(const std::string& name, const std::vector<std::string>& dirs);
// Names of the suites (*.json) in a folder, sorted.
std::vector<std::string> list_suites(const std::string& dir);

}  // namespace microsim::validation
