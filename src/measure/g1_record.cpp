// The G1 table (g1_table) and its rows (add_row): both estimators' G1 of a view beside the
// models on the surface's own facets, per normal bin and summed over the bins.
#include "microsim/measure/g1_measure.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "microsim/measure/stats.hpp"

namespace microsim {

namespace {

double per_replicate(std::uint64_t total, int R) { return static_cast<double>(total) / R; }

}  // namespace

Estimate G1Result::g1_area_sampling() const {
  return replicate_mean(sample_visible_r, 1.0 / per_replicate(sample_rays, replicates));
}

Estimate G1Result::g1_raycast() const {
  const double k = front_projected > 0 ? window_area_perp / front_projected : 0;
  return replicate_mean(raycast_hits_r, k / per_replicate(raycast_rays, replicates));
}

Estimate G1Result::visible_area_ratio() const {
  const double denom = std::abs(v.z()) * total_area_macro();  // |v.n| A (undersurface: v.n < 0)
  const double k = denom > 0 ? window_area_perp / denom : 0;
  return replicate_mean(raycast_hits_r, k / per_replicate(raycast_rays, replicates));
}

Estimate G1Result::bin_g1_area_sampling(int b) const {
  // visible / samples of the bin: a ratio whose denominator varies between replicates.
  return replicate_ratio(bins[b].visible_r, bins[b].samples_r);
}

Estimate G1Result::bin_g1_raycast(int b) const {
  const double k = bins[b].front_projected > 0 ? window_area_perp / bins[b].front_projected : 0;
  Estimate e = replicate_mean(bins[b].raycast_hits_r, k / per_replicate(raycast_rays, replicates));
  e.n = bins[b].raycast_hits;
  return e;
}

Table g1_table() {
  Table t;
  t.error = ErrorKind::Replicates;
  const ErrorKind R = ErrorKind::Replicates, N = ErrorKind::None;
  t.spec.columns = {
      {"theta_deg", Merge::Copy, N, "deg", "view zenith angle, from the macrosurface normal (> 90: the undersurface of a mesh)"},
      {"phi_deg", Merge::Copy, N, "deg", "view azimuth"},
      {"surfaces", Merge::Count, N, "count", "number of surfaces K averaged (ensembles only), with t_dof = K - 1 after it"},
      {"replicates", Merge::Copy, N, "count", "independent randomized replicates the rays are split into"},
      {"g1", Merge::Measured, R, "1",
       "G1 by area sampling: fraction of points, drawn by projected area A_f max(0, v.m_f), unoccluded toward v"},
      {"g1_raycast", Merge::Measured, R, "1",
       "G1 by ray casting: visible projected area of the first hits along -v / sum_f A_f max(0, v.m_f)"},
      {"visible_area_ratio", Merge::Measured, R, "1",
       "visible projected area / ((v.n) A), A the macrosurface area; 1 at theta = 0 for a valid periodic surface"},
      {"smith_numeric", Merge::Spread, N, "1",
       "Smith G1 = 1 / (1 + Lambda) with Lambda from the surface's own facets, sum_f A_f max(0, -v.m_f) / ((v.n) A)"},
      {"smith_nominal", Merge::Copy, N, "1", "Smith G1 of the generator's nominal NDF (null without one)"}};
  t.spec.comparisons = {
      {"g1", "smith_nominal", ModelKind::Nominal, "z_nominal", "rel_dev_nominal", "p_nominal"},
      {"g1", "smith_numeric", ModelKind::Facets, "z_numeric", "", ""}};
  t.spec.bin_columns = {
      {"theta_m_range_deg", Merge::Key, N, "deg", "zenith range [lo, hi] of the normal bin"},
      {"phi_m_range_deg", Merge::Key, N, "deg", "azimuth range [lo, hi] of the normal bin"},
      {"m", Merge::Direction, N, "1", "mean unit normal [x, y, z] of the bin's facets"},
      {"area_fraction", Merge::Mean, N, "1", "the bin's share of the surface's facet area"},
      {"g1", Merge::Spread, R, "1", "G1 of the bin's facets by area sampling (0 where they all face away from v)"},
      {"g1_raycast", Merge::Spread, R, "1", "G1 of the bin's facets by ray casting"}};
  t.spec.row_fields = {
      {"visible_projected_area", Merge::Copy, R, "length^2", "visible projected area, perpendicular to v, in the surface's units"},
      {"macro_projected_area", Merge::Copy, N, "length^2", "|v.n| A"},
      {"eq_2b", Merge::Copy, R, "1",
       "theta = 0 only: visible_area_ratio, which is the integral of (n.m) G1(n, m) D(m) over the sphere (1 for a "
       "valid periodic surface)"},
      {"lambda_numeric", Merge::Copy, N, "1", "Smith Lambda(v) from the surface's own facets"},
      {"rays", Merge::Copy, N, "count", "rays cast by the ray-casting estimator"},
      {"area_samples", Merge::Copy, N, "count", "points drawn by the area-sampling estimator"},
      {"border_crossings", Merge::Copy, N, "count", "periodic wrap-arounds of the rays"},
      {"bins_dof", Merge::Copy, N, "count", "normal bins with area-sampling points (facing v)"},
      {"bins_chi2_smith", Merge::Copy, N, "1",
       "sum over those bins of ((g1 - smith_numeric) / error)^2, the error at least the resolution of the bin's points"},
      {"bins_chi2_vcavity", Merge::Copy, N, "1", "the same against the bins' vcavity_numeric"},
      {"bins_mad_smith", Merge::Copy, N, "1",
       "mean |g1 - smith_numeric| over the bins, weighted by their projected area facing v"},
      {"bins_mad_vcavity", Merge::Copy, N, "1", "the same against vcavity_numeric"},
      {"bins_mad_noise", Merge::Copy, N, "1", "the same mean of the bins' errors times sqrt(2 / pi): what noise alone gives"},
      {"max_abs_z_estimators", Merge::Copy, N, "1", "largest |z_estimators| over the bins"},
      {"undersurface", Merge::Copy, N, "", "true on rows of the undersurface of a mesh (theta > 90)"},
      {"g1_reverse_v", Merge::Copy, R, "1", "undersurface rows: the surface's own G1 at -v, an approximation of g1"},
      {"g1_reflect_v", Merge::Copy, R, "1",
       "undersurface rows: the surface's own G1 at v reflected across the macrosurface, the other approximation"},
      {"z_reverse_v", Merge::Copy, N, "1", "(g1_reverse_v - g1) / their combined error (rel_dev_reverse_v: / g1)"},
      {"z_reflect_v", Merge::Copy, N, "1", "(g1_reflect_v - g1) / their combined error (rel_dev_reflect_v: / g1)"}};
  for (const Column& c : tracer_count_fields(true)) t.spec.row_fields.push_back(c);
  t.spec.bin_fields = {
      {"z_estimators", Merge::Copy, N, "1", "(g1 - g1_raycast) / their combined error"},
      {"smith_numeric", Merge::Copy, N, "1", "the row's smith_numeric (Smith G1 does not depend on m)"},
      {"vcavity_numeric", Merge::Copy, N, "1", "V-cavity G1 averaged over the bin's facets by projected area facing v"}};
  return t;
}

namespace {

// The row's estimates: G1 by both estimators, the visible area and the models beside them.
void put_g1_estimates(Json& row, const G1Result& r, const Microsurface& s) {
  Estimate g = r.g1_area_sampling(), gr = r.g1_raycast(), var = r.visible_area_ratio();
  row["g1"] = g.mean;
  row["g1_stderr"] = g.stderr_;
  row["g1_raycast"] = gr.mean;
  row["g1_raycast_stderr"] = gr.stderr_;
  row["visible_area_ratio"] = var.mean;
  row["visible_area_ratio_stderr"] = var.stderr_;
  // In absolute units (surface units squared), perpendicular to v: hits / rays x window area.
  {
    const Estimate p = replicate_mean(r.raycast_hits_r, 1.0 / per_replicate(r.raycast_rays, r.replicates));
    row["visible_projected_area"] = p.mean * r.window_area_perp;
    row["visible_projected_area_stderr"] = p.stderr_ * r.window_area_perp;
    row["macro_projected_area"] = std::abs(r.v.z()) * r.macro_area;  // |v.n| A
  }
  if (r.theta == 0.0) {  // [GeomBSDF24, eq. 2b]: int (n.m) G1(n, m) D(m) dm = visible area along n / A
    row["eq_2b"] = var.mean;
    row["eq_2b_stderr"] = var.stderr_;
  }
  row["lambda_numeric"] = r.lambda_numeric;
  double smith_numeric = 1.0 / (1.0 + r.lambda_numeric);
  row["smith_numeric"] = smith_numeric;
  row["z_numeric"] = z_json(g.mean, smith_numeric, g.stderr_);
  if (s.nominal) {
    // Undersurface rows: the nominal model with v reversed [GeomBSDF24, "Inherent Assumptions"].
    double model = s.nominal->G1(r.undersurface ? Vec3(-r.v) : r.v);
    row["smith_nominal"] = model;
    row["rel_dev_nominal"] = (g.mean - model) / model;
  } else {
    row["smith_nominal"] = nullptr;
    row["rel_dev_nominal"] = nullptr;
  }
}

// The rays and what the tracer counted of them.
void put_g1_ray_counts(Json& row, const G1Result& r, const Microsurface& s) {
  row["rays"] = r.raycast_rays;
  row["area_samples"] = r.sample_rays;
  row["replicates"] = r.replicates;
  if (s.macro().region) {  // a measured window: rays that met its side walls (Tracer rule)
    row["side_exits"] = r.counters.side_exits;
    row["side_entries"] = r.counters.side_entries;
  }
  if (!s.macro().finite_object()) {
    row["lost_rays"] = r.counters.lost_below + r.counters.unresolved;
  } else {
    // A finite object: window rays that pass beside it are misses, not losses.
    row["lost_rays"] = r.counters.unresolved;
    row["missed_rays"] = r.counters.lost_below;
  }
  row["backface_hits"] = r.counters.backface_hits;
  row["border_crossings"] = r.counters.border_crossings;
  row["trace_counters"] = fields_json(r.counters);  // every counter, as TraceCounters declares them
  row["seconds"] = r.seconds;
}

// The deviations of the bins' G1 from the models on their own facets (bins_* fields).
struct BinDeviations {
  double chi2_smith = 0, chi2_vcav = 0, mad_smith = 0, mad_vcav = 0, mad_noise = 0, max_abs_z = 0;
  int dof = 0;
};

// Bin b (holding facets) with its estimates and models, added to the deviations `d` (weights
// w of projected area facing v over `wsum`).
Json g1_bin_json(const G1Result& r, int b, double wsum, BinDeviations& d) {
  const G1NormalBin& nb = r.bins[b];
  Json jb;
  jb["m"] = {nb.mean_normal.x(), nb.mean_normal.y(), nb.mean_normal.z()};
  int it = b / r.binning.n_phi(), ip = b % r.binning.n_phi();
  if (r.undersurface)  // labelled by the undersurface normal -m (theta measured from +z)
    jb["theta_m_range_deg"] = {180 - deg(r.binning.theta_hi(it)), 180 - deg(r.binning.theta_lo(it))};
  else
    jb["theta_m_range_deg"] = {deg(r.binning.theta_lo(it)), deg(r.binning.theta_hi(it))};
  jb["phi_m_range_deg"] = {deg(r.binning.phi_lo(ip)), deg(r.binning.phi_hi(ip))};
  jb["area_fraction"] = nb.area / r.total_area;
  if (!(nb.front_projected > 0 && nb.samples > 0)) {
    jb["g1"] = 0.0;  // back-facing to v: G1(v, m) = 0 by definition
    jb["g1_stderr"] = 0.0;
    return jb;
  }
  Estimate eb = r.bin_g1_area_sampling(b), ea = r.bin_g1_raycast(b);
  jb["g1"] = eb.mean;
  jb["g1_stderr"] = eb.stderr_;
  jb["g1_raycast"] = ea.mean;
  jb["g1_raycast_stderr"] = ea.stderr_;
  const double z = z_score(eb.mean, ea.mean, std::hypot(eb.stderr_, ea.stderr_));
  jb["z_estimators"] = z_json(eb.mean, ea.mean, std::hypot(eb.stderr_, ea.stderr_));
  if (std::isfinite(z)) d.max_abs_z = std::max(d.max_abs_z, std::abs(z));
  const double smith = 1.0 / (1.0 + r.lambda_numeric);     // [GeomBSDF24, eq. 3Xc]: W1, no m dependence
  const double vcav = nb.vcavity_weighted / nb.front_projected;  // [Heitz14, eq. 24], bin average
  jb["smith_numeric"] = smith;
  jb["vcavity_numeric"] = vcav;
  const double w = nb.front_projected / wsum;
  d.mad_smith += w * std::abs(eb.mean - smith);
  d.mad_vcav += w * std::abs(eb.mean - vcav);
  d.mad_noise += w * eb.stderr_ * std::sqrt(2 / kPi);
  // A bin whose samples are all visible (or none) has a zero error: use the resolution of
  // its n samples instead (stats.hpp proportion_floor), so that chi^2 stays finite and honest.
  const double sb = std::max(eb.stderr_, proportion_floor(nb.samples));
  d.chi2_smith += std::pow((eb.mean - smith) / sb, 2);
  d.chi2_vcav += std::pow((eb.mean - vcav) / sb, 2);
  ++d.dof;
  return jb;
}

// Per-bin models on the bin's own facets, and the deviation of the measurement from each.
void put_g1_bins(Json& row, const G1Result& r) {
  Json bins = Json::array();
  BinDeviations d;
  double wsum = 0;
  for (int b = 0; b < r.binning.size(); ++b)
    if (r.bins[b].samples > 0) wsum += r.bins[b].front_projected;
  for (int b = 0; b < r.binning.size(); ++b)
    if (r.bins[b].area > 0) bins.push_back(g1_bin_json(r, b, wsum, d));
  row["bins_dof"] = d.dof;
  row["bins_chi2_smith"] = d.chi2_smith;
  row["bins_chi2_vcavity"] = d.chi2_vcav;
  row["bins_mad_smith"] = d.mad_smith;
  row["bins_mad_vcavity"] = d.mad_vcav;
  row["bins_mad_noise"] = d.mad_noise;
  row["max_abs_z_estimators"] = d.max_abs_z;
  row["bins"] = bins;
}

}  // namespace

Json& add_row(Table& t, const G1Result& r, const Microsurface& s) {
  t.rows.push_back(Json::object());
  Json& row = t.rows.back();
  row["theta_deg"] = deg(r.theta);
  row["phi_deg"] = deg(r.phi);
  put_g1_estimates(row, r, s);
  put_g1_ray_counts(row, r, s);
  put_g1_bins(row, r);
  return row;
}

void add_undersurface_approximations(Json& row, const G1Result& under, const G1Result& reverse_v,
                                     const G1Result& reflect_v) {
  row["undersurface"] = true;
  const Estimate g = under.g1_area_sampling();
  for (auto [name, e] : {std::pair<std::string, Estimate>{"reverse_v", reverse_v.g1_area_sampling()},
                         std::pair<std::string, Estimate>{"reflect_v", reflect_v.g1_area_sampling()}}) {
    row["g1_" + name] = e.mean;
    row["g1_" + name + "_stderr"] = e.stderr_;
    row["z_" + name] = z_json(e.mean, g.mean, std::hypot(g.stderr_, e.stderr_));
    row["rel_dev_" + name] = rel_dev_json(e.mean, g.mean);
  }
}

}  // namespace microsim
