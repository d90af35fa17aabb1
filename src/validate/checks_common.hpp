// Shared by the checks of `microsim validate` (one file per check): number formatting, the
// ensemble mean and the error floor of proportions, and the makers of rows; the checks
// themselves and their work estimates, for the registry (checks.cpp).
#pragma once
#include "microsim/measure/stats.hpp"
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>
#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/measure/vndf_measure.hpp"
#include "microsim/validate/bsdf_object_rows.hpp"
#include "microsim/measure/ndf_measure.hpp"
#include "microsim/models/ndf.hpp"
#include "microsim/surface/discretization.hpp"
#include "microsim/trace/tracer.hpp"

#include "microsim/validate/validate.hpp"

namespace microsim::validation {

std::string num(double x, int precision = 6);
std::string fixed(double x, int digits);
std::string angle(double d);
// Mean and between-surface standard error (sd / sqrt(K)) of per-surface values.
std::pair<double, double> mean_and_se(const std::vector<double>& x);
// The estimator's error with a floor at the resolution of n samples (stats.hpp proportion_floor).
Estimate floored(Estimate e, std::uint64_t n, double scale = 1.0);
// A mean over K surfaces with the between-surface error, the ray-count error of the mean a floor.
struct EnsembleMean {
  double mean = 0, stderr_ = 0;
  int dof = 0;  // K - 1
};
EnsembleMean ensemble_mean(const std::vector<Estimate>& per_surface);
void push_nominal(CheckOutput& out, Row r, const std::string& where,
                  const std::vector<Estimate>& per_surface, double model, const std::string& group,
                  const Json& extra);
Row make_row(const SurfaceSet& set, const std::string& label, const std::string& quantity,
             const std::string& model_name, Kind kind, const std::string& reference);
void push_measured(CheckOutput& out, Row r, const std::string& where, double measured,
                   double stderr_, double model, const char* error, const std::string& group,
                   const Json& extra);
std::string surface_label(const SurfaceSet& set, std::size_t k);
// A check's measurement options (G1Options, G2Options, VndfOptions): `rays`, and the seed and
// the tally split of the validate options.
template <class MeasureOptions>
MeasureOptions check_options(const Options& o, std::uint64_t rays) {
  MeasureOptions m;
  m.rays = rays;
  m.seed = o.seed;
  m.split = o.split;
  return m;
}
// One surface of the G1, G2 and VNDF checks: its tracer and facet table, built once, and the
// entry of measurements[check] that its rows go into ({"label", "rows"}, more fields allowed).
struct SurfacePass {
  std::size_t k;
  const Microsurface& surface;
  std::string label;  // surface_label
  const Tracer& tracer;
  const FacetTable& table;
  Json& entry;
  Json& rows() { return entry["rows"]; }
};
// Runs `body` on every surface of the set in order (the facet pass counted as 0.1 work units per
// facet, as the checks' work estimates count it); returns the entries, one per surface.
Json for_each_surface(const SurfaceSet& set, const DirectionBinning& binning, Progress& progress,
                      const std::function<void(SurfacePass&)>& body);
// Every view direction of the options, phi outer and theta inner (the order of the records).
void for_each_view(const Options& o, const std::function<void(double theta_deg, double phi_deg, const Vec3& v)>& body);
// Runs one measurement worth `unit` work units with its progress callback set (the options'
// `progress` member), then counts it done.
template <class Opts, class Measure>
auto measure_with_progress(Progress& progress, double unit, Opts& options, Measure&& measure) {
  options.progress = [&progress, unit](double f) { progress.update(f * unit); };
  auto r = measure(options);
  progress.completed += unit;
  return r;
}
// A normal bin's ranges in degrees, as the rows print and record them.
struct NormalBinRange {
  double theta_lo, theta_hi, phi_lo, phi_hi;
  std::string text() const;  // "m in [a,b]x[c,d]"
  Json with(Json extra) const;  // extra + theta_m_range_deg, phi_m_range_deg
};
NormalBinRange normal_bin_range(const DirectionBinning& binning, int b);
// Ray counts of the G2, VNDF and BSDF checks, derived from --rays.
std::uint64_t share_of_rays(const Options& o, std::uint64_t divisor);
// An info row when the set's surfaces are coarser than the converged level for `check`.
std::optional<Row> discretization_row(const SurfaceSet& set, const std::string& check);

// The checks (check_*.cpp) and their work estimates.
void check_d_identities(const SurfaceSet& set, Progress& progress, CheckOutput& out);
void check_d_nominal(const SurfaceSet& set, Progress& progress, CheckOutput& out);
double g1_work(const SurfaceSet& set);
void check_g1(const SurfaceSet& set, Progress& progress, CheckOutput& out);
double g2_work(const SurfaceSet& set);
void check_g2(const SurfaceSet& set, Progress& progress, CheckOutput& out);
double vndf_work(const SurfaceSet& set);
void check_vndf(const SurfaceSet& set, Progress& progress, CheckOutput& out);
double bsdf_work(const SurfaceSet& set);
void check_bsdf_albedo(const SurfaceSet& set, Progress& progress, CheckOutput& out);

}  // namespace microsim::validation
