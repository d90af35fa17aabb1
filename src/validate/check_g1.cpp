// Check of G1 (both estimators, Smith from the facets and nominal, per normal bin).
#include "checks_common.hpp"
#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/surface/generators.hpp"

namespace microsim::validation {

// ---------------------------------------------------------------------------------------------
// G1: the two estimators of docs/theory/masking.md, visible area ratio, Smith from the facets, and per
// normal bin Smith (m-independent) and the V-cavity model [Heitz14, eq. 24] averaged over the
// bin's facets.

// Per normal bin: sum_f A_f (v.m_f)+ G1_vcavity(v, m_f) / sum_f A_f (v.m_f)+ .
std::vector<double> vcavity_bin_model(const FacetTable& t, const Vec3& v, int nbins) {
  using Acc = std::vector<double>;
  const std::size_t nf = t.size();
  Acc acc = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, nf, std::max<std::size_t>(1 << 15, nf / 64)), Acc{},
      [&](const tbb::blocked_range<std::size_t>& range, Acc a) {
        if (a.empty()) a.assign(2 * static_cast<std::size_t>(nbins), 0.0);
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          Vec3 m;
          double area;
          t.normal_area(k, m, area);
          m.normalize();
          const double w = area * std::max(0.0, v.dot(m));
          const int b = t.bin(k);
          if (w <= 0 || b < 0) continue;
          a[2 * b] += w * models::vcavity_G1(v, m);  // [Heitz14, eq. 24]
          a[2 * b + 1] += w;
        }
        return a;
      },
      [](Acc a, const Acc& b) {
        if (a.empty()) return b;
        for (std::size_t k = 0; k < b.size(); ++k) a[k] += b[k];
        return a;
      });
  std::vector<double> model(nbins, 0.0);
  if (acc.empty()) return model;
  for (int b = 0; b < nbins; ++b) model[b] = acc[2 * b + 1] > 0 ? acc[2 * b] / acc[2 * b + 1] : 0.0;
  return model;
}

double g1_work(const SurfaceSet& set) {
  const Options& o = set.options;
  double w = 0;
  // As counted in check_g1: the facet table once, then per direction both estimators' rays
  // and the V-cavity pass over the facets.
  for (const auto& s : set.surfaces)
    w += 0.1 * static_cast<double>(s.num_facets()) +
         static_cast<double>(o.theta_deg.size() * o.phi_deg.size()) *
             (2.0 * static_cast<double>(o.rays) + 0.4 * static_cast<double>(s.num_facets()));
  return w;
}

