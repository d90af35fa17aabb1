#include "microsim/measure/table.hpp"

#include <cmath>
#include <stdexcept>

#include "microsim/measure/stats.hpp"

namespace microsim {

const char* error_kind_name(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::None: return "none";
    case ErrorKind::Replicates: return "replicates";
    case ErrorKind::Binomial: return "binomial";
    case ErrorKind::Jackknife: return "jackknife";
    case ErrorKind::Surfaces: return "surfaces";
    case ErrorKind::Blocks: return "blocks";
    case ErrorKind::Rounding: return "rounding";
  }
  return "none";
}

const char* error_kind_meaning(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::None: return "no error bar (a parameter, an exact sum over facets, a model)";
    case ErrorKind::Replicates:
      return "spread of the R independent randomized replicates the rays are split into: "
             "sqrt(var / R) of the replicate means";
    case ErrorKind::Binomial: return "independent counts: sqrt(p (1 - p) / n), exact for multinomial bins";
    case ErrorKind::Jackknife: return "delete-one-replicate jackknife of a nonlinear function of the replicates' tallies";
    case ErrorKind::Surfaces:
      return "spread of K independent surfaces: sd / sqrt(K), Student t with K - 1 degrees of freedom";
    case ErrorKind::Blocks: return "spread of the estimate over blocks (regions) of one surface, divided by sqrt(blocks)";
    case ErrorKind::Rounding: return "resolution of a finite count or of floating-point sums";
  }
  return "";
}

std::vector<Column> tracer_count_fields(bool windows) {
  const ErrorKind N = ErrorKind::None;
  std::vector<Column> f = {
      {"lost_rays", Merge::Copy, N, "count",
       "rays that found no first hit: still inside the surface's slab after the wrap limit, or (periodic "
       "surfaces) leaving it downward"},
      {"missed_rays", Merge::Copy, N, "count", "finite objects: rays of the window passing beside the object"},
      {"backface_hits", Merge::Copy, N, "count", "first hits on the unexpected side of a facet"}};
  if (windows) {
    f.push_back({"side_exits", Merge::Copy, N, "count", "measured windows: rays leaving through a side wall"});
    f.push_back({"side_entries", Merge::Copy, N, "count", "measured windows: rays entering through a side wall"});
  }
  f.push_back({"trace_counters", Merge::Copy, N, "count",
               "every counter of the tracer, by name (rays, border_crossings, lost_below, "
               "backface_hits, unresolved, side_exits, side_entries)"});
  f.push_back({"seconds", Merge::Copy, N, "s", "wall time of the row's measurement"});
  return f;
}

const char* merge_name(Merge merge) {
  switch (merge) {
    case Merge::Copy: return "copy";
    case Merge::Key: return "key";
    case Merge::Count: return "count";
    case Merge::Measured: return "measured";
    case Merge::Spread: return "spread";
    case Merge::Mean: return "mean";
    case Merge::Direction: return "direction";
    case Merge::Sharpest: return "sharpest";
  }
  return "";
}

const char* merge_meaning(Merge merge) {
  switch (merge) {
    case Merge::Copy: return "the first surface's value (the same on every surface)";
    case Merge::Sharpest:
      return "the value of the surface whose NAME_stderr (NAME itself for an error column) is smallest, the "
             "first on a tie (a Monte Carlo model whose run may differ between surfaces)";
    case Merge::Key: return "copied; identifies the row or bin across surfaces (bins are matched on every key)";
    case Merge::Count: return "the number of surfaces K, and t_dof = K - 1 beside it";
    case Merge::Measured:
      return "mean over surfaces; NAME_stderr becomes the between-surface error and NAME_stderr_rays "
             "the ray-count error of the mean, sqrt(sum se_k^2) / K";
    case Merge::Spread: return "mean over surfaces with the between-surface error NAME_stderr";
    case Merge::Mean: return "mean over surfaces, no error";
    case Merge::Direction: return "a unit 3-vector: the normalized sum over surfaces";
  }
  return "";
}

Json ensemble_p_value(const Json& z, std::size_t surfaces) {
  // No p-value without a z (a zero error: the comparison has no error bar).
  if (!z.is_number() || surfaces < 2) return nullptr;
  return student_t_two_sided_p(z.get<double>(), static_cast<double>(surfaces - 1));
}

