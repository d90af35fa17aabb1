// The result of a G2 measurement ([GeomBSDF24, eq. 16], measure/g2_measure.hpp): the options,
// the counts per normal bin and per replicate, the exact facet sums and the models beside them,
// with the estimates and their standard errors derived from the counts. Shared by the one G2
// estimator (g2_estimator.hpp) and its entry points, below both.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/measure/binning.hpp"
#include "microsim/measure/shards.hpp"
#include "microsim/models/g2_forms.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

struct G2Options {
  std::uint64_t rays = 1000000;  // area samples per direction pair (two occlusion rays each)
  std::uint64_t seed = 1;
  int normal_theta_bins = 18;  // normal bins over the whole sphere (10 degree rings)
  int normal_phi_bins = 8;     // 45 degree sectors
  int replicates = 32;         // independent randomized replicates (standard errors)
  std::function<void(double)> progress;
  // Other processes sharing the replicates (measure/shards.hpp); nullptr: all computed here.
  TallySplit* split = nullptr;
};

struct G2NormalBin {
  Vec3 mean_normal = Vec3::Zero();  // w_f-weighted mean unit normal of the facets facing both
  double area = 0;                  // sum_f A_f in the bin
  double front_area = 0;            // sum_f A_f over the bin's facets facing both directions
  double weight = 0;                // sum_f w_f over the same facets
  double vcavity_sum = 0;           // sum_f w_f G2_vcavity(o, i, m_f) over the same facets
  std::uint64_t samples = 0, visible_o = 0, visible_i = 0, visible_both = 0;
  // The same counts per replicate (size G2Result::replicates).
  std::vector<std::uint64_t> samples_r, visible_o_r, visible_i_r, visible_both_r;
  // Every count once, as (name, total, per replicate): the exchange between processes and the
  // totals derive from this list (g2_estimator.cpp).
  template <class F>
  static constexpr void for_each_replicate_count(F&& f) {
    f("samples", &G2NormalBin::samples, &G2NormalBin::samples_r);
    f("visible_o", &G2NormalBin::visible_o, &G2NormalBin::visible_o_r);
    f("visible_i", &G2NormalBin::visible_i, &G2NormalBin::visible_i_r);
    f("visible_both", &G2NormalBin::visible_both, &G2NormalBin::visible_both_r);
  }
};

struct G2Result {
  Vec3 o, i;
  std::uint64_t samples = 0, visible_o = 0, visible_i = 0, visible_both = 0;
  double total_area = 0;     // sum_f A_f
  double front_area = 0;     // sum_f A_f over the facets facing both
  double weight = 0;         // sum_f w_f
  int replicates = 1;        // each of samples / replicates points
  double macro_area = 1;     // A
  double lambda_o = 0, lambda_i = 0;  // Smith Lambda from the surface's own facets
  double vcavity = 0;        // V-cavity G2 averaged over the facets facing both (weights w_f)
  TraceCounters counters;
  std::vector<G2NormalBin> bins;
  DirectionBinning binning{1, 1, kPi};
  double seconds = 0;

  // Averages (replicate means) and per-bin ratios (replicate_ratio), with standard errors.
  Estimate g2() const;
  Estimate g1_o() const;
  Estimate g1_i() const;
  Estimate bin_g2(int b) const;
  Estimate bin_g1_o(int b) const;
  Estimate bin_g1_i(int b) const;
  // [Heitz14, eq. 20-23] with Lambda from the surface's facets.
  models::G2Forms smith_numeric() const;

  // The four forms built per normal bin from the bin's measured g1_o and g1_i
  // (models::g2_forms_from_g1), averaged over bins with the estimator's weights (the bins'
  // w_f sums), with the standard error of the mean difference g2 - form (delete-one-replicate
  // jackknife: the forms are smooth functions of the bins' counts).
  struct FormsFromG1 {
    models::G2Forms value, diff, diff_stderr;
  };
  FormsFromG1 bin_forms_from_g1(int b) const;
  FormsFromG1 forms_from_g1() const;
};

DirectionBinning g2_normal_binning(const G2Options& options);

// The four forms as an array, in the order of their fields (the jackknife and the records).
std::array<double, 4> form_values(const models::G2Forms& f);

}  // namespace microsim
