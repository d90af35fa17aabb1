#include "microsim/api/vndf_request.hpp"

#include <chrono>
#include <memory>
#include <optional>

#include "microsim/api/estimator_record.hpp"
#include "microsim/api/request_checks.hpp"
#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/measure/stats.hpp"
#include "microsim/measure/vcavity_measure.hpp"
#include "microsim/measure/vndf_measure.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

namespace {

const char* const kGrooveByGroove =
    "true for a V-cavity ensemble: [Heitz14, Sec. 6.1] made explicit, every ray picks a groove uniformly "
    "(equal macro areas) and a uniform origin on its tile and is traced on that groove alone, an "
    "infinite periodic V-groove";
const char* const kChi2Vcavity =
    "*_vcavity: the chi-square test of the hit histogram against the V-cavity model's bin "
    "probabilities over the ensemble's facets, sum_f A_f (v.m_f)+ G1_vcavity(v, m_f) ([Heitz14, eq. 13] "
    "with eq. 24), exact for separate grooves";

Json vndf_definitions(bool ensemble) {
  return {
      {"dv", "histogram of the normals of front-face first hits of parallel rays along -v: "
             "(hits in bin / hits) / solid angle of the bin ([GeomBSDF24, eq. 3b], [Heitz14, eq. 13])"},
      {"dv_model", "bin average of the nominal NDF's D_v(m) = G1(v) max(0,v.m) D(m) / (v.n) "
                   "[Heitz14, eq. 13], by quadrature"},
      {"dv_smith_numeric", "Smith's D_v with the surface's own facets: sum_f in bin A_f "
                           "max(0,v.m_f) / sum_f A_f max(0,v.m_f) / solid angle"},
      {"z", "per bin (dv - dv_model) / stderr, the binomial stderr under the model (ensembles: "
            "the between-surface stderr); max_abs_z over bins holding >= 5 expected hits "
            "(ensembles: >= 0.2% of the visible normals) against sidak_z, the two-sided threshold "
            "for family_alpha Sidak-corrected over bins_tested (ensembles of K surfaces: the "
            "Student t quantile with K - 1 degrees of freedom)"},
      {"chi2", "Pearson chi-square of the hit histogram against the nominal bin probabilities "
               "(bins with >= 5 expected hits, the rest pooled), p_value its upper tail; "
               "*_smith_numeric the same against dv_smith_numeric"},
      {"sampler_*", "the same chi-square test for sampler_samples normals drawn by the nominal "
                    "NDF's VNDF sampler (models/ndf.hpp sample_visible_normal)"},
      {"replicates", "null: the ray origins are i.i.d. uniform (not stratified), so the bin "
                     "counts are multinomial and the binomial standard error is exact"},
      {"stderr", ensemble ? "between-surface standard error (sd / sqrt(K)); "
                            "per_surface holds each surface's rows"
                          : "ray-count (binomial) standard error of this one surface"}};
}

// The V-cavity model's VNDF over the ensemble's own facets (exact there), into the row.
void put_vcavity_test(Json& row, const VndfResult& m, const Microsurface& s, const VndfOptions& vo) {
  const GofResult gof = histogram_gof(m.bin_hits, m.hits, vcavity_vndf_probabilities(s, m.v, m.binning), vo.family_alpha);
  row["chi2_vcavity"] = gof.chi2;
  row["dof_vcavity"] = gof.dof;
  row["p_value_vcavity"] = gof.p_value;
  row["max_abs_z_vcavity"] = gof.max_abs_z;
  row["pass_vcavity"] = gof.pass();
}

// What the surfaces' measurements add up to beside their rows.
struct VndfTotals {
  TraceCounters counters;
  std::uint64_t lost = 0;
  std::size_t done = 0;  // directions measured
};

// The rows of surface k: every direction (phi outer, theta inner). A V-cavity ensemble is measured
// groove by groove [Heitz14, Sec. 6.1], each groove an infinite periodic V-groove of its own; its
// stored strips traced together would mask each other.
Table vndf_surface_rows(const VndfRequest& r, const Microsurface& s, std::size_t k, const VndfOptions& vo,
                        VndfTotals& totals) {
  std::optional<SceneEnsemble> grooves;
  if (is_vcavity(s)) grooves.emplace(vcavity_grooves(s, "measure vndf", GrooveFrames::StoredNormalNormalized));
  const DirectionBinning bins = vndf_binning(vo);
  std::unique_ptr<Tracer> tracer;
  FacetTable table;
  if (!grooves) {
    tracer = std::make_unique<Tracer>(s);
    table = build_facet_table(s, bins);
  }
  Table rows = vndf_table(vo.family_alpha);
  for (double p : r.phi.degrees)
    for (double t : r.theta.degrees) {
      const Vec3 v = direction_from_angles(rad(t), rad(p));
      VndfResult m = grooves ? measure_vndf(*grooves, v, vo) : measure_vndf(*tracer, v, vo, &table);
      totals.counters += m.counters;
      totals.lost += !s.macro().finite_object() ? m.counters.lost_below + m.counters.unresolved : m.counters.unresolved;
      std::optional<SamplerTest> sampler;
      // The sampler does not depend on the surface: tested once, with the first one.
      if (s.nominal && vo.sampler_samples > 0 && k == 0)
        sampler = test_vndf_sampler(*s.nominal, v, vo.sampler_samples, bins, vo.seed, vo.family_alpha);
      Json& row = add_row(rows, m, s, vo, sampler);
      if (grooves) put_vcavity_test(row, m, s, vo);
      row["theta_deg"] = t;
      row["phi_deg"] = p;
      ++totals.done;
    }
  return rows;
}

}  // namespace

