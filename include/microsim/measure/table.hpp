// The result table of every estimator: named columns (a value NAME with its standard error
// NAME_stderr beside it), the models beside the measurements, a per-bin sub-table ("bins") in
// every row, and the rules by which K tables of independent surfaces merge into the table of
// the ensemble (docs/theory/error-bars.md). One rule for every quantity:
//  - a measured column becomes the mean over surfaces with the between-surface standard error
//    sd / sqrt(K) (ErrorKind::Surfaces); the ray-count error of that mean, sqrt(sum se_k^2) / K,
//    is kept as NAME_stderr_rays;
//  - a comparison with a model computed from each surface's own facets uses the ray-count error
//    (the model is exact for those facets: what is left is ray noise); a comparison with a
//    nominal model uses the between-surface error, and its p-value is Student t with K - 1
//    degrees of freedom;
//  - z = (measured - model) / stderr (z_score in stats.hpp), rel_dev = (measured - model) / |model|;
//    where the error is exactly 0 and the values differ, z is null (no error bar to compare with).
// Writers (JSON records, CSV, EXR) read the rows; the rows hold plain named fields so that the
// records keep their field names and order.
#pragma once
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "microsim/common.hpp"

namespace microsim {

// What a column's standard error measures.
enum class ErrorKind {
  None,        // no error bar (a parameter, an exact sum over facets)
  Replicates,  // spread of R independent randomized replicates (stratified passes)
  Binomial,    // i.i.d. counts: sqrt(p (1 - p) / n), exact for multinomial bins
  Jackknife,   // delete-one-replicate jackknife (a nonlinear function of replicate tallies)
  Surfaces,    // spread of K independent surfaces, sd / sqrt(K) (Student t, K - 1 dof)
  Blocks,      // spread of blocks of one surface
  Rounding,    // resolution of a finite count or of floating-point sums
};
const char* error_kind_name(ErrorKind kind);
// One sentence saying what the standard error of that kind measures (for the reference pages).
const char* error_kind_meaning(ErrorKind kind);

// How a column of one surface's table becomes the column of the ensemble's table.
enum class Merge {
  Copy,       // the same on every surface (a parameter, a nominal model): the first surface's
  Key,        // identifies a bin across surfaces: copied, and bins are matched on every Key
  Count,      // writes K under this column's name, then t_dof = K - 1
  Measured,   // mean, NAME_stderr between surfaces, NAME_stderr_rays from the rows' NAME_stderr
  Spread,     // mean and NAME_stderr between surfaces (a model from each surface's own facets)
  Mean,       // mean only
  Direction,  // a 3-vector: the sum over surfaces, normalized
  Sharpest,   // a Monte Carlo model run beside every surface (its run may differ between surfaces): the value of
              // the surface whose NAME_stderr (NAME itself for an error column) is smallest, the first on a tie
};

const char* merge_name(Merge merge);
// One sentence saying what the merge writes into the ensemble's row (for the reference pages).
const char* merge_meaning(Merge merge);

// A column of the table: its name and merge rule, and what the reference pages say of it.
struct Column {
  std::string name;
  Merge merge = Merge::Copy;
  // The kind of NAME_stderr in one surface's row (None: the row has no NAME_stderr).
  ErrorKind error = ErrorKind::None;
  std::string unit = {};     // "1": a number without unit; "deg", "1/sr", ...; empty: not a number
  std::string meaning = {};  // what the value is, in one sentence
};

// Which model a comparison is made with, which decides the error of the comparison.
enum class ModelKind {
  Facets,   // computed from each surface's own facets: ray-count error NAME_stderr_rays
  Nominal,  // the generator's nominal model: between-surface error NAME_stderr, Student t p
  Zero,     // the measured column is itself a difference (model 0): ray-count error
};

// A comparison written into each ensemble row (or bin) after the merge, in this order:
// z (always), rel_dev and p (when named). A null model gives null outputs.
struct Comparison {
  std::string measured;
  std::string model;  // column name; empty for ModelKind::Zero
  ModelKind kind = ModelKind::Nominal;
  std::string z, rel_dev, p;
  // The model's own standard error column (a Monte Carlo model), combined in quadrature with
  // the measured error; empty: an exact model.
  std::string model_error = {};
};

// How a table of one surface merges into an ensemble's.
struct TableSpec {
  std::vector<Column> columns;            // the ensemble row's columns, in output order
  std::vector<Comparison> comparisons;    // appended after the columns
  std::vector<Column> bin_columns;        // the per-bin sub-table "bins" (empty: no bins)
  std::vector<Comparison> bin_comparisons;
  // Further fields of one surface's rows and bins (bookkeeping, that surface's diagnostics),
  // listed for the reference pages; the merge does not carry them into an ensemble's rows (its
  // per_surface rows keep them). Their merge rule is unused.
  std::vector<Column> row_fields = {};
  std::vector<Column> bin_fields = {};
  // A verdict over the whole merged row (e.g. a Sidak-corrected test over its bins), run last
  // with the number of surfaces; "bins" is the last field when it runs.
  std::function<void(Json& row, std::size_t surfaces)> verdict;
};

// The tracer's counts that rows of ray estimators carry (lost_rays, backface_hits, ...), as
// row_fields; `windows`: also the side walls of measured windows.
std::vector<Column> tracer_count_fields(bool windows);

struct Table {
  ErrorKind error = ErrorKind::Replicates;  // of the NAME_stderr columns
  std::size_t surfaces = 1;                 // K (> 1: merged from K surfaces)
  Json rows = Json::array();                // one object per measured direction
  TableSpec spec;
};

// Mean and between-surface error of each column over K >= 2 tables of the same rows (the same
// directions in the same order), by the tables' spec. Per-bin sub-tables are matched by their
// Key columns; each merged bin gets "surfaces" = the number of surfaces that have it.
Table merge(const std::vector<const Table*>& parts);

// One comparison of the rule above, written into `row`; K is the number of surfaces (Student t
// p-value with K - 1 degrees of freedom; none for K < 2).
void compare(Json& row, const Comparison& c, std::size_t surfaces);

// A comparison with a nominal model made on one surface: without the between-surface error it
// is no verdict on the model, so the z named `z` becomes null and its value (in units of the
// ray-count error) is kept as `z`_rays, at the end of the row. Rows without `z` are unchanged.
void one_surface_nominal_z(Json& row, const std::string& z);

// Two-sided Student t p-value of a z computed with the between-surface error of K surfaces
// (null when z is not a number or K < 2).
Json ensemble_p_value(const Json& z, std::size_t surfaces);

// z and rel_dev as JSON values (z_score and rel_dev of stats.hpp); an infinite value (a zero
// error, or a zero model) is null, in memory as in the written record.
Json z_json(double measured, double model, double stderr_);
Json rel_dev_json(double measured, double model);

}  // namespace microsim
