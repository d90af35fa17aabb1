// Checks of D: the [GeomBSDF24, eq. 1b/1c] identities and D against the nominal NDF.
#include "checks_common.hpp"
#include "microsim/surface/rounding_bound.hpp"

namespace microsim::validation {

// ---------------------------------------------------------------------------------------------
// D identities: [GeomBSDF24, eq. 1b] (sum_f A_f m_f / A = n) and eq. 1c (sum_f A_f (n.m_f) / A = 1).
void check_d_identities(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  Json per_surface = Json::array();
  for (std::size_t k = 0; k < set.surfaces.size(); ++k) {
    const Microsurface& s = set.surfaces[k];
    const FacetSums f = facet_sums(s);
    const Macrosurface& m = s.macro();
    // Bound on the double rounding of a sum of N terms (|error| <= N eps sum |terms|, with a
    // factor 2 for the cross products that make the terms): the identities hold exactly for
    // any float-valued vertices of a closed (or bit-exactly periodic) surface. An open mesh
    // boundary (the V-cavity's strips) adds what the float rounding of its vertices can move
    // the sums by (surface/rounding_bound.hpp), computed from the vertices themselves.
    const double eps = std::numeric_limits<double>::epsilon();
    const double tol = 2.0 * (static_cast<double>(s.num_facets()) + 3.0) * eps * f.total_area / m.area;
    const FacetSumRounding rounding = facet_sum_rounding_bound(s);
    const Vec3 tol_axis = Vec3::Constant(tol) + rounding.bound / m.area;
    const Vec3 b = f.sum_area_normal / m.area;
    const char* axis[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      // A measured window's interior is not closed: its x, y sums are the net height change
      // across it over A (the interior's mean slope), reported, not tested; z is eq. 1c's.
      const bool open_region = m.region && !m.periodic && a < 2;
      Row r = make_row(set, surface_label(set, k), std::string("eq_1b_") + axis[a], "macro_normal",
                       open_region ? Kind::Info : Kind::Deterministic,
                       open_region ? "[GeomBSDF24, eq. 1b] (a window's interior: its mean slope, not an identity)" : "[GeomBSDF24, eq. 1b]");
      r.measured = b[a];
      r.model = m.normal[a];
      r.tolerance = tol_axis[a];
      r.error = "rounding";
      r.group = set.name + "/eq_1b";
      r.condition += (r.condition.empty() ? "" : ", ") + std::string("sum A_f m_f.") + axis[a] + " / A";
      out.rows.push_back(r);
    }
    Row c = make_row(set, surface_label(set, k), "eq_1c", "one", Kind::Deterministic, "[GeomBSDF24, eq. 1c]");
    c.measured = f.sum_area_cos / m.area;
    c.model = 1.0;
    c.tolerance = tol_axis.z();
    c.error = "rounding";
    c.group = set.name + "/eq_1c";
    c.condition += ", sum A_f (n.m_f) / A";
    out.rows.push_back(c);
    per_surface.push_back({{"label", set.labels[k]},
                           {"sum_area_normal_over_A", {b.x(), b.y(), b.z()}},
                           {"sum_area_cos_over_A", f.sum_area_cos / m.area},
                           {"total_area_over_A", f.total_area / m.area},
                           {"tolerance", tol},
                           {"tolerance_axis", {tol_axis.x(), tol_axis.y(), tol_axis.z()}},
                           {"vertex_rounding_bound_over_A",
                            {rounding.bound.x() / m.area, rounding.bound.y() / m.area, rounding.bound.z() / m.area}},
                           {"open_boundary_vertices", rounding.open_vertices},
                           {"boundary_half_edges", rounding.boundary_half_edges},
                           {"seam_matched_half_edges", rounding.seam_matched}});
    progress.completed += 0.1 * static_cast<double>(s.num_facets());
    progress.update();
  }
  out.measurements = per_surface;
}

namespace {
// The nominal D averaged over theta ring it (phi-averaged bin averages).
double nominal_ring_d(const DirectionBinning& bins, const models::Ndf& nominal, int it) {
  double model = 0;
  for (int ip = 0; ip < bins.n_phi(); ++ip)
    model += bins.bin_average(bins.index(it, ip), [&](const Vec3& m) { return nominal.D(m); });
  return model / bins.n_phi();
}

// D of ring it and its error: one surface's with its block error, or the ensemble mean with the
// between-surface error.
std::pair<double, double> measured_ring_d(const std::vector<NdfResult>& res, int it) {
  const std::size_t K = res.size();
  if (K == 1) return {res[0].ring_d[it], res[0].ring_d_stderr[it]};
  std::vector<double> x;
  double blocks2 = 0;
  for (const auto& r : res) {
    x.push_back(r.ring_d[it]);
    blocks2 += r.ring_d_stderr[it] * r.ring_d_stderr[it];
  }
  double d, se;
  std::tie(d, se) = mean_and_se(x);
  // Floor: the within-surface (block) error of the mean, in case K values agree by chance.
  se = std::max(se, std::sqrt(blocks2) / static_cast<double>(K));
  return {d, se};
}

std::string d_label(const SurfaceSet& set, std::size_t K) {
  return K > 1 ? std::to_string(K) + " surfaces" : surface_label(set, 0);
}

Row ring_row(const SurfaceSet& set, std::size_t K, double lo, double hi, double d, double se, double model) {
  Row r = make_row(set, d_label(set, K), "d_ring", "nominal", Kind::Model, "[Heitz14, Sec. 3.2] Beckmann D, bin-averaged");
  r.condition += (K > 1 || !surface_label(set, 0).empty() ? ", " : " ") + std::string("theta_m ") +
                 angle(lo) + "-" + angle(hi);
  r.measured = d;
  r.stderr_ = se;
  r.model = model;
  r.error = K > 1 ? "surfaces" : "blocks";
  if (K > 1) r.dof = static_cast<int>(K) - 1;
  r.group = set.name + "/d_ring";
  r.extra = {{"theta_m_range_deg", {lo, hi}}};
  return r;
}

// Moment fit of alpha (slope variance alpha^2/2 per axis, [Heitz14, Sec. 3.2, App. A]) vs the
// nominal alpha: rows, and each surface's fitted alphas into the record.
void push_fitted_alpha_rows(const SurfaceSet& set, const std::vector<FacetSums>& sums, const models::Ndf& nominal,
                            Json& ndf, CheckOutput& out) {
  const std::size_t K = sums.size();
  for (int a = 0; a < 2; ++a) {
    std::vector<double> x;
    for (const auto& f : sums) x.push_back(std::sqrt(2 * (a == 0 ? f.slope_var_x : f.slope_var_y)));
    auto [mean, se] = mean_and_se(x);
    Row r = make_row(set, d_label(set, K), a == 0 ? "fitted_alpha_x" : "fitted_alpha_y", "nominal",
                     K > 1 ? Kind::Model : Kind::Info, "[Heitz14, Sec. 3.2 and App. A]: P22 dslope = (n.m) D dm, Beckmann slope variance alpha^2/2 per axis");
    r.measured = mean;
    if (K > 1) {
      r.stderr_ = se;
      r.dof = static_cast<int>(K) - 1;
    }
    r.model = a == 0 ? nominal.alpha_x : nominal.alpha_y;
    r.error = K > 1 ? "surfaces" : "none (one surface)";
    out.rows.push_back(r);
    ndf[a == 0 ? "fitted_alpha_x" : "fitted_alpha_y"] = x;
  }
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// D against the generator's nominal NDF, per theta ring (phi-averaged). One surface: the
// spatial-block standard error of measure_ndf; an ensemble: the between-surface one.
void check_d_nominal(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  const Options& o = set.options;
  const models::Ndf& nominal = *set.surfaces[0].nominal;
  NdfOptions no;
  no.n_theta = o.ndf_theta_bins;
  no.n_phi = o.ndf_phi_bins;
  std::vector<NdfResult> res;
  std::vector<FacetSums> sums;
  for (const Microsurface& s : set.surfaces) {
    res.push_back(measure_ndf(s, no));
    sums.push_back(res.back().sums);
    progress.completed += 0.2 * static_cast<double>(s.num_facets());
    progress.update();
  }
  const std::size_t K = res.size();
  const DirectionBinning& bins = res[0].bins;
  Json ndf = {{"theta_lo_deg", Json::array()}, {"theta_hi_deg", Json::array()},
              {"d", Json::array()}, {"d_stderr", Json::array()}, {"d_nominal", Json::array()},
              {"error", K > 1 ? "surfaces" : "blocks"}, {"surfaces", K},
              {"nominal", std::string(models::to_string(nominal.kind))},
              {"alpha_x", nominal.alpha_x}, {"alpha_y", nominal.alpha_y}};
  for (int it = 0; it < bins.n_theta(); ++it) {
    const double model = nominal_ring_d(bins, nominal, it);
    const auto [d, se] = measured_ring_d(res, it);
    const double lo = deg(bins.theta_lo(it)), hi = deg(bins.theta_hi(it));
    ndf["theta_lo_deg"].push_back(lo);
    ndf["theta_hi_deg"].push_back(hi);
    ndf["d"].push_back(d);
    ndf["d_stderr"].push_back(se);
    ndf["d_nominal"].push_back(model);
    // Rings where the model puts at least min_ring_mass of the microsurface area (per unit
    // macro area) are tested; the far tails hold too few facets for a normal z.
    if (model * bins.solid_angle_of_ring(it) < o.min_ring_mass) continue;
    out.rows.push_back(ring_row(set, K, lo, hi, d, se, model));
  }
  push_fitted_alpha_rows(set, sums, nominal, ndf, out);
  out.measurements = ndf;
}

}  // namespace microsim::validation
