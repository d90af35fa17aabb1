// Rows averaged over an ensemble of independent surfaces of the same statistics (DESIGN.md "Two
// kinds of error bar"): the mean over surfaces with the between-surface standard error
// sd / sqrt(K), the ray-count one kept as *_stderr_rays. Shared by the measure commands.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "microsim/common.hpp"

namespace microsim::cli {

// How a field of the per-surface rows becomes a field of the ensemble row.
enum class Field {
  Copy,        // taken from the first surface's row (parameters, nominal models)
  Count,       // the number of surfaces (the key names the output field), and "t_dof" = K - 1
  Measured,    // mean, KEY_stderr between surfaces, KEY_stderr_rays from the rows' KEY_stderr
  MeanStderr,  // mean and KEY_stderr between surfaces
  Mean,        // mean only
  Normal,      // a 3-vector averaged and normalized
  Key,         // bins only: identifies the bin across surfaces (copied)
};
using FieldSpec = std::vector<std::pair<std::string, Field>>;

// Two-sided p-value of z = (mean - model) / stderr when stderr is the between-surface error of
// K surfaces: Student t with K - 1 degrees of freedom (measure/stats.hpp), not the normal law.
// Null when z is not a number or K < 2.
Json ensemble_p_value(const Json& z, std::size_t surfaces);

// Mean over rows of a numeric field, with the between-surface standard error sd / sqrt(K).
std::pair<double, double> ensemble_stat(const std::vector<const Json*>& rows, const std::string& key);

// The ensemble row, fields in the order of `row_fields`, then "bins" (when bin_fields is not
// empty) with the bins of the first surface matched to the others by their Key fields.
Json ensemble_row(const std::vector<const Json*>& rows, const FieldSpec& row_fields,
                  const FieldSpec& bin_fields = {});

}  // namespace microsim::cli

#include <functional>

#include "cli_common.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim::cli {

// Loads every file (input_surface) first (a bad file is reported before the long run starts), then calls
// measure(surface, k) for each surface k in turn (one surface in memory at a time) and collects
// the rows it returns (a JSON array per surface).
std::vector<Json> measure_over_surfaces(
    const GlobalOptions& g, const std::vector<std::string>& files,
    const std::function<Json(const Microsurface&, std::size_t)>& measure);

// Fills j["rows"] (and for several surfaces j["per_surface"]): one surface's rows as they are;
// for several, row d is combine(row d of every surface).
void put_rows(Json& j, const std::vector<std::string>& files, const std::vector<Json>& per_surface,
              const std::function<Json(const std::vector<const Json*>&)>& combine);

}  // namespace microsim::cli
