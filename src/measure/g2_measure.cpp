// The G2 estimator on a whole surface (its Tracer, one part), and the G2 table and rows.
#include "microsim/measure/g2_measure.hpp"

#include <algorithm>
#include <chrono>

#include "g2_estimator.hpp"
#include "microsim/measure/facet_table.hpp"
#include "microsim/measure/stats.hpp"

namespace microsim {

namespace {

// The exact facet sums of r.bins at (r.o, r.i), r.total_area, r.front_area, r.lambda_o and
// r.lambda_i (deterministic parallel sums over the surface's facets); returns the V-cavity sum
// over every bin.
double sum_g2_facets_per_bin(G2Result& r, const FacetTable& ft, const Microsurface& s) {
  const int nbins = r.binning.size();
  const Vec3 o = r.o, i = r.i;
  // Per bin: area, area facing both, weight w_f, w-weighted normal (3), V-cavity sum; then the
  // back-facing projected areas toward o and toward i.
  constexpr std::size_t kW = 7;
  const std::size_t width = kW * static_cast<std::size_t>(nbins) + 2;
  const std::vector<double> sums = sum_over_facets(s.num_facets(), width, [&](std::size_t k, double* acc) {
    Vec3 m;
    double a;
    ft.normal_area(k, m, a);
    const G2FacetTerms t = g2_facet_terms(o, i, m, a);
    double* bin = acc + kW * static_cast<std::size_t>(ft.bin(k));
    bin[0] += a;
    if (t.front) {
      bin[1] += a;
      bin[2] += t.weight;
      bin[3] += t.weight * m.x();
      bin[4] += t.weight * m.y();
      bin[5] += t.weight * m.z();
      bin[6] += t.vcavity;
    }
    acc[width - 2] += t.back_o;
    acc[width - 1] += t.back_i;
  });
  double vcav_total = 0;
  for (int b = 0; b < nbins; ++b) {
    const double* bin = sums.data() + kW * static_cast<std::size_t>(b);
    G2NormalBin& nb = r.bins[b];
    nb.area = bin[0];
    nb.front_area = bin[1];
    nb.weight = bin[2];
    nb.mean_normal = Vec3(bin[3], bin[4], bin[5]);
    if (nb.mean_normal.norm() > 0) nb.mean_normal.normalize();
    nb.vcavity_sum = bin[6];
    r.total_area += bin[0];
    r.front_area += bin[1];
    vcav_total += bin[6];
  }
  // Lambda(v) = sum_f A_f max(0, -v.m_f) / ((v.n) A)   [Heitz14, App. A]
  const Vec3 n = s.macro().normal;
  r.lambda_o = sums[width - 2] / (o.dot(n) * s.macro().area);
  r.lambda_i = sums[width - 1] / (i.dot(n) * s.macro().area);
  return vcav_total;
}

// w_f of facet k from its 2 A_f m_f, without a square root (g2_facet_terms' weight).
struct CrossWeight {
  const FacetTable& ft;
  Vec3 o, i;
  double operator()(std::size_t k) const {
    const Vec3 c = ft.cross(k);
    const double oc = o.dot(c), ic = i.dot(c);
    return oc > 0 && ic > 0 ? 0.25 * (oc + ic) : 0.0;
  }
};

// A whole surface as the estimator's one part, traced in the world frame. The points are drawn
// along the CDF of w_f computed block by block (BlockFacetSampler, in facet order: spatially
// coherent), every replicate's points on its facets.
class SurfacePoints : public G2Points {
 public:
  SurfacePoints(const Tracer& tracer, const FacetTable& ft, const Vec3& o, const Vec3& i, std::uint64_t per_replicate)
      : tracer_(tracer), ft_(ft), weight_{ft, o, i}, n_(per_replicate), sampler_(tracer.surface().num_facets(), weight_) {}
  double total() const { return sampler_.total(); }
  std::uint64_t stream() const override { return pair_stream(weight_.o, weight_.i, 0xC2000000ull); }
  std::size_t parts() const override { return 1; }
  std::unique_ptr<Scene> scene(std::size_t) const override { return make_scene(tracer_); }
  Vec3 to_local(std::size_t, const Vec3& w) const override { return w; }
  UnitRange facets(std::size_t) const override { return {0, tracer_.surface().num_facets()}; }
  UnitRange points_on(int, UnitRange) const override { return {0, n_}; }
  std::size_t place(int, std::uint64_t j, CounterRng& rng) const override {
    const double u = (static_cast<double>(j) + rng.uniform()) / n_ * sampler_.total();
    return sampler_.draw(u, weight_);
  }
  int bin(std::size_t f) const override { return ft_.bin(f); }
  bool buried(std::size_t f) const override { return ft_.buried(f); }

