// Masking-shadowing G2(o, m, i) measured on an explicit microsurface ([GeomBSDF24, eq. 16a],
// docs/theory/g2.md): per facet, the fraction of its area visible from both o and i (symmetric in o and i,
// [GeomBSDF24, eq. 16b]). Over a normal bin or all normals the facets are weighted by
//   w_f = A_f (max(0, o.m_f) + max(0, i.m_f)) / 2   over the facets facing both (else 0),
// symmetric in (o, i), equal to G1's projected-area weight A_f max(0, v.m_f) at o = i = v (so
// G2(v, m, v) = G1(v, m) bin by bin and on average, [GeomBSDF24, eq. 16]) and to the BRDF's A_f (i.m) at
// the half vector m = h (where o.h = i.h). Points are drawn with density proportional to w_f
// and two occlusion rays, toward o and toward i, are traced from each:
//   G2(o, m, i) = sum_{f in B} w_f V_f(o, i) / sum_{f in B} w_f,
// and g1_o, g1_i the same ratio with the visibility toward o alone and toward i alone, from the
// same points and weights (at o = i they are G2 itself, and G1(v, m) of the area-sampling G1).
// Facets facing only one direction have G2 = 0 by definition and carry no weight.
//
// Models beside it, averaged with the estimator's own weights:
//  * the four Smith forms [Heitz14, eq. 20-23] do not depend on m beyond chi+(o.m) chi+(i.m), so
//    their average over the facets facing both is their value; they are evaluated with
//    Lambda from the surface's own facets (docs/theory/masking.md) and, when the surface has one, with its
//    nominal NDF [Heitz14, Sec. 3];
//  * the same four forms built per bin from the measured G1(o, m) and G1(i, m) of the bin
//    (Lambda = 1/G1 - 1): they isolate the correlation each form assumes between the two
//    visibilities from the m-dependence of masking that Smith ignores;
//  * the V-cavity G2 depends on m: it is averaged over the surface's own facets facing both,
//    with the weights w_f, exactly like the measurement.
// Standard errors: the rays are split into independent replicates (measure/replicates.hpp).
#pragma once
#include <functional>

#include <nlohmann/json.hpp>

#include "microsim/measure/binning.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/table.hpp"
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
  // totals derive from this list (estimator_steps.cpp).
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

// o and i must have o.n > 0 and i.n > 0 (UsageError otherwise). The random points depend on
// the seed and on the unordered pair {o, i} (and the weights are symmetric): swapping o and i
// traces the same points, so the
// symmetry G2(o, m, i) = G2(i, m, o) [GeomBSDF24, eq. 16b] holds sample for sample. `table` (from
// build_facet_table with g2_normal_binning(options)) saves recomputing the facets.
G2Result measure_g2(const Tracer& tracer, const Vec3& o, const Vec3& i, const G2Options& options,
                    const FacetTable* table = nullptr);

// The table of G2 over direction pairs (measure/table.hpp), and the row of one pair appended to
// it: directions, g2 and g1_o, g1_i with standard errors, the models and the bins.
Table g2_table();
Json& add_row(Table& t, const G2Result& r, const Microsurface& s);

}  // namespace microsim