void VndfRequest::check() const {
  if (surfaces.empty()) throw UsageError("no surface given");
  require_integer_in(rays, 1, kMaxRays, "rays");
  require_integer_in(sampler_samples, 0, kMaxRays, "sampler_samples");
  require_integer_in(theta_bins, 1, 360, "theta_bins");
  require_integer_in(phi_bins, 1, 720, "phi_bins");
  require_above_horizon(theta.degrees, "theta");
}

Json measure_vndf_record(const VndfRequest& r, const RunContext& ctx) {
  r.check();
  const auto t0 = std::chrono::steady_clock::now();
  VndfOptions vo = estimator_options<VndfOptions>(r.rays, r.seed, ctx);
  vo.theta_bins = r.theta_bins;
  vo.phi_bins = r.phi_bins;
  vo.sampler_samples = static_cast<std::uint64_t>(r.sampler_samples);
  Json j = estimator_record("measure vndf", r.surfaces, ctx);
  j["parameters"] = {{"theta", r.theta.text},
                     {"phi", r.phi.text},
                     {"rays", r.rays},
                     {"sampler_samples", r.sampler_samples},
                     {"seed", r.seed},
                     {"replicates", nullptr},
                     {"normal_bins", {{"theta", r.theta_bins}, {"phi", r.phi_bins}, {"theta_max_deg", 90}}},
                     {"family_alpha", vo.family_alpha}};
  j["definitions"] = vndf_definitions(r.surfaces.size() > 1);
  const std::size_t total = r.surfaces.size() * r.theta.degrees.size() * r.phi.degrees.size();
  VndfTotals totals;
  vo.progress = [&](double f) {
    if (ctx.progress) ctx.progress((totals.done + f) / total);
  };
  std::vector<Table> per_surface = measure_each_surface(r.surfaces, [&](const Microsurface& s, std::size_t k) {
    if (k == 0) {
      const bool grooves = is_vcavity(s);
      j["surface"] = s.description;
      j["groove_by_groove"] = grooves;
      if (grooves) {
        j["definitions"]["groove_by_groove"] = kGrooveByGroove;
        j["definitions"]["chi2_vcavity"] = kChi2Vcavity;
      }
    }
    return vndf_surface_rows(r, s, k, vo, totals);
  });
  put_rows(j, r.surfaces, per_surface);
  j["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  j["total_rays"] = totals.counters.rays;
  j["lost_rays"] = totals.lost;
  j["backface_hits"] = totals.counters.backface_hits;
  return j;
}

}  // namespace microsim
