// Helpers shared by the checks (checks_common.hpp).
#include "checks_common.hpp"

namespace microsim::validation {

std::string num(double x, int precision) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", precision, x);
  return buf;
}
std::string fixed(double x, int digits) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << x;
  return os.str();
}
std::string angle(double d) { return num(d, 4); }

// Mean and between-surface standard error (sd / sqrt(K)) of per-surface values.
std::pair<double, double> mean_and_se(const std::vector<double>& x) {
  const SampleMean m = sample_mean(x);
  return {m.mean, m.stderr_};
}

// The estimator's error with a floor at the resolution of n samples: a proportion at 0 or 1
// has no spread but is known only to ~1/n (the error of (k + 1/2)/(n + 1) at k = n), so a
// comparison with a model there is not an infinite z.
Estimate floored(Estimate e, std::uint64_t n, double scale) {
  if (n > 0) e.stderr_ = std::max(e.stderr_, scale * proportion_floor(n));
  return e;
}

// A mean over K surfaces with the between-surface error: the ray-count error of the mean,
// sqrt(sum se_k^2) / K, is a floor (K values can agree by chance, e.g. all unmasked).
EnsembleMean ensemble_mean(const std::vector<Estimate>& per_surface) {
  std::vector<double> x, rays;
  for (const Estimate& e : per_surface) {
    x.push_back(e.mean);
    rays.push_back(e.stderr_);
  }
  const SampleMean m = sample_mean(x);
  return {m.mean, std::max(m.stderr_, mean_of_errors(rays)), static_cast<int>(per_surface.size()) - 1};
}

// A comparison of K surfaces with a nominal model: a model row with the between-surface error
// and K - 1 degrees of freedom for K > 1; for one surface an info row (measured and model, no
// error bar: one surface's ray-count error says nothing about surface-to-surface variation).
void push_nominal(CheckOutput& out, Row r, const std::string& where,
                  const std::vector<Estimate>& per_surface, double model, const std::string& group,
                  const Json& extra) {
  const std::size_t K = per_surface.size();
  const EnsembleMean e = ensemble_mean(per_surface);
  r.condition += (K > 1 ? " " + std::to_string(K) + " surfaces," : "") + " " + where;
  r.measured = e.mean;
  r.model = model;
  r.group = group;
  r.extra = extra;
  r.extra["surfaces"] = K;
  if (K > 1) {
    r.kind = Kind::Model;
    r.stderr_ = e.stderr_;
    r.dof = e.dof;
    r.error = "surfaces";
  } else {
    r.kind = Kind::Info;
    r.error = "none (one surface: give several for a between-surface error)";
  }
  out.rows.push_back(std::move(r));
}

Row make_row(const SurfaceSet& set, const std::string& label, const std::string& quantity,
             const std::string& model_name, Kind kind, const std::string& reference) {
  Row r;
  r.entry = set.name;
  r.quantity = quantity;
  r.model_name = model_name;
  r.kind = kind;
  r.reference = reference;
  r.condition = set.name + (label.empty() ? "" : " " + label);
  return r;
}

// Completes a row with its measurement (where, measured, stderr, model, error kind, group,
// plot fields) and appends it.
void push_measured(CheckOutput& out, Row r, const std::string& where, double measured,
                   double stderr_, double model, const char* error, const std::string& group,
                   const Json& extra) {
  r.condition += " " + where;
  r.measured = measured;
  r.stderr_ = stderr_;
  r.model = model;
  r.error = error;
  r.group = group;
  r.extra = extra;
  out.rows.push_back(std::move(r));
}

std::string surface_label(const SurfaceSet& set, std::size_t k) {
  return set.surfaces.size() > 1 || !set.labels[k].empty() ? set.labels[k] : "";
}

Json for_each_surface(const SurfaceSet& set, const DirectionBinning& binning, Progress& progress,
                      const std::function<void(SurfacePass&)>& body) {
  Json entries = Json::array();
  for (std::size_t k = 0; k < set.surfaces.size(); ++k) {
    const Microsurface& s = set.surfaces[k];
    Tracer tracer(s);
    const FacetTable table = build_facet_table(s, binning);
    progress.completed += 0.1 * static_cast<double>(s.num_facets());
    Json entry = {{"label", set.labels[k]}, {"rows", Json::array()}};
    SurfacePass pass{k, s, surface_label(set, k), tracer, table, entry};
    body(pass);
    entries.push_back(std::move(entry));
  }
  return entries;
}