 private:
  const Tracer& tracer_;
  const FacetTable& ft_;
  CrossWeight weight_;
  std::uint64_t n_;
  BlockFacetSampler sampler_;
};

}  // namespace

G2Result measure_g2(const Tracer& tracer, const Vec3& o_in, const Vec3& i_in, const G2Options& opt,
                    const FacetTable* table) {
  const Microsurface& s = tracer.surface();
  G2Result r = start_g2(o_in, i_in, opt, s.macro().area);
  const auto t0 = std::chrono::steady_clock::now();
  FacetTable own;
  const FacetTable& ft = facet_table_for(s, r.binning, table, own);
  const double vcav_total = sum_g2_facets_per_bin(r, ft, s);
  const ReplicatePlan plan = plan_g2(r, opt);
  const SurfacePoints points(tracer, ft, r.o, r.i, plan.per_replicate());
  r.weight = points.total();
  if (!(r.weight > 0)) throw RuntimeFailure("no facet faces both directions");
  r.vcavity = vcav_total / r.weight;
  trace_g2_points(points, r, opt, plan);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

namespace {
const char* const kForms[] = {"separable", "height_correlated", "direction_correlated",
                              "height_direction_correlated"};
}  // namespace

// Ensemble rows: means over surfaces with between-surface errors. Models from each surface's own
// facets are compared with the ray-count error (the difference g2 - model is per surface, its
// spread is the ray noise); nominal models with the between-surface error.
Table g2_table() {
  Table t;
  t.error = ErrorKind::Replicates;
  const ErrorKind R = ErrorKind::Replicates, N = ErrorKind::None;
  const std::string weight = "points drawn with density A_f (o.m_f + i.m_f) / 2 on the facets facing both o and i";
  auto& c = t.spec.columns;
  c = {{"theta_o_deg", Merge::Copy, N, "deg", "view (outgoing) zenith angle"},
       {"phi_o_deg", Merge::Copy, N, "deg", "view azimuth"},
       {"theta_i_deg", Merge::Copy, N, "deg", "light (incoming) zenith angle"},
       {"phi_i_deg", Merge::Copy, N, "deg", "light azimuth"},
       {"delta_phi_deg", Merge::Copy, N, "deg", "azimuth difference between o and i, in [0, 180]"},
       {"surfaces", Merge::Count, N, "count", "number of surfaces K averaged (ensembles only), with t_dof = K - 1 after it"},
       {"replicates", Merge::Copy, N, "count", "independent randomized replicates the points are split into"},
       {"g2", Merge::Measured, R, "1", "G2(o, i): fraction of the " + weight + " unoccluded toward o and toward i"},
       {"g1_o", Merge::Measured, R, "1", "fraction of the same points unoccluded toward o"},
       {"g1_i", Merge::Measured, R, "1", "fraction of the same points unoccluded toward i"},
       {"half_bin_theta_m_range_deg", Merge::Copy, N, "deg", "zenith range of the normal bin holding the half vector (o + i) / |o + i|"},
       {"half_bin_phi_m_range_deg", Merge::Copy, N, "deg", "azimuth range of that bin"},
       {"g2_half", Merge::Measured, R, "1",
        "g2 of the half vector's bin, the G2(o, h, i) of a specular microfacet BRDF (null below 100 samples)"},
       {"lambda_o_numeric", Merge::Spread, N, "1", "Smith Lambda(o) from the surface's own facets"},
       {"lambda_i_numeric", Merge::Spread, N, "1", "Smith Lambda(i) from the surface's own facets"}};
  const char* const form_meaning[] = {"separable", "height-correlated", "direction-correlated",
                                      "height-direction-correlated"};
  for (int k = 0; k < 4; ++k)
    c.push_back({std::string("smith_") + kForms[k], Merge::Spread, N, "1",
                 std::string("Smith G2, ") + form_meaning[k] + " form, with Lambda from the surface's own facets"});
  c.push_back({"vcavity", Merge::Spread, N, "1",
               "V-cavity G2 averaged over the surface's facets facing both o and i, weighted like g2"});
  for (int k = 0; k < 4; ++k)
    c.push_back({std::string("smith_") + kForms[k] + "_nominal", Merge::Copy, N, "1",
                 std::string("Smith G2, ") + form_meaning[k] + " form, of the generator's nominal NDF (null without one)"});
  for (int k = 0; k < 4; ++k) {
    c.push_back({std::string(kForms[k]) + "_from_g1", Merge::Spread, N, "1",
                 std::string("the ") + form_meaning[k] + " form built in each normal bin from the bin's measured "
                 "g1_o and g1_i, averaged over the bins with the weights of g2"});
    c.push_back({std::string(kForms[k]) + "_from_g1_diff", Merge::Measured, ErrorKind::Jackknife, "1",
                 std::string("bin average of g2 - ") + kForms[k] + "_from_g1: the test of the correlation the form assumes"});
  }
  auto& z = t.spec.comparisons;
  for (const char* f : kForms)
    z.push_back({"g2", std::string("smith_") + f, ModelKind::Facets, std::string("z_") + f, "", ""});
  z.push_back({"g2", "vcavity", ModelKind::Facets, "z_vcavity", "", ""});
  for (const char* f : kForms)
    z.push_back({"g2", std::string("smith_") + f + "_nominal", ModelKind::Nominal,
                 std::string("z_") + f + "_nominal", "", std::string("p_") + f + "_nominal"});
  for (const char* f : kForms)
    z.push_back({std::string(f) + "_from_g1_diff", "", ModelKind::Zero, std::string("z_") + f + "_from_g1", "", ""});
  t.spec.bin_columns = {
      {"theta_m_range_deg", Merge::Key, N, "deg", "zenith range [lo, hi] of the normal bin"},
      {"phi_m_range_deg", Merge::Key, N, "deg", "azimuth range [lo, hi] of the normal bin"},
      {"m", Merge::Direction, N, "1", "mean unit normal [x, y, z] of the bin's facets"},
      {"area_fraction", Merge::Mean, N, "1", "the bin's share of the surface's facet area"},
      {"front_fraction", Merge::Mean, N, "1", "share of the bin's area on facets facing both o and i"},
      {"g2", Merge::Spread, R, "1", "g2 over the bin's facets (0 where none faces both)"},
      {"g1_o", Merge::Spread, R, "1", "g1_o over the bin's facets"},
      {"g1_i", Merge::Spread, R, "1", "g1_i over the bin's facets"},
      {"vcavity", Merge::Mean, N, "1", "V-cavity G2 over the bin's facets, weighted like g2"}};
  t.spec.row_fields = {{"area_samples", Merge::Copy, N, "count", "points drawn"},
                       {"occlusion_rays", Merge::Copy, N, "count", "occlusion rays traced (two per point)"}};
  for (const Column& f : tracer_count_fields(false)) t.spec.row_fields.push_back(f);
  t.spec.bin_fields = {
      {"weight_fraction", Merge::Copy, N, "1", "the bin's share of sum_f A_f (o.m_f + i.m_f) / 2"},
      {"separable_from_g1", Merge::Copy, N, "1", "g1_o g1_i of the bin"},
      {"height_correlated_from_g1", Merge::Copy, N, "1", "the height-correlated form built from the bin's g1_o and g1_i"},
      {"samples", Merge::Copy, N, "count", "points drawn in the bin"}};
  return t;
}

namespace {

// The bin holding the half vector h = (o + i)/|o + i|: the G2(o, h, i) that a specular
// microfacet BRDF uses ([Heitz14, eq. 17] with G2), where the Smith forms apply as they are.
void put_half_bin(Json& row, const G2Result& r) {
  const int hb = r.binning.bin_of((r.o + r.i).normalized());
  const G2NormalBin& hbin = r.bins[hb];
  const int hit = hb / r.binning.n_phi(), hip = hb % r.binning.n_phi();
  row["half_bin_theta_m_range_deg"] = {deg(r.binning.theta_lo(hit)), deg(r.binning.theta_hi(hit))};
  row["half_bin_phi_m_range_deg"] = {deg(r.binning.phi_lo(hip)), deg(r.binning.phi_hi(hip))};
  // (At least 100 samples: a nearly empty bin gives no usable value, and identical 0/2 or 2/2
  // counts on every surface of an ensemble would fake a zero between-surface error.)
  if (hbin.samples >= 100) {
    row["g2_half"] = r.bin_g2(hb).mean;
    row["g2_half_stderr"] = r.bin_g2(hb).stderr_;
  } else {
    row["g2_half"] = nullptr;
    row["g2_half_stderr"] = nullptr;
  }
}

// The models from the surface's own facets with the z-scores of g2 against them, and the
// nominal NDF's Smith forms.
void put_g2_models(Json& row, const G2Result& r, const Microsurface& s, const Estimate& g2, double dphi) {
  row["lambda_o_numeric"] = r.lambda_o;
  row["lambda_i_numeric"] = r.lambda_i;
  const models::G2Forms f = r.smith_numeric();
  const std::pair<const char*, double> forms[] = {
      {"smith_separable", f.separable},
      {"smith_height_correlated", f.height_correlated},
      {"smith_direction_correlated", f.direction_correlated},
      {"smith_height_direction_correlated", f.height_direction_correlated},
      {"vcavity", r.vcavity}};
  for (const auto& [name, value] : forms) row[name] = value;
  // z-scores against the models computed from this surface's own facets: the ray-count
  // standard error is the right one (the model is exact for this surface's facets).
  for (const auto& [name, value] : forms)
    row[std::string("z_") + (std::string(name).rfind("smith_", 0) == 0 ? name + 6 : name)] =
        z_json(g2.mean, value, g2.stderr_);
  if (s.nominal) {
    const models::Ndf& ndf = *s.nominal;
    const models::G2Forms fn = models::g2_forms_from_lambda(ndf.Lambda(r.o), ndf.Lambda(r.i), dphi);
    row["smith_separable_nominal"] = fn.separable;
    row["smith_height_correlated_nominal"] = fn.height_correlated;
    row["smith_direction_correlated_nominal"] = fn.direction_correlated;
    row["smith_height_direction_correlated_nominal"] = fn.height_direction_correlated;
  } else {
    for (const char* k : {"smith_separable_nominal", "smith_height_correlated_nominal",
                          "smith_direction_correlated_nominal",
                          "smith_height_direction_correlated_nominal"})
      row[k] = nullptr;
  }
}

// The forms built per bin from the measured G1s (correlation assumption alone), their
// difference to g2 with its standard error (delta method) and z-score.
void put_forms_from_g1(Json& row, const G2Result& r) {
  const G2Result::FormsFromG1 fg = r.forms_from_g1();
  const auto fv = form_values(fg.value), fd = form_values(fg.diff), fs = form_values(fg.diff_stderr);
  const char* const* names = kForms;
  for (int k = 0; k < 4; ++k) {
    row[std::string(names[k]) + "_from_g1"] = fv[k];
    row[std::string(names[k]) + "_from_g1_diff"] = fd[k];
    row[std::string(names[k]) + "_from_g1_diff_stderr"] = fs[k];
    row[std::string("z_") + names[k] + "_from_g1"] = z_json(fd[k], 0.0, fs[k]);
  }
}

// The normal bins holding facets.
Json g2_bins_json(const G2Result& r) {
  Json bins = Json::array();
  for (int b = 0; b < r.binning.size(); ++b) {
    const G2NormalBin& nb = r.bins[b];
    if (nb.area <= 0) continue;
    Json jb;
    jb["m"] = {nb.mean_normal.x(), nb.mean_normal.y(), nb.mean_normal.z()};
    const int it = b / r.binning.n_phi(), ip = b % r.binning.n_phi();
    jb["theta_m_range_deg"] = {deg(r.binning.theta_lo(it)), deg(r.binning.theta_hi(it))};
    jb["phi_m_range_deg"] = {deg(r.binning.phi_lo(ip)), deg(r.binning.phi_hi(ip))};
    jb["area_fraction"] = nb.area / r.total_area;
    jb["front_fraction"] = nb.front_area / nb.area;
    jb["weight_fraction"] = r.weight > 0 ? nb.weight / r.weight : 0.0;
    if (nb.weight > 0 && nb.samples > 0) {
      const Estimate e2 = r.bin_g2(b), eo = r.bin_g1_o(b), ei = r.bin_g1_i(b);
      jb["g2"] = e2.mean;
      jb["g2_stderr"] = e2.stderr_;
      jb["g1_o"] = eo.mean;
      jb["g1_o_stderr"] = eo.stderr_;
      jb["g1_i"] = ei.mean;
      jb["g1_i_stderr"] = ei.stderr_;
      jb["vcavity"] = nb.vcavity_sum / nb.weight;
      const G2Result::FormsFromG1 bf = r.bin_forms_from_g1(b);
      jb["separable_from_g1"] = bf.value.separable;
      jb["height_correlated_from_g1"] = bf.value.height_correlated;
      jb["samples"] = nb.samples;
    } else {  // no facet of the bin faces both directions: G2 = 0 by definition
      for (const char* k : {"g2", "g2_stderr", "g1_o", "g1_o_stderr", "g1_i", "g1_i_stderr",
                            "vcavity"})
        jb[k] = 0.0;
      jb["samples"] = nb.samples;
    }
    bins.push_back(jb);
  }
  return bins;
}

}  // namespace

Json& add_row(Table& t, const G2Result& r, const Microsurface& s) {
  t.rows.push_back(Json::object());
  Json& row = t.rows.back();
  row["theta_o_deg"] = deg(theta_of(r.o));
  row["phi_o_deg"] = deg(phi_of(r.o));
  row["theta_i_deg"] = deg(theta_of(r.i));
  row["phi_i_deg"] = deg(phi_of(r.i));
  const double dphi = models::azimuth_difference(r.o, r.i);
  row["delta_phi_deg"] = deg(dphi);
  const Estimate g2 = r.g2(), go = r.g1_o(), gi = r.g1_i();
  row["g2"] = g2.mean;
  row["g2_stderr"] = g2.stderr_;
  row["g1_o"] = go.mean;
  row["g1_o_stderr"] = go.stderr_;
  row["g1_i"] = gi.mean;
  row["g1_i_stderr"] = gi.stderr_;
  put_half_bin(row, r);
  put_g2_models(row, r, s, g2, dphi);
  put_forms_from_g1(row, r);
  row["area_samples"] = r.samples;
  row["replicates"] = r.replicates;
  row["occlusion_rays"] = r.counters.rays;
  row["lost_rays"] = r.counters.lost_below + r.counters.unresolved;
  row["backface_hits"] = r.counters.backface_hits;
  row["trace_counters"] = fields_json(r.counters);  // every counter, as TraceCounters declares them
  row["seconds"] = r.seconds;
  row["bins"] = g2_bins_json(r);
  return row;
}

}  // namespace microsim
