#include "microsim/api/g2_request.hpp"

#include <chrono>
#include <memory>
#include <optional>

#include "microsim/api/estimator_record.hpp"
#include "microsim/api/request_checks.hpp"
#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

namespace {

const char* const kGrooveByGroove =
    "true for a V-cavity ensemble: [Heitz14, Sec. 6.1] made explicit, each groove (normals m, m' drawn "
    "from (n.m) D(m)) traced on its own as an infinite periodic V-groove, the points drawn over "
    "the whole ensemble with the weights w_f; `vcavity` [Heitz14, eq. 24 and Sec. 6] is then exact";

Json g2_definitions(bool ensemble) {
  return {
      {"g2", "fraction of the facets facing both o and i (o.m_f > 0, i.m_f > 0) unoccluded "
             "toward o and toward i, weighted by w_f = A_f (o.m_f + i.m_f) / 2 (points drawn "
             "with that density, two occlusion rays per point; [GeomBSDF24, eq. 16a]): "
             "symmetric in o and i, G1's projected-area weight at o = i (g2 = g1 there, [GeomBSDF24, "
             "eq. 16]) and the BRDF's A_f (i.m) at the half vector"},
      {"g1_o", "fraction of the same points and weights unoccluded toward o (g1_i: toward i)"},
      {"g2_half", "g2 of the normal bin holding the half vector (o+i)/|o+i| (half_bin_*_range_deg): "
                  "the G2(o, h, i) of a specular microfacet BRDF, to compare with the Smith forms "
                  "as they are (null when the bin holds fewer than 100 samples)"},
      {"bins", "per normal bin, the same ratios over the bin's facets facing both; front_fraction = "
               "their area / the bin's area; weight_fraction = the bin's share of sum w_f"},
      {"smith_*", "[Heitz14, eq. 20] (separable), 21 (height correlated), 22 (direction correlated), 23 "
                  "(height-direction correlated) with the van Ginneken lambda(phi) = 4.41 phi / "
                  "(4.41 phi + 1) and Lambda from the surface's facets, sum_f A_f max(0,-v.m_f) / "
                  "((v.n) A); they do not depend on m, so they equal their own area average"},
      {"smith_*_nominal", "the same with the closed-form Lambda of the surface's nominal NDF"},
      {"*_from_g1", "the four forms built in each normal bin from the bin's measured g1_o and g1_i "
                    "(Lambda = 1/G1 - 1, [Heitz14, eq. 10]), averaged over bins with the bins' weights "
                    "sum w_f; *_from_g1_diff = average of (g2 - form), *_diff_stderr its standard "
                    "error (delete-one-replicate jackknife); they "
                    "test the correlation each form assumes, free of the m-dependence of G1"},
      {"vcavity", "V-cavity G2 (Cook-Torrance) averaged over the surface's facets facing both, "
                  "weighted by w_f like the measurement"},
      {"z_*", "(g2 - model) / stderr; for models from the facets the ray-count error "
              "(g2_stderr, or g2_stderr_rays for ensembles), for nominal models the between-"
              "surface error g2_stderr of an ensemble"},
      {"stderr", replicate_stderr_definition(ensemble)}};
}

// The rows of one surface: every direction pair (phi_o, theta_o, phi_i, theta_i from outer to
// inner). A V-cavity ensemble is measured groove by groove [Heitz14, Sec. 6.1], each groove an
// infinite periodic V-groove of its own; its stored strips traced together would mask each other.
Table g2_surface_rows(const G2Request& r, const Microsurface& s, const G2Options& go, TraceCounters& counters,
                      double& build_seconds, std::size_t& done) {
  std::optional<SceneEnsemble> grooves;
  if (is_vcavity(s)) grooves.emplace(vcavity_grooves(s, "measure g2", GrooveFrames::StoredNormalNormalized));
  std::unique_ptr<Tracer> tracer;
  FacetTable table;
  if (!grooves) {
    tracer = std::make_unique<Tracer>(s);
    build_seconds += tracer->build_seconds();
    table = build_facet_table(s, g2_normal_binning(go));
  }
  Table rows = g2_table();
  for (double p_o : r.phi_o.degrees)
    for (double t_o : r.theta_o.degrees)
      for (double p_i : r.phi_i.degrees)
        for (double t_i : r.theta_i.degrees) {
          const Vec3 vo = direction_from_angles(rad(t_o), rad(p_o)), vi = direction_from_angles(rad(t_i), rad(p_i));
          G2Result m = grooves ? measure_g2(*grooves, vo, vi, go) : measure_g2(*tracer, vo, vi, go, &table);
          counters += m.counters;
          Json& row = add_row(rows, m, s);
          row["theta_o_deg"] = t_o;  // exactly as requested
          row["phi_o_deg"] = p_o;
          row["theta_i_deg"] = t_i;
          row["phi_i_deg"] = p_i;
          ++done;
        }
  return rows;
}

}  // namespace

void G2Request::check() const {
  if (surfaces.empty()) throw UsageError("no surface given");
  require_given(theta_o.text, "theta_o");
  require_given(theta_i.text, "theta_i");
  require_rays_and_replicates(rays, replicates);
  require_above_horizon(theta_o.degrees, "theta_o");
  require_above_horizon(theta_i.degrees, "theta_i");
}

Json measure_g2_record(const G2Request& r, const RunContext& ctx) {
  r.check();
  const auto t0 = std::chrono::steady_clock::now();
  G2Options go = estimator_options<G2Options>(r.rays, r.seed, ctx);
  go.replicates = r.replicates;
  Json j = estimator_record("measure g2", r.surfaces, ctx);
  j["parameters"] = {{"theta_o", r.theta_o.text}, {"phi_o", r.phi_o.text}, {"theta_i", r.theta_i.text},
                     {"phi_i", r.phi_i.text},     {"rays", r.rays},         {"seed", r.seed},
                     {"replicates", go.replicates},
                     {"normal_bins", {{"theta", go.normal_theta_bins}, {"phi", go.normal_phi_bins}}}};
  j["definitions"] = g2_definitions(r.surfaces.size() > 1);
  const std::size_t total = r.surfaces.size() * r.theta_o.degrees.size() * r.phi_o.degrees.size() *
                            r.theta_i.degrees.size() * r.phi_i.degrees.size();
  std::size_t done = 0;
  go.progress = [&](double f) {
    if (ctx.progress) ctx.progress((done + f) / total);
  };
  TraceCounters counters;
  double build_seconds = 0;
  std::vector<Table> per_surface = measure_each_surface(r.surfaces, [&](const Microsurface& s, std::size_t k) {
    if (k == 0) {
      const bool grooves = is_vcavity(s);
      j["surface"] = s.description;
      j["groove_by_groove"] = grooves;
      if (grooves) j["definitions"]["groove_by_groove"] = kGrooveByGroove;
    }
    return g2_surface_rows(r, s, go, counters, build_seconds, done);
  });
  j["build_seconds"] = build_seconds;
  put_rows(j, r.surfaces, per_surface);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  j["wall_seconds"] = wall;
  j["total_rays"] = counters.rays;
  j["rays_per_second"] = counters.rays / wall;
  j["lost_rays"] = counters.lost_below + counters.unresolved;
  j["backface_hits"] = counters.backface_hits;
  return j;
}

}  // namespace microsim
