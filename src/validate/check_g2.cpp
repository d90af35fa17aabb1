// Check of G2 (hotspot identity, Smith forms, V-cavity).
#include "checks_common.hpp"
#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/measure/vcavity_measure.hpp"
#include "microsim/surface/generators.hpp"

namespace microsim::validation {

// ---------------------------------------------------------------------------------------------
// G2 ([GeomBSDF24, eq. 16], [Heitz14, eq. 20-23]): the hotspot G2(v,m,v) = G1(v,m) as an identity against an
// independent `measure g1` run, per normal bin and on average; the four Smith forms with Lambda
// from the facets and the V-cavity as approximate models (ray-count error), the four forms of
// the nominal NDF over ensembles (between-surface error). The symmetry G2(o,m,i) = G2(i,m,o)
// holds sample for sample by construction of measure_g2 (the points depend on the unordered
// pair), so it is a deterministic unit test (tests/test_g2.cpp), not a z-row here.
struct G2Pair {
  double theta_o, phi_o, theta_i, phi_i;
};
const std::vector<G2Pair>& g2_pairs() {
  static const std::vector<G2Pair> pairs = {{30, 0, 60, 180}, {60, 0, 45, 90}};
  return pairs;
}
const std::vector<double>& g2_hotspot_theta() {
  static const std::vector<double> t = {30, 60, 80};
  return t;
}

double g2_work(const SurfaceSet& set) {
  const double n = static_cast<double>(share_of_rays(set.options, 4));
  double w = 0;
  // Per pair one G2 run (two occlusion rays per point); per hotspot angle one G2 run and one
  // G1 run (both estimators).
  for (const auto& s : set.surfaces)
    w += 0.1 * static_cast<double>(s.num_facets()) +
         2.0 * n * static_cast<double>(g2_pairs().size() + 2 * g2_hotspot_theta().size());
  return w;
}

namespace {

// The hotspot per normal bin ([GeomBSDF24, eq. 16]: G2(v,m,v) = G1(v,m)) at theta t: rows, and
// the bins of the record's `hot` entry; bins with too few counts are left out.
void push_hotspot_bins(const SurfaceSet& set, const G2Result& h, const G1Result& g, const DirectionBinning& binning,
                       const std::string& where, double t, Json& hot, CheckOutput& out) {
  const Options& o = set.options;
  const Json ang = {{"theta_deg", t}};
  for (int b = 0; b < binning.size(); ++b) {
    const G2NormalBin& hb = h.bins[b];
    const G1NormalBin& gb = g.bins[b];
    if (hb.samples < o.min_bin_count || gb.samples < o.min_bin_count) continue;
    const NormalBinRange bin = normal_bin_range(binning, b);
    const Estimate e2 = floored(h.bin_g2(b), hb.samples);
    const Estimate e1 = floored(g.bin_g1_area_sampling(b), gb.samples);
    const Json bx = bin.with(ang);
    Row rb = make_row(set, "", "g2_hotspot_bin", "g1_bin_independent", Kind::Identity,
                      "[GeomBSDF24, eq. 16]: G2(v,m,v) = G1(v,m) per normal bin");
    push_measured(out, std::move(rb), where + ", " + bin.text(), e2.mean, std::hypot(e2.stderr_, e1.stderr_), e1.mean, "rays",
                  set.name + "/g2_hotspot_bin/theta " + angle(t), bx);
    hot["bins"].push_back({{"theta_m_range_deg", {bin.theta_lo, bin.theta_hi}},
                           {"phi_m_range_deg", {bin.phi_lo, bin.phi_hi}}, {"g2", e2.mean}, {"g2_stderr", e2.stderr_},
                           {"g1_independent", e1.mean}, {"g1_independent_stderr", e1.stderr_}});
  }
}

// A pair's directions, its text in the rows and its angles in the records.
struct PairView {
  Vec3 vo, vi;
  std::string dir;
  Json ang;
};
PairView pair_view(const G2Pair& p) {
  return {direction_from_angles(rad(p.theta_o), rad(p.phi_o)), direction_from_angles(rad(p.theta_i), rad(p.phi_i)),
          "o " + angle(p.theta_o) + "/" + angle(p.phi_o) + " i " + angle(p.theta_i) + "/" + angle(p.phi_i),
          {{"theta_o_deg", p.theta_o}, {"phi_o_deg", p.phi_o}, {"theta_i_deg", p.theta_i}, {"phi_i_deg", p.phi_i}}};
}

// The four Smith forms of the nominal NDF ([Heitz14, eq. 20-23] with its Lambda): a statistic of
// the generated surfaces, compared over the ensemble (g2_by_pair: each surface's G2 per pair).
void push_nominal_forms(const SurfaceSet& set, const std::vector<std::vector<Estimate>>& g2_by_pair,
                        CheckOutput& out) {
  const Microsurface& s0 = set.surfaces[0];
  if (!s0.nominal) return;
  for (std::size_t ip = 0; ip < g2_pairs().size(); ++ip) {
    const PairView pv = pair_view(g2_pairs()[ip]);
    const Vec3 &vo = pv.vo, &vi = pv.vi;
    const double phi = std::acos(std::clamp(
        Vec2(vo.x(), vo.y()).normalized().dot(Vec2(vi.x(), vi.y()).normalized()), -1.0, 1.0));
    const models::G2Forms fm =
        models::g2_forms_from_lambda(s0.nominal->Lambda(vo), s0.nominal->Lambda(vi), phi);
    auto nominal_row = [&](const std::string& name, double value, const std::string& ref) {
      Row r = make_row(set, "", "g2", name, Kind::Model, ref);
      push_nominal(out, std::move(r), pv.dir, g2_by_pair[ip], value, set.name + "/g2_" + name, pv.ang);
    };
    nominal_row("separable_nominal", fm.separable, "[Heitz14, eq. 20], nominal NDF");
    nominal_row("height_correlated_nominal", fm.height_correlated, "[Heitz14, eq. 21], nominal NDF");
    nominal_row("direction_correlated_nominal", fm.direction_correlated, "[Heitz14, eq. 22], nominal NDF");
    nominal_row("height_direction_correlated_nominal", fm.height_direction_correlated,
                "[Heitz14, eq. 23], nominal NDF");
  }
}

// The check's runs of one surface with their progress: G2 for a pair of directions, and the
// independent G1 the hotspot is compared with. A V-cavity ensemble is its grooves, each an
// infinite periodic groove traced on its own ([Heitz14, Sec. 6.1], as measure g1 and check_g1
// do), not the stored strips traced together.
struct G2Runs {
  const Options& o;
  G2Options& go;
  Progress& progress;
  G2Result g2(const SurfacePass& pass, const Vec3& a, const Vec3& b) {
    const Microsurface& s = pass.surface;
    G2Result r = measure_with_progress(progress, 2.0 * static_cast<double>(go.rays), go, [&](const G2Options& g) {
      if (!is_vcavity(s)) return measure_g2(pass.tracer, a, b, g, &pass.table);
      return measure_g2(vcavity_grooves(s, "check g2", GrooveFrames::StoredNormalNormalized), a, b, g);
    });
    progress.update();
    return r;
  }
  // Another seed: independent points and rays; the same normal bins.
  G1Result independent_g1(const SurfacePass& pass, const Vec3& v) {
    const Microsurface& s = pass.surface;
    G1Options g1o;
    g1o.rays = go.rays;
    g1o.seed = o.seed + 0x9e3779b9ULL;
    g1o.split = o.split;
    g1o.normal_theta_bins = go.normal_theta_bins;
    g1o.normal_phi_bins = go.normal_phi_bins;
    const G1Result g = measure_with_progress(progress, 2.0 * static_cast<double>(g1o.rays), g1o,
                                             [&](const G1Options& opt) {
                                               return is_vcavity(s) ? measure_g1(vcavity_grooves(s, "measure_g1", GrooveFrames::StoredNormalOverHypot), {v}, opt).at(0)
                                                                    : measure_g1(pass.tracer, v, opt, &pass.table);
                                             });
    progress.update();
    return g;
  }
};

// The averaged G2 of pair ip on one surface against the approximate models: Smith forms with
// Lambda from the facets and the V-cavity averaged over the same facets (the surface's own
// statistics: ray-count error). Returns the estimate for the nominal forms.
Estimate check_g2_pair(const SurfaceSet& set, SurfacePass& pass, std::size_t ip, G2Runs& runs, CheckOutput& out) {
  const PairView pv = pair_view(g2_pairs()[ip]);
  const G2Result a = runs.g2(pass, pv.vo, pv.vi);
  const std::string where = (pass.label.empty() ? "" : pass.label + ", ") + pv.dir;
  const Estimate ga = floored(a.g2(), a.samples);
  auto model_row = [&](const std::string& name, double value, const std::string& ref) {
    Row r = make_row(set, "", "g2", name, Kind::Model, ref);
    push_measured(out, std::move(r), where, ga.mean, ga.stderr_, value, "rays", set.name + "/g2_" + name, pv.ang);
  };
  const models::G2Forms fn = a.smith_numeric();
  model_row("separable_numeric", fn.separable, "[Heitz14, eq. 20], Lambda from the facets");
  model_row("height_correlated_numeric", fn.height_correlated, "[Heitz14, eq. 21], Lambda from the facets");
  model_row("direction_correlated_numeric", fn.direction_correlated, "[Heitz14, eq. 22], Lambda from the facets");
  model_row("height_direction_correlated_numeric", fn.height_direction_correlated,
            "[Heitz14, eq. 23], Lambda from the facets");
  model_row("vcavity", a.vcavity,
            is_vcavity(pass.surface)
                ? "[Heitz14, eq. 24 and Sec. 6], averaged over the facets facing both (exact for separate grooves)"
                : "[Heitz14, eq. 24 and Sec. 6], averaged over the facets facing both");
  Table g2_rows = g2_table();
  pass.rows().push_back(add_row(g2_rows, a, pass.surface));
  return ga;
}

// Hotspot ([GeomBSDF24, eq. 16]: G2(v,m,v) = G1(v,m)) at theta t: G2 at o = i against `measure
// g1` run independently, estimator (b) with the same weights A_f max(0, v.m_f), per normal bin
// and on average. Beside it, Smith's direction-correlated form [Heitz14, eq. 22], which is
// exactly G1 at o = i. Returns the record's `hotspot` entry.
Json check_g2_hotspot(const SurfaceSet& set, const SurfacePass& pass, double t, const DirectionBinning& binning,
                      G2Runs& runs, CheckOutput& out) {
  const Vec3 v = direction_from_angles(rad(t), 0.0);
  const G2Result h = runs.g2(pass, v, v);
  const G1Result g = runs.independent_g1(pass, v);
  const std::string where = (pass.label.empty() ? "" : pass.label + ", ") + "theta " + angle(t);
  const Json ang = {{"theta_deg", t}};
  const Estimate g2 = floored(h.g2(), h.samples), g1 = floored(g.g1_area_sampling(), g.sample_rays);
  Row r = make_row(set, "", "g2_hotspot", "g1_independent", Kind::Identity,
                   "[GeomBSDF24, eq. 16]: G2(v,m,v) = G1(v,m); G1 by an independent measure g1 run");
  push_measured(out, std::move(r), where, g2.mean, std::hypot(g2.stderr_, g1.stderr_), g1.mean,
                "rays", set.name + "/g2_hotspot", ang);
  Row dc = make_row(set, "", "g2_hotspot", "direction_correlated_numeric", Kind::Model,
                    "[Heitz14, eq. 22] at o = i: 1/(1 + Lambda), Lambda from the facets");
  push_measured(out, std::move(dc), where, g2.mean, g2.stderr_,
                h.smith_numeric().direction_correlated, "rays",
                set.name + "/g2_hotspot_direction_correlated", ang);
  Json hot = {{"theta_deg", t}, {"g2", g2.mean}, {"g2_stderr", g2.stderr_},
              {"g1_independent", g1.mean}, {"g1_independent_stderr", g1.stderr_},
              {"direction_correlated_numeric", h.smith_numeric().direction_correlated},
              {"bins", Json::array()}};
  push_hotspot_bins(set, h, g, binning, where, t, hot, out);
  return hot;
}

}  // namespace

void check_g2(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  const Options& o = set.options;
  G2Options go = check_options<G2Options>(o, share_of_rays(o, 4));
  const DirectionBinning binning = g2_normal_binning(go);
  G2Runs runs{o, go, progress};
  // The averaged G2 of each surface per pair, for the nominal forms over the ensemble.
  std::vector<std::vector<Estimate>> g2_by_pair(g2_pairs().size());
  const Json per_surface = for_each_surface(set, binning, progress, [&](SurfacePass& pass) {
    for (std::size_t ip = 0; ip < g2_pairs().size(); ++ip)
      g2_by_pair[ip].push_back(check_g2_pair(set, pass, ip, runs, out));
    Json hotspot = Json::array();
    for (double t : g2_hotspot_theta()) hotspot.push_back(check_g2_hotspot(set, pass, t, binning, runs, out));
    pass.entry["hotspot"] = hotspot;
  });
  push_nominal_forms(set, g2_by_pair, out);
  out.measurements = per_surface;
}

}  // namespace microsim::validation