namespace {

// The models of one view beside its measured G1(v, m): Smith from the facets' Lambda, and the
// V-cavity model per normal bin.
struct BinModels {
  double smith_numeric;
  const std::vector<double>& vcavity;
};
// Where a view's rows are: its condition text, its group suffix and its angles.
struct ViewPlace {
  const std::string& where;
  const std::string& dir;
  const Json& angles;
};

// Per normal bin G1(v, m): estimators (a) = (b), Smith and the V-cavity model; bins with too few
// counts are left out.
void push_bin_rows(const SurfaceSet& set, const G1Result& r, const DirectionBinning& binning,
                   const BinModels& models, const ViewPlace& at, CheckOutput& out) {
  const Options& o = set.options;
  for (int b = 0; b < binning.size(); ++b) {
    const G1NormalBin& nb = r.bins[b];
    if (nb.front_projected <= 0 || nb.samples < o.min_bin_count ||
        nb.raycast_hits < o.min_bin_count)
      continue;
    const NormalBinRange bin = normal_bin_range(binning, b);
    const std::string bin_where = at.where + ", " + bin.text();
    Json bx = bin.with(at.angles);
    bx["m"] = {nb.mean_normal.x(), nb.mean_normal.y(), nb.mean_normal.z()};
    const Estimate eb = floored(r.bin_g1_area_sampling(b), nb.samples);
    const double sa = r.window_area_perp / nb.front_projected;
    const Estimate ha = floored(r.bin_g1_raycast(b), r.raycast_rays, sa);
    Row a = make_row(set, "", "g1_bin", "g1_bin_raycast", Kind::Identity,
                     "G1(v,m) estimators (a) = (b)");
    push_measured(out, std::move(a), bin_where, eb.mean,
                  std::hypot(eb.stderr_, ha.stderr_), ha.mean, "rays",
                  set.name + "/g1_bin_raycast/" + at.dir, bx);
    // Smith: G1(v, m) = chi+(v.m) G1(v), independent of m [Heitz14, eq. 9-10].
    Row sm = make_row(set, "", "g1_bin", "smith_numeric", Kind::Model,
                      "[Heitz14, eq. 9-10]: Smith G1(v,m) = chi+(v.m) G1(v)");
    push_measured(out, std::move(sm), bin_where, eb.mean,
                  eb.stderr_, models.smith_numeric, "rays",
                  set.name + "/g1_bin_smith/" + at.dir, bx);
    Row vc = make_row(set, "", "g1_bin", "vcavity", Kind::Model,
                      "[Heitz14, eq. 24], averaged over the bin's facets");
    push_measured(out, std::move(vc), bin_where, eb.mean,
                  eb.stderr_, models.vcavity[b], "rays",
                  set.name + "/g1_bin_vcavity/" + at.dir, bx);
  }
}

// The measurement's row of the record (measure g1's), with the models per bin beside the
// measured G1(v, m).
Json measurement_row(const G1Result& r, const Microsurface& s, const DirectionBinning& binning,
                     const BinModels& models, double t, double p) {
  Table g1_rows = g1_table();
  Json& row = add_row(g1_rows, r, s);
  row["theta_deg"] = t;
  row["phi_deg"] = p;
  // In the order add_row lists the bins.
  std::size_t jb = 0;
  for (int b = 0; b < binning.size() && jb < row["bins"].size(); ++b) {
    if (r.bins[b].area <= 0) continue;
    row["bins"][jb]["smith_numeric"] = r.bins[b].front_projected > 0 ? models.smith_numeric : 0.0;
    row["bins"][jb]["vcavity"] = models.vcavity[b];
    row["bins"][jb]["samples"] = r.bins[b].samples;
    row["bins"][jb]["raycast_hits"] = r.bins[b].raycast_hits;
    ++jb;
  }
  return row;
}

// Averaged G1 against the Smith G1 of the nominal NDF ([Heitz14, eq. 11] with alpha_o): a
// statistic of the generated surfaces, so it needs the between-surface error. One surface
// gives the relative deviation only.
void push_nominal_rows(const SurfaceSet& set,
                       std::map<std::pair<double, double>, std::vector<Estimate>>& g1_by_direction,
                       CheckOutput& out) {
  const Options& o = set.options;
  const Microsurface& s0 = set.surfaces[0];
  if (!s0.nominal) return;
  for (double p : o.phi_deg)
    for (double t : o.theta_deg) {
      const Vec3 v = direction_from_angles(rad(t), rad(p));
      Row r = make_row(set, "", "g1", "smith_nominal", Kind::Model,
                       "[Heitz14, eq. 11] with alpha_o; Beckmann Lambda");
      push_nominal(out, std::move(r), "theta " + angle(t) + " phi " + angle(p),
                   g1_by_direction[{t, p}], s0.nominal->G1(v), "",
                   {{"theta_deg", t}, {"phi_deg", p}});
    }
}

}  // namespace

