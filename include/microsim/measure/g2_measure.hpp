// Masking-shadowing G2(o, m, i) measured on an explicit microsurface (000 eq. 16a, DESIGN.md
// "G2"): points are drawn uniformly by area over the facets that face both directions
// (o.m_f > 0 and i.m_f > 0; every other facet has G2 = 0 by definition), and two occlusion
// rays, toward o and toward i, are traced from each. Per normal bin m:
//   G2(o, m, i) = (area of the bin facing both and visible from both) / (area facing both),
// and the same for G1 from o alone and from i alone. The row value is the same ratio over all
// facets facing both directions, weighted by area A_f (the "area front-facing to both").
//
// Models beside it, averaged with the estimator's own weights:
//  * the four Smith forms (001 eq. 20-23) do not depend on m beyond chi+(o.m) chi+(i.m), so
//    their area average over the facets facing both is their value; they are evaluated with
//    Lambda from the surface's own facets (DESIGN.md) and, when the surface has one, with its
//    nominal NDF (001 sec. 3);
//  * the same four forms built per bin from the measured G1(o, m) and G1(i, m) of the bin
//    (Lambda = 1/G1 - 1): they isolate the correlation each form assumes between the two
//    visibilities from the m-dependence of masking that Smith ignores;
//  * the V-cavity G2 depends on m: it is averaged over the surface's own facets facing both,
//    with weights A_f, exactly like the measurement.
#pragma once
#include <functional>

#include <nlohmann/json.hpp>

#include "microsim/measure/binning.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/models/g2_forms.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

struct G2Options {
  std::uint64_t rays = 1000000;  // area samples per direction pair (two occlusion rays each)
  std::uint64_t seed = 1;
  int normal_theta_bins = 18;  // normal bins over the whole sphere (10 degree rings)
  int normal_phi_bins = 8;     // 45 degree sectors
  std::function<void(double)> progress;
};

struct G2NormalBin {
  Vec3 mean_normal = Vec3::Zero();  // area-weighted mean unit normal of the facets facing both
  double area = 0;                  // sum_f A_f in the bin
  double front_area = 0;            // sum_f A_f over the bin's facets facing both directions
  double vcavity_sum = 0;           // sum_f A_f G2_vcavity(o, i, m_f) over the same facets
  std::uint64_t samples = 0, visible_o = 0, visible_i = 0, visible_both = 0;
};

struct G2Result {
  Vec3 o, i;
  std::uint64_t samples = 0, visible_o = 0, visible_i = 0, visible_both = 0;
  double total_area = 0;     // sum_f A_f
  double front_area = 0;     // sum_f A_f over the facets facing both
  double macro_area = 1;     // A
  double lambda_o = 0, lambda_i = 0;  // Smith Lambda from the surface's own facets
  double vcavity = 0;        // V-cavity G2 averaged over the facets facing both (weights A_f)
  TraceCounters counters;
  std::vector<G2NormalBin> bins;
  DirectionBinning binning{1, 1, kPi};
  double seconds = 0;

  Estimate g2() const { return binomial_estimate(visible_both, samples); }
  Estimate g1_o() const { return binomial_estimate(visible_o, samples); }
  Estimate g1_i() const { return binomial_estimate(visible_i, samples); }
  Estimate bin_g2(int b) const { return binomial_estimate(bins[b].visible_both, bins[b].samples); }
  Estimate bin_g1_o(int b) const { return binomial_estimate(bins[b].visible_o, bins[b].samples); }
  Estimate bin_g1_i(int b) const { return binomial_estimate(bins[b].visible_i, bins[b].samples); }
  // 001 eq. 20-23 with Lambda from the surface's facets.
  models::G2Forms smith_numeric() const;

  // The four forms built per normal bin from the bin's measured g1_o and g1_i
  // (models::g2_forms_from_g1), averaged over bins with the estimator's weights (the bins' area
  // facing both), with the standard error of the mean difference g2 - form (delta method on
  // each bin's multinomial counts: both / o only / i only / neither).
  struct FormsFromG1 {
    models::G2Forms value, diff, diff_stderr;
  };
  FormsFromG1 bin_forms_from_g1(int b) const;
  FormsFromG1 forms_from_g1() const;
};

DirectionBinning g2_normal_binning(const G2Options& options);

// o and i must have o.n > 0 and i.n > 0 (UsageError otherwise). The random points depend on
// the seed and on the unordered pair {o, i}: swapping o and i traces the same points, so the
// symmetry G2(o, m, i) = G2(i, m, o) (000 eq. 16b) holds sample for sample. `table` (from
// build_facet_table with g2_normal_binning(options)) saves recomputing the facets.
G2Result measure_g2(const Tracer& tracer, const Vec3& o, const Vec3& i, const G2Options& options,
                    const FacetTable* table = nullptr);

// JSON row: directions, g2 and g1_o, g1_i with standard errors, the models and the bins.
Json g2_row_json(const G2Result& r, const Microsurface& s);

}  // namespace microsim
