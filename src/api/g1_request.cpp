#include "microsim/api/g1_request.hpp"

#include <chrono>

#include "microsim/api/estimator_record.hpp"
#include "microsim/api/request_checks.hpp"
#include "microsim/measure/g1_views.hpp"
#include "microsim/surface/microsurface.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

namespace {

const char* const kVcavityDefinition =
    "[Heitz14, Sec. 6.1] made explicit: each groove of the ensemble (normals m, m' drawn from "
    "(n.m) D(m)) is traced on its own as an infinite periodic V-groove; ray casting uses the "
    "same number of rays per groove (equal macro areas), area sampling draws points over the "
    "whole ensemble by front-facing projected area; counts are pooled per normal bin. "
    "vcavity_numeric is [Heitz14, eq. 24] on the same normals";

Json g1_definitions(bool ensemble) {
  return {
      {"g1", "area sampling: fraction of points, drawn by projected area A_f max(0,v.m_f), "
             "unoccluded toward v (estimator b of docs/theory/masking.md)"},
      {"g1_raycast", "visible projected area of first hits along -v / sum_f A_f max(0,v.m_f) "
                     "(estimator a)"},
      {"visible_area_ratio", "visible projected area / ((v.n) A); visible_projected_area is the "
                             "same in absolute units, macro_projected_area = |v.n| A"},
      {"smith_numeric", "1/(1+Lambda), Lambda = sum_f A_f max(0,-v.m_f) / ((v.n) A)"},
      {"smith_nominal", "Smith G1 of the generator's nominal NDF ([Heitz14, eq. 11] with alpha_o); "
                        "undersurface rows: at -v"},
      {"bins", "per normal bin: g1, g1_raycast, smith_numeric (1/(1+lambda_numeric) for "
               "front-facing bins) and vcavity_numeric ([Heitz14, eq. 24] averaged over the bin's facets "
               "by front-facing projected area); bins_mad_* and bins_chi2_* summarise the "
               "deviation of g1 from each model over the bins"},
      {"undersurface", "theta > 90 (meshes): g1 is the explicit measurement of the undersurface "
                       "(the sheet with reversed normals seen from v); g1_reverse_v and "
                       "g1_reflect_v are the surface's own G1 at -v and at v reflected across the "
                       "macrosurface, the two approximations of [GeomBSDF24, 'Inherent Assumptions']"},
      {"eq_2b", "the visible_area_ratio at theta = 0 is [GeomBSDF24, eq. 2b], int (n.m) G1(n,m) D(m) dm; "
                "1 for a valid periodic microsurface"},
      {"z_numeric", "(g1 - smith_numeric) / the ray-count error (g1_stderr; ensembles: "
                    "g1_stderr_rays), since the model comes from each surface's own facets; "
                    "z_nominal and p_nominal (ensembles) use the between-surface error and "
                    "Student t with K - 1 degrees of freedom; a zero error gives a null z"},
      {"stderr", replicate_stderr_definition(ensemble)}};
}

// What the surfaces' measurements add up to beside their rows.
struct G1Totals {
  TraceCounters counters;
  double build_seconds = 0;
  bool periodic = true;  // every ray from above meets the surface (not a finite object)
};

// Every surface's table of rows (views: phi outer, theta inner), its first surface's description
// and V-cavity definition put into j.
std::vector<Table> measure_g1_surfaces(const G1Request& r, const G1Options& go, const RunContext& ctx, Json& j,
                                       G1Totals& totals) {
  std::vector<Vec3> views;
  for (double p : r.phi.degrees)
    for (double t : r.theta.degrees) views.push_back(direction_from_angles(rad(t), rad(p)));
  const double total = static_cast<double>(r.surfaces.size() * views.size());
  return measure_each_surface(r.surfaces, [&](const Microsurface& s, std::size_t k) {
    const double before = static_cast<double>(k * views.size());
    G1Views m = measure_g1_views(s, views, go, [&](double done) {
      if (ctx.progress) ctx.progress((before + done) / total);
    });
    if (k == 0) {
      j["surface"] = s.description;
      totals.periodic = !s.macro().finite_object();
      if (m.vcavity) j["definitions"]["vcavity"] = kVcavityDefinition;
    }
    totals.counters += m.counters;
    totals.build_seconds += m.build_seconds;
    std::size_t i = 0;
    for (double p : r.phi.degrees)
      for (double t : r.theta.degrees) {
        m.table.rows[i]["theta_deg"] = t;  // exactly as requested (no round trip through radians)
        m.table.rows[i++]["phi_deg"] = p;
      }
    return std::move(m.table);
  });
}

}  // namespace

void G1Request::check() const {
  if (surfaces.empty()) throw UsageError("no surface given");
  require_rays_and_replicates(rays, replicates);
  for (double t : theta.degrees)
    if (!(t >= 0 && t <= 180) || t == 90)
      throw ParameterError("{theta} must be in [0, 90) degrees, or (90, 180] for the undersurface of a "
                           "mesh (got " + fixed_text(t, 2) + ")");
}

Json measure_g1_record(const G1Request& r, const RunContext& ctx) {
  r.check();
  const auto t0 = std::chrono::steady_clock::now();
  G1Options go = estimator_options<G1Options>(r.rays, r.seed, ctx);
  go.replicates = r.replicates;
  Json j = estimator_record("measure g1", r.surfaces, ctx);
  j["surface"] = nullptr;  // the first surface's description (filled when measured, kept in this place)
  j["parameters"] = {{"theta", r.theta.text}, {"phi", r.phi.text}, {"rays", r.rays}, {"seed", r.seed},
                     {"replicates", go.replicates},
                     {"normal_bins", {{"theta", go.normal_theta_bins}, {"phi", go.normal_phi_bins}}}};
  j["definitions"] = g1_definitions(r.surfaces.size() > 1);
  G1Totals totals;
  const std::vector<Table> per_surface = measure_g1_surfaces(r, go, ctx, j, totals);
  const TraceCounters& c = totals.counters;
  j["build_seconds"] = totals.build_seconds;
  put_rows(j, r.surfaces, per_surface);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  j["wall_seconds"] = wall;
  j["total_rays"] = c.rays;
  j["rays_per_second"] = c.rays / wall;
  // Finite objects: window rays passing beside the object are misses, not losses.
  j["lost_rays"] = totals.periodic ? c.lost_below + c.unresolved : c.unresolved;
  if (!totals.periodic) j["missed_rays"] = c.lost_below;
  j["backface_hits"] = c.backface_hits;
  return j;
}

}  // namespace microsim