namespace {

bool has_number(const Json& row, const std::string& key) {
  auto it = row.find(key);
  return it != row.end() && it->is_number();
}

// Values of a numeric field over the rows that have it.
std::vector<double> values(const std::vector<const Json*>& rows, const std::string& key) {
  std::vector<double> x;
  for (const Json* r : rows)
    if (has_number(*r, key)) x.push_back((*r)[key].get<double>());
  return x;
}

void merge_columns(Json& out, const std::vector<const Json*>& rows, const std::vector<Column>& columns) {
  for (const Column& c : columns) {
    const std::string& key = c.name;
    const Merge how = c.merge;
    switch (how) {
      case Merge::Copy:
      case Merge::Key:
        out[key] = rows[0]->contains(key) ? (*rows[0])[key] : Json(nullptr);
        break;
      case Merge::Sharpest: {
        const std::string err = key.size() > 7 && key.compare(key.size() - 7, 7, "_stderr") == 0 ? key : key + "_stderr";
        const Json* best = rows[0];
        for (const Json* r : rows)
          if (has_number(*r, err) && (!has_number(*best, err) || (*r)[err].get<double>() < (*best)[err].get<double>()))
            best = r;
        out[key] = best->contains(key) ? (*best)[key] : Json(nullptr);
        break;
      }
      case Merge::Count:
        out[key] = rows.size();
        out["t_dof"] = rows.size() - 1;
        break;
      case Merge::Measured:
      case Merge::Spread:
      case Merge::Mean: {
        const std::vector<double> x = values(rows, key);
        if (x.empty()) {  // no surface has a value (e.g. an empty bin): null, not a made-up 0
          out[key] = nullptr;
          if (how != Merge::Mean) out[key + "_stderr"] = nullptr;
          if (how == Merge::Measured) out[key + "_stderr_rays"] = nullptr;
          break;
        }
        const SampleMean m = sample_mean(x);
        out[key] = m.mean;
        if (how == Merge::Mean) break;
        out[key + "_stderr"] = m.stderr_;
        if (how == Merge::Spread) break;
        std::vector<double> se;
        for (const Json* r : rows)
          if (has_number(*r, key + "_stderr")) se.push_back((*r)[key + "_stderr"].get<double>());
        // sqrt(sum se_k^2) / K over all K rows (a row without an error adds nothing).
        out[key + "_stderr_rays"] = mean_of_errors(se, rows.size());
        break;
      }
      case Merge::Direction: {
        Vec3 m = Vec3::Zero();
        for (const Json* r : rows) {
          const Json& a = (*r)[key];
          m += Vec3(a[0].get<double>(), a[1].get<double>(), a[2].get<double>());
        }
        if (m.norm() > 0) m.normalize();
        out[key] = {m.x(), m.y(), m.z()};
        break;
      }
    }
  }
}

Json merge_bins(const std::vector<const Json*>& rows, const TableSpec& spec, std::size_t surfaces) {
  Json bins = Json::array();
  for (const auto& b0 : (*rows[0])["bins"]) {
    std::vector<const Json*> same;
    for (const Json* r : rows)
      for (const auto& b : (*r)["bins"]) {
        bool match = true;
        for (const Column& c : spec.bin_columns)
          if (c.merge == Merge::Key && b[c.name] != b0[c.name]) match = false;
        if (match) same.push_back(&b);
      }
    Json eb;
    merge_columns(eb, same, spec.bin_columns);
    eb["surfaces"] = same.size();
    for (const Comparison& c : spec.bin_comparisons) compare(eb, c, surfaces);
    bins.push_back(eb);
  }
  return bins;
}

}  // namespace

Json z_json(double measured, double model, double stderr_) {
  const double z = z_score(measured, model, stderr_);
  return std::isfinite(z) ? Json(z) : Json(nullptr);
}
Json rel_dev_json(double measured, double model) {
  const double r = rel_dev(measured, model);
  return std::isfinite(r) ? Json(r) : Json(nullptr);
}

void compare(Json& row, const Comparison& c, std::size_t surfaces) {
  const bool zero = c.kind == ModelKind::Zero;
  const bool defined = has_number(row, c.measured) && (zero || has_number(row, c.model));
  const std::string error = c.measured + (c.kind == ModelKind::Nominal ? "_stderr" : "_stderr_rays");
  if (!defined || !has_number(row, error)) {
    row[c.z] = nullptr;
    if (!c.rel_dev.empty()) row[c.rel_dev] = nullptr;
    if (!c.p.empty()) row[c.p] = nullptr;
    return;
  }
  const double x = row[c.measured].get<double>(), model = zero ? 0.0 : row[c.model].get<double>();
  double se = row[error].get<double>();
  if (!c.model_error.empty()) se = std::hypot(se, has_number(row, c.model_error) ? row[c.model_error].get<double>() : 0.0);
  row[c.z] = z_json(x, model, se);
  if (!c.rel_dev.empty()) row[c.rel_dev] = rel_dev_json(x, model);
  if (!c.p.empty())
    row[c.p] = c.kind == ModelKind::Nominal ? ensemble_p_value(row[c.z], surfaces) : Json(nullptr);
}

void one_surface_nominal_z(Json& row, const std::string& z) {
  if (!row.contains(z)) return;
  row[z + "_rays"] = row[z];
  row[z] = nullptr;
}

Table merge(const std::vector<const Table*>& parts) {
  if (parts.empty()) throw std::invalid_argument("merge: no tables");
  const Table& first = *parts[0];
  for (const Table* t : parts)
    if (t->rows.size() != first.rows.size())
      throw std::invalid_argument("merge: the tables hold different numbers of rows");
  Table out;
  out.error = ErrorKind::Surfaces;
  out.surfaces = parts.size();
  out.spec = first.spec;
  for (std::size_t d = 0; d < first.rows.size(); ++d) {
    std::vector<const Json*> same;
    for (const Table* t : parts) same.push_back(&t->rows[d]);
    Json e = Json::object();
    merge_columns(e, same, first.spec.columns);
    for (const Comparison& c : first.spec.comparisons) compare(e, c, parts.size());
    if (!first.spec.bin_columns.empty()) e["bins"] = merge_bins(same, first.spec, parts.size());
    if (first.spec.verdict) {
      first.spec.verdict(e, parts.size());
      if (e.contains("bins")) {  // the sub-table stays the last field
        Json bins = std::move(e["bins"]);
        e.erase("bins");
        e["bins"] = std::move(bins);
      }
    }
    out.rows.push_back(std::move(e));
  }
  return out;
}

}  // namespace microsim