void check_g1(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  const Options& o = set.options;
  G1Options go = check_options<G1Options>(o, o.rays);
  const DirectionBinning binning = g1_normal_binning(go);
  const bool periodic = set.surfaces[0].macro().periodic;
  // Averaged G1 per direction and surface, for the ensemble comparison with the nominal Smith.
  std::map<std::pair<double, double>, std::vector<Estimate>> g1_by_direction;
  const Json per_surface = for_each_surface(set, binning, progress, [&](SurfacePass& pass) {
    const Microsurface& s = pass.surface;
    const std::string& label = pass.label;
    for_each_view(o, [&](double t, double p, const Vec3& v) {
      // A V-cavity ensemble is its grooves, each an infinite periodic groove traced on its own
      // (as measure g1 does), not the stored strips traced together.
      const G1Result r = measure_with_progress(progress, 2.0 * static_cast<double>(o.rays), go,
                                               [&](const G1Options& opt) {
                                                 return is_vcavity(s) ? measure_g1(vcavity_grooves(s, "measure_g1", GrooveFrames::StoredNormalOverHypot), {v}, opt).at(0)
                                                                      : measure_g1(pass.tracer, v, opt, &pass.table);
                                               });
      const std::vector<double> vcav = vcavity_bin_model(pass.table, r.v, binning.size());
      progress.completed += 0.4 * static_cast<double>(s.num_facets());
      progress.update();
      const std::string dir = "theta " + angle(t) + " phi " + angle(p);
      const std::string where = (label.empty() ? "" : label + ", ") + dir;
      const Json ang = {{"theta_deg", t}, {"phi_deg", p}};
      const double smith_numeric = 1.0 / (1.0 + r.lambda_numeric);

      // Visible area ratio: exactly 1 on a periodic tile (every ray from above hits once).
      const double ratio_scale = r.window_area_perp / (v.z() * r.macro_area);
      const Estimate ratio = floored(r.visible_area_ratio(), r.raycast_rays, ratio_scale);
      Row var = make_row(set, "", "visible_area_ratio", periodic ? "one" : "",
                         periodic ? Kind::Identity : Kind::Info,
                         "visible area ratio; [GeomBSDF24, 'Inherent Assumptions']");
      var.condition += " " + where;
      var.measured = ratio.mean;
      var.stderr_ = ratio.stderr_;
      if (periodic) var.model = 1.0;
      var.error = "rays";
      var.group = set.name + "/visible_area_ratio/" + dir;
      var.extra = ang;
      out.rows.push_back(var);

      // Averaged G1: estimator (b) against estimator (a) -- the same quantity. On a periodic
      // tile every ray hits once, so (a) is (v.n) A / sum_f A_f (v.m_f)+ = 1/(1+Lambda)
      // exactly and this row repeats `g1 vs smith_numeric` (the hits are tested by the
      // visible area ratio): an info row there, so that no comparison is counted twice.
      const Estimate gb = floored(r.g1_area_sampling(), r.sample_rays);
      const double scale_a = r.window_area_perp / r.front_projected;
      const Estimate ga = floored(r.g1_raycast(), r.raycast_rays, scale_a);
      Row est = make_row(set, "", "g1", "g1_raycast", periodic ? Kind::Info : Kind::Identity,
                         periodic ? "G1 estimators (a) = (b); on a periodic tile (a) "
                                    "is 1/(1+Lambda) identically (tested by g1 vs smith_numeric)"
                                  : "G1 estimators (a) = (b)");
      push_measured(out, std::move(est), where, gb.mean, std::hypot(gb.stderr_, ga.stderr_),
                    ga.mean, "rays", set.name + "/g1_raycast/" + dir, ang);

      // Averaged G1 against 1/(1 + Lambda) from the facets: on a periodic tile the visible
      // projected area is (v.n) A [GeomBSDF24, eq. 2a-2b], so the projected-area average
      // G1 = (v.n) A / sum_f A_f (v.m_f)+ = 1/(1+Lambda) exactly [GeomBSDF24, eq. 3Xc-3Xd]: an
      // identity, not a test of Smith. On a finite object it is a model (the object is not
      // infinitesimally thick, [GeomBSDF24, "Inherent Assumptions"]).
      Row sn = make_row(set, "", "g1", "smith_numeric", periodic ? Kind::Identity : Kind::Model,
                        "[GeomBSDF24, eq. 3Xc-3Xd] (exact for the projected-area average on a periodic tile)");
      push_measured(out, std::move(sn), where, gb.mean,
                    gb.stderr_, smith_numeric, "rays",
                    set.name + "/smith_numeric/" + dir, ang);

      const BinModels models{smith_numeric, vcav};
      push_bin_rows(set, r, binning, models, {where, dir, ang}, out);
      pass.rows().push_back(measurement_row(r, s, binning, models, t, p));
      g1_by_direction[{t, p}].push_back(gb);
    });
  });
  push_nominal_rows(set, g1_by_direction, out);
  out.measurements = per_surface;
}

}  // namespace microsim::validation