void for_each_view(const Options& o, const std::function<void(double, double, const Vec3&)>& body) {
  for (double p : o.phi_deg)
    for (double t : o.theta_deg) body(t, p, direction_from_angles(rad(t), rad(p)));
}

NormalBinRange normal_bin_range(const DirectionBinning& binning, int b) {
  const int it = b / binning.n_phi(), ip = b % binning.n_phi();
  return {deg(binning.theta_lo(it)), deg(binning.theta_hi(it)), deg(binning.phi_lo(ip)),
          deg(binning.phi_hi(ip))};
}
std::string NormalBinRange::text() const {
  return "m in [" + angle(theta_lo) + "," + angle(theta_hi) + "]x[" + angle(phi_lo) + "," + angle(phi_hi) + "]";
}
Json NormalBinRange::with(Json extra) const {
  extra["theta_m_range_deg"] = {theta_lo, theta_hi};
  extra["phi_m_range_deg"] = {phi_lo, phi_hi};
  return extra;
}

// ---------------------------------------------------------------------------------------------
// Shared by the G2, VNDF and BSDF checks: ray counts derived from --rays (kept modest so that
// every check together stays within a few times the cost of the G1 check).
std::uint64_t share_of_rays(const Options& o, std::uint64_t divisor) {
  return std::max<std::uint64_t>(1000, o.rays / divisor);
}

// An info row when the set's coarsest surface is coarser than the converged level of the study
// for the quantities of `check` (docs/theory/discretization.md): the rows then describe the
// triangulated grid more than the continuous surface it stands for.
std::optional<Row> discretization_row(const SurfaceSet& set, const std::string& check) {
  const auto level = converged_level(check);
  if (!level) return std::nullopt;
  std::optional<Discretization> coarsest;
  for (const Microsurface& m : set.surfaces) {
    const auto d = discretization_of(m.description);
    if (!d) continue;
    if (!coarsest) coarsest = d;
    coarsest->cells_per_correlation_length =
        std::min(coarsest->cells_per_correlation_length, d->cells_per_correlation_length);
    coarsest->correlation_lengths_per_tile =
        std::min(coarsest->correlation_lengths_per_tile, d->correlation_lengths_per_tile);
  }
  if (!coarsest) return std::nullopt;
  const bool coarse_grid = coarsest->cells_per_correlation_length < level->cells_per_correlation_length * (1 - 1e-9);
  const bool small_tile = coarsest->correlation_lengths_per_tile < level->correlation_lengths_per_tile * (1 - 1e-9);
  if (!coarse_grid && !small_tile) return std::nullopt;
  Row r = make_row(set, "", coarse_grid ? "cells_per_correlation_length" : "correlation_lengths_per_tile",
                   "converged_level", Kind::Info, "discretization study (analysis/convergence.sh)");
  r.measured = coarse_grid ? coarsest->cells_per_correlation_length : coarsest->correlation_lengths_per_tile;
  r.model = coarse_grid ? level->cells_per_correlation_length : level->correlation_lengths_per_tile;
  r.condition += ": coarser than the converged level for " + check + " (" + level->what + "): " +
                 num(coarsest->cells_per_correlation_length, 3) + " cells per l (converged " +
                 num(level->cells_per_correlation_length, 3) + "), " +
                 num(coarsest->correlation_lengths_per_tile, 4) + " l per tile (converged " +
                 num(level->correlation_lengths_per_tile, 4) + ")";
  r.error = "none";
  r.extra = {{"check", check},
             {"cells_per_correlation_length", coarsest->cells_per_correlation_length},
             {"correlation_lengths_per_tile", coarsest->correlation_lengths_per_tile},
             {"converged_cells_per_correlation_length", level->cells_per_correlation_length},
             {"converged_correlation_lengths_per_tile", level->correlation_lengths_per_tile}};
  return r;
}

}  // namespace microsim::validation
