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
