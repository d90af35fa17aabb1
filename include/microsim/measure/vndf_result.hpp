// The result of a VNDF measurement ([Heitz14, eq. 13], measure/vndf_measure.hpp): the options,
// the first-hit counts per normal bin and the exact facet sums of Smith's D_v beside them.
// Shared by the one VNDF estimator (vndf_estimator.hpp) and its entry points, below both.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/measure/binning.hpp"
#include "microsim/measure/shards.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

struct VndfOptions {
  std::uint64_t rays = 1000000;
  std::uint64_t seed = 1;
  int theta_bins = 18;  // over theta_m in [0, 90] degrees (5 degree rings)
  int phi_bins = 16;    // 22.5 degree sectors
  // Samples for the chi-square test of the nominal NDF's VNDF sampler (0: no sampler test).
  std::uint64_t sampler_samples = 0;
  // Family-wise false-alarm rate of the per-bin z test: 0.0027 is "3 sigma" for one bin,
  // Sidak-corrected over the bins tested.
  double family_alpha = 0.0027;
  std::function<void(double)> progress;
  // Other processes sharing the rays (measure/shards.hpp); nullptr: all traced here.
  TallySplit* split = nullptr;
};

DirectionBinning vndf_binning(const VndfOptions& options);

struct VndfResult {
  Vec3 v;
  DirectionBinning binning{1, 1, kPi / 2};
  std::uint64_t rays = 0;
  std::uint64_t hits = 0;           // front-face first hits (the normalization)
  std::uint64_t hits_below = 0;     // of which with a normal below the horizon (no bin)
  std::vector<std::uint64_t> bin_hits;
  std::vector<double> front_projected;  // sum_f A_f max(0, v.m_f) per bin
  double front_projected_total = 0;     // over all facets
  double window_area_perp = 0;
  double macro_area = 1;
  TraceCounters counters;
  double seconds = 0;

  Estimate dv(int b) const;                // histogram density in bin b
  double dv_smith_numeric(int b) const;    // Smith with the surface's own facets
  // Bin probabilities of the Smith-numeric VNDF (sum = mass of the binned normals).
  std::vector<double> smith_numeric_probabilities() const;
};

}  // namespace microsim
