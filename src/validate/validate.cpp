#include "microsim/validate/validate.hpp"
#include "microsim/measure/stats.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/measure/vndf_measure.hpp"
#include "microsim/validate/bsdf_object_rows.hpp"
#include "microsim/measure/ndf_measure.hpp"
#include "microsim/models/ndf.hpp"
#include "microsim/surface/discretization.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim::validation {

const char* to_string(Kind k) {
  switch (k) {
    case Kind::Identity: return "identity";
    case Kind::Deterministic: return "deterministic";
    case Kind::Model: return "model";
    case Kind::Info: return "info";
  }
  return "info";
}

double sidak_z(double alpha, std::size_t k) {
  return microsim::sidak_z(alpha, static_cast<int>(std::min<std::size_t>(k, 1u << 30)));
}

Estimate proportion(std::uint64_t k, std::uint64_t n) {
  Estimate e = binomial_estimate(k, n);
  e.stderr_ = std::max(e.stderr_, proportion_floor(n));
  return e;
}

void set_chi2(Row& r, double chi2, int dof) {
  const double d = std::max(1, dof);
  r.measured = chi2 / d;
  r.stderr_ = std::sqrt(2.0 / d);
  r.model = 1.0;
}

Row albedo_total_row(std::uint64_t paths, std::uint64_t lost, std::uint64_t unterminated,
                     double albedo_up, double albedo_down) {
  Row e;
  e.quantity = "albedo_total";
  e.model_name = "one";
  e.kind = Kind::Deterministic;
  e.reference = "energy conservation of a mirror (000 eq. 21d with F = 1): every path leaves";
  e.measured = albedo_up + albedo_down;
  e.model = 1.0;
  // Every path of `paths` that does not leave moves the total by 1/paths. Accepted: the loss
  // budget of the tracer, kMaxLostFraction of the paths (at least one path), plus half a path
  // for the rounding of the sums.
  const double n = static_cast<double>(paths);
  const double allowed = std::max(1.0, std::ceil(kMaxLostFraction * n));
  e.tolerance = paths > 0 ? (allowed + 0.5) / n : 0.0;
  std::ostringstream budget;
  budget << kMaxLostFraction;
  e.error = "exact (lost and unterminated paths counted; budget " + budget.str() +
            " of the paths, at least one)";
  e.extra = {{"paths", paths}, {"lost", lost}, {"unterminated", unterminated}};
  return e;
}

double assign_verdicts(std::vector<Row>& rows, double significance) {
  std::size_t tested = 0;
  for (const Row& r : rows)
    if ((r.kind == Kind::Identity || r.kind == Kind::Model) && r.model && r.stderr_) ++tested;
  const double zt = sidak_z(significance, tested);
  const int k = static_cast<int>(std::min<std::size_t>(std::max<std::size_t>(tested, 1), 1u << 30));
  std::map<int, double> t_threshold;  // by degrees of freedom
  for (Row& r : rows) {
    r.z.reset();
    r.rel_dev.reset();
    r.threshold.reset();
    if (r.model && *r.model != 0) r.rel_dev = (r.measured - *r.model) / std::abs(*r.model);
    const bool tests = (r.kind == Kind::Identity || r.kind == Kind::Model) && r.model && r.stderr_;
    if (tests) {
      const double diff = r.measured - *r.model;
      if (*r.stderr_ > 0) r.z = diff / *r.stderr_;
      else r.z = std::abs(diff) <= 1e-12 * std::max(1.0, std::abs(*r.model))
                     ? 0.0
                     : std::copysign(std::numeric_limits<double>::infinity(), diff);
      if (r.dof && *r.dof >= 1) {
        auto it = t_threshold.find(*r.dof);
        if (it == t_threshold.end())
          it = t_threshold.emplace(*r.dof, microsim::sidak_t(significance, k, *r.dof)).first;
        r.threshold = it->second;
      } else {
        r.threshold = zt;
      }
    }
    switch (r.kind) {
      case Kind::Deterministic:
        r.verdict = r.model && std::abs(r.measured - *r.model) <= r.tolerance ? "pass" : "FAIL";
        break;
      case Kind::Identity:
        r.verdict = tests && std::abs(*r.z) <= *r.threshold ? "pass" : "FAIL";
        break;
      case Kind::Model:
        r.verdict = !tests ? "measured" : std::abs(*r.z) <= *r.threshold ? "agrees" : "deviates (finding)";
        break;
      case Kind::Info: r.verdict = "measured"; break;
    }
  }
  return zt;
}

std::size_t Result::count(const std::string& verdict) const {
  return static_cast<std::size_t>(
      std::count_if(rows.begin(), rows.end(), [&](const Row& r) { return r.verdict == verdict; }));
}

namespace {

std::string num(double x, int precision = 6) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", precision, x);
  return buf;
}
std::string fixed(double x, int digits) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << x;
  return os.str();
}
std::string angle(double d) { return num(d, 4); }

// Mean and between-surface standard error (sd / sqrt(K)) of per-surface values.
std::pair<double, double> mean_and_se(const std::vector<double>& x) {
  const SampleMean m = sample_mean(x);
  return {m.mean, m.stderr_};
}

// The estimator's error with a floor at the resolution of n samples: a proportion at 0 or 1
// has no spread but is known only to ~1/n (the error of (k + 1/2)/(n + 1) at k = n), so a
// comparison with a model there is not an infinite z.
Estimate floored(Estimate e, std::uint64_t n, double scale = 1.0) {
  if (n > 0) e.stderr_ = std::max(e.stderr_, scale * proportion_floor(n));
  return e;
}

// A mean over K surfaces with the between-surface error: the ray-count error of the mean,
// sqrt(sum se_k^2) / K, is a floor (K values can agree by chance, e.g. all unmasked).
struct EnsembleMean {
  double mean = 0, stderr_ = 0;
  int dof = 0;  // K - 1
};
EnsembleMean ensemble_mean(const std::vector<Estimate>& per_surface) {
  std::vector<double> x, rays;
  for (const Estimate& e : per_surface) {
    x.push_back(e.mean);
    rays.push_back(e.stderr_);
  }
  const SampleMean m = sample_mean(x);
  return {m.mean, std::max(m.stderr_, mean_of_errors(rays)), static_cast<int>(per_surface.size()) - 1};
}

// A comparison of K surfaces with a nominal model: a model row with the between-surface error
// and K - 1 degrees of freedom for K > 1; for one surface an info row (measured and model, no
// error bar: one surface's ray-count error says nothing about surface-to-surface variation).
void push_nominal(CheckOutput& out, Row r, const std::string& where,
                  const std::vector<Estimate>& per_surface, double model, const std::string& group,
                  const Json& extra) {
  const std::size_t K = per_surface.size();
  const EnsembleMean e = ensemble_mean(per_surface);
  r.condition += (K > 1 ? " " + std::to_string(K) + " surfaces," : "") + " " + where;
  r.measured = e.mean;
  r.model = model;
  r.group = group;
  r.extra = extra;
  r.extra["surfaces"] = K;
  if (K > 1) {
    r.kind = Kind::Model;
    r.stderr_ = e.stderr_;
    r.dof = e.dof;
    r.error = "surfaces";
  } else {
    r.kind = Kind::Info;
    r.error = "none (one surface: give several for a between-surface error)";
  }
  out.rows.push_back(std::move(r));
}

Row make_row(const SurfaceSet& set, const std::string& label, const std::string& quantity,
             const std::string& model_name, Kind kind, const std::string& reference) {
  Row r;
  r.entry = set.name;
  r.quantity = quantity;
  r.model_name = model_name;
  r.kind = kind;
  r.reference = reference;
  r.condition = set.name + (label.empty() ? "" : " " + label);
  return r;
}

// Completes a row with its measurement (where, measured, stderr, model, error kind, group,
// plot fields) and appends it.
void push_measured(CheckOutput& out, Row r, const std::string& where, double measured,
                   double stderr_, double model, const char* error, const std::string& group,
                   const Json& extra) {
  r.condition += " " + where;
  r.measured = measured;
  r.stderr_ = stderr_;
  r.model = model;
  r.error = error;
  r.group = group;
  r.extra = extra;
  out.rows.push_back(std::move(r));
}

std::string surface_label(const SurfaceSet& set, std::size_t k) {
  return set.surfaces.size() > 1 || !set.labels[k].empty() ? set.labels[k] : "";
}

// ---------------------------------------------------------------------------------------------
// D identities: 000 eq. 1b (sum_f A_f m_f / A = n) and eq. 1c (sum_f A_f (n.m_f) / A = 1).
void check_d_identities(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  Json per_surface = Json::array();
  for (std::size_t k = 0; k < set.surfaces.size(); ++k) {
    const Microsurface& s = set.surfaces[k];
    const FacetSums f = facet_sums(s);
    const Macrosurface& m = s.macro();
    // Bound on the double rounding of a sum of N terms (|error| <= N eps sum |terms|, with a
    // factor 2 for the cross products that make the terms): the identities hold exactly for
    // any float-valued vertices of a closed (or periodic) surface.
    const double eps = std::numeric_limits<double>::epsilon();
    const double tol = 2.0 * (static_cast<double>(s.num_facets()) + 3.0) * eps * f.total_area / m.area;
    const Vec3 b = f.sum_area_normal / m.area;
    const char* axis[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      // A measured window's interior is not closed: its x, y sums are the net height change
      // across it over A (the interior's mean slope), reported, not tested; z is eq. 1c's.
      const bool open_region = m.region && !m.periodic && a < 2;
      Row r = make_row(set, surface_label(set, k), std::string("eq_1b_") + axis[a], "macro_normal",
                       open_region ? Kind::Info : Kind::Deterministic,
                       open_region ? "000 eq. 1b (a window's interior: its mean slope, not an identity)" : "000 eq. 1b");
      r.measured = b[a];
      r.model = m.normal[a];
      r.tolerance = tol;
      r.error = "rounding";
      r.group = set.name + "/eq_1b";
      r.condition += (r.condition.empty() ? "" : ", ") + std::string("sum A_f m_f.") + axis[a] + " / A";
      out.rows.push_back(r);
    }
    Row c = make_row(set, surface_label(set, k), "eq_1c", "one", Kind::Deterministic, "000 eq. 1c");
    c.measured = f.sum_area_cos / m.area;
    c.model = 1.0;
    c.tolerance = tol;
    c.error = "rounding";
    c.group = set.name + "/eq_1c";
    c.condition += ", sum A_f (n.m_f) / A";
    out.rows.push_back(c);
    per_surface.push_back({{"label", set.labels[k]},
                           {"sum_area_normal_over_A", {b.x(), b.y(), b.z()}},
                           {"sum_area_cos_over_A", f.sum_area_cos / m.area},
                           {"total_area_over_A", f.total_area / m.area},
                           {"tolerance", tol}});
    progress.completed += 0.1 * static_cast<double>(s.num_facets());
    progress.update();
  }
  out.measurements = per_surface;
}

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
    double model = 0;
    for (int ip = 0; ip < bins.n_phi(); ++ip)
      model += bins.bin_average(bins.index(it, ip), [&](const Vec3& m) { return nominal.D(m); });
    model /= bins.n_phi();
    double d, se;
    if (K == 1) {
      d = res[0].ring_d[it];
      se = res[0].ring_d_stderr[it];
    } else {
      std::vector<double> x;
      double blocks2 = 0;
      for (const auto& r : res) {
        x.push_back(r.ring_d[it]);
        blocks2 += r.ring_d_stderr[it] * r.ring_d_stderr[it];
      }
      std::tie(d, se) = mean_and_se(x);
      // Floor: the within-surface (block) error of the mean, in case K values agree by chance.
      se = std::max(se, std::sqrt(blocks2) / static_cast<double>(K));
    }
    const double lo = deg(bins.theta_lo(it)), hi = deg(bins.theta_hi(it));
    ndf["theta_lo_deg"].push_back(lo);
    ndf["theta_hi_deg"].push_back(hi);
    ndf["d"].push_back(d);
    ndf["d_stderr"].push_back(se);
    ndf["d_nominal"].push_back(model);
    // Rings where the model puts at least min_ring_mass of the microsurface area (per unit
    // macro area) are tested; the far tails hold too few facets for a normal z.
    if (model * bins.solid_angle_of_ring(it) < o.min_ring_mass) continue;
    Row r = make_row(set, K > 1 ? std::to_string(K) + " surfaces" : surface_label(set, 0), "d_ring",
                     "nominal", Kind::Model, "DESIGN.md D; 001 Sec. 3.2 Beckmann D, bin-averaged");
    r.condition += (K > 1 || !surface_label(set, 0).empty() ? ", " : " ") + std::string("theta_m ") +
                   angle(lo) + "-" + angle(hi);
    r.measured = d;
    r.stderr_ = se;
    r.model = model;
    r.error = K > 1 ? "surfaces" : "blocks";
    if (K > 1) r.dof = static_cast<int>(K) - 1;
    r.group = set.name + "/d_ring";
    r.extra = {{"theta_m_range_deg", {lo, hi}}};
    out.rows.push_back(r);
  }
  // Moment fit of alpha (slope variance alpha^2/2 per axis, 001 Sec. 3.2, App. A) vs the nominal alpha.
  for (int a = 0; a < 2; ++a) {
    std::vector<double> x;
    for (const auto& f : sums) x.push_back(std::sqrt(2 * (a == 0 ? f.slope_var_x : f.slope_var_y)));
    auto [mean, se] = mean_and_se(x);
    Row r = make_row(set, K > 1 ? std::to_string(K) + " surfaces" : surface_label(set, 0),
                     a == 0 ? "fitted_alpha_x" : "fitted_alpha_y", "nominal",
                     K > 1 ? Kind::Model : Kind::Info, "001 Sec. 3.2 and App. A: P22 dslope = (n.m) D dm, Beckmann slope variance alpha^2/2 per axis");
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
  out.measurements = ndf;
}

// ---------------------------------------------------------------------------------------------
// G1: the two estimators of DESIGN.md, visible area ratio, Smith from the facets, and per
// normal bin Smith (m-independent) and the V-cavity model (001 eq. 24) averaged over the
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
          a[2 * b] += w * models::vcavity_G1(v, m);  // 001 eq. (24)
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

void check_g1(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  const Options& o = set.options;
  G1Options go;
  go.rays = o.rays;
  go.seed = o.seed;
  go.split = o.split;
  const DirectionBinning binning = g1_normal_binning(go);
  const std::size_t K = set.surfaces.size();
  const bool periodic = set.surfaces[0].macro().periodic;
  Json per_surface = Json::array();
  // Averaged G1 per direction and surface, for the ensemble comparison with the nominal Smith.
  std::map<std::pair<double, double>, std::vector<Estimate>> g1_by_direction;
  for (std::size_t k = 0; k < K; ++k) {
    const Microsurface& s = set.surfaces[k];
    const std::string label = surface_label(set, k);
    Tracer tracer(s);
    const FacetTable table = build_facet_table(s, binning);
    progress.completed += 0.1 * static_cast<double>(s.num_facets());
    Json rows = Json::array();
    for (double p : o.phi_deg)
      for (double t : o.theta_deg) {
        const Vec3 v = direction_from_angles(rad(t), rad(p));
        const double unit = 2.0 * static_cast<double>(o.rays);
        go.progress = [&](double f) { progress.update(f * unit); };
        G1Result r = measure_g1(tracer, v, go, &table);
        progress.completed += unit;
        const std::vector<double> vcav = vcavity_bin_model(table, r.v, binning.size());
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
                           "DESIGN.md visible area ratio; 000 Inherent Assumptions");
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
                           periodic ? "DESIGN.md G1 estimators (a) = (b); on a periodic tile (a) "
                                      "is 1/(1+Lambda) identically (tested by g1 vs smith_numeric)"
                                    : "DESIGN.md G1 estimators (a) = (b)");
        push_measured(out, std::move(est), where, gb.mean, std::hypot(gb.stderr_, ga.stderr_),
                      ga.mean, "rays", set.name + "/g1_raycast/" + dir, ang);

        // Averaged G1 against 1/(1 + Lambda) from the facets: on a periodic tile the visible
        // projected area is (v.n) A (000 eq. 2a-2b), so the projected-area average
        // G1 = (v.n) A / sum_f A_f (v.m_f)+ = 1/(1+Lambda) exactly (000 eq. 3Xc-3Xd): an
        // identity, not a test of Smith. On a finite object it is a model (the object is not
        // infinitesimally thick, 000 "Inherent Assumptions").
        Row sn = make_row(set, "", "g1", "smith_numeric", periodic ? Kind::Identity : Kind::Model,
                          "000 eq. 3Xc-3Xd (exact for the projected-area average on a periodic tile)");
        push_measured(out, std::move(sn), where, gb.mean,
                      gb.stderr_, smith_numeric, "rays",
                      set.name + "/smith_numeric/" + dir, ang);

        // Per normal bin G1(v, m).
        for (int b = 0; b < binning.size(); ++b) {
          const G1NormalBin& nb = r.bins[b];
          if (nb.front_projected <= 0 || nb.samples < o.min_bin_count ||
              nb.raycast_hits < o.min_bin_count)
            continue;
          const int it = b / binning.n_phi(), ip = b % binning.n_phi();
          const double tlo = deg(binning.theta_lo(it)), thi = deg(binning.theta_hi(it));
          const double plo = deg(binning.phi_lo(ip)), phi_hi = deg(binning.phi_hi(ip));
          const std::string bin_where = where + ", m in [" + angle(tlo) + "," + angle(thi) + "]x[" +
                                        angle(plo) + "," + angle(phi_hi) + "]";
          Json bx = ang;
          bx["theta_m_range_deg"] = {tlo, thi};
          bx["phi_m_range_deg"] = {plo, phi_hi};
          bx["m"] = {nb.mean_normal.x(), nb.mean_normal.y(), nb.mean_normal.z()};
          const Estimate eb = floored(r.bin_g1_area_sampling(b), nb.samples);
          const double sa = r.window_area_perp / nb.front_projected;
          const Estimate ha = floored(r.bin_g1_raycast(b), r.raycast_rays, sa);
          Row a = make_row(set, "", "g1_bin", "g1_bin_raycast", Kind::Identity,
                           "DESIGN.md G1(v,m) estimators (a) = (b)");
          push_measured(out, std::move(a), bin_where, eb.mean,
                        std::hypot(eb.stderr_, ha.stderr_), ha.mean, "rays",
                        set.name + "/g1_bin_raycast/" + dir, bx);
          // Smith: G1(v, m) = chi+(v.m) G1(v), independent of m (001 eq. 9-10).
          Row sm = make_row(set, "", "g1_bin", "smith_numeric", Kind::Model,
                            "001 eq. (9)-(10): Smith G1(v,m) = chi+(v.m) G1(v)");
          push_measured(out, std::move(sm), bin_where, eb.mean,
                        eb.stderr_, smith_numeric, "rays",
                        set.name + "/g1_bin_smith/" + dir, bx);
          Row vc = make_row(set, "", "g1_bin", "vcavity", Kind::Model,
                            "001 eq. (24), averaged over the bin's facets");
          push_measured(out, std::move(vc), bin_where, eb.mean,
                        eb.stderr_, vcav[b], "rays",
                        set.name + "/g1_bin_vcavity/" + dir, bx);
        }

        Table g1_rows = g1_table();
        Json& row = add_row(g1_rows, r, s);
        row["theta_deg"] = t;
        row["phi_deg"] = p;
        // Models per bin beside the measured G1(v, m), in the order add_row lists the bins.
        std::size_t jb = 0;
        for (int b = 0; b < binning.size() && jb < row["bins"].size(); ++b) {
          if (r.bins[b].area <= 0) continue;
          row["bins"][jb]["smith_numeric"] = r.bins[b].front_projected > 0 ? smith_numeric : 0.0;
          row["bins"][jb]["vcavity"] = vcav[b];
          row["bins"][jb]["samples"] = r.bins[b].samples;
          row["bins"][jb]["raycast_hits"] = r.bins[b].raycast_hits;
          ++jb;
        }
        rows.push_back(row);
        g1_by_direction[{t, p}].push_back(gb);
      }
    per_surface.push_back({{"label", set.labels[k]}, {"rows", rows}});
  }
  // Averaged G1 against the Smith G1 of the nominal NDF (001 eq. 11 with alpha_o): a
  // statistic of the generated surfaces, so it needs the between-surface error. One surface
  // gives the relative deviation only.
  const Microsurface& s0 = set.surfaces[0];
  if (s0.nominal) {
    for (double p : o.phi_deg)
      for (double t : o.theta_deg) {
        const Vec3 v = direction_from_angles(rad(t), rad(p));
        Row r = make_row(set, "", "g1", "smith_nominal", Kind::Model,
                         "001 eq. (11) with alpha_o; Beckmann Lambda");
        push_nominal(out, std::move(r), "theta " + angle(t) + " phi " + angle(p),
                     g1_by_direction[{t, p}], s0.nominal->G1(v), "",
                     {{"theta_deg", t}, {"phi_deg", p}});
      }
  }
  out.measurements = per_surface;
}


// ---------------------------------------------------------------------------------------------
// Shared by the G2, VNDF and BSDF checks: ray counts derived from --rays (kept modest so that
// every check together stays within a few times the cost of the G1 check).
std::uint64_t share_of_rays(const Options& o, std::uint64_t divisor) {
  return std::max<std::uint64_t>(1000, o.rays / divisor);
}

// ---------------------------------------------------------------------------------------------
// G2 (000 eq. 16, 001 eq. 20-23): the hotspot G2(v,m,v) = G1(v,m) as an identity against an
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

void check_g2(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  const Options& o = set.options;
  G2Options go;
  go.rays = share_of_rays(o, 4);
  go.seed = o.seed;
  go.split = o.split;
  const DirectionBinning binning = g2_normal_binning(go);
  const std::size_t K = set.surfaces.size();
  Json per_surface = Json::array();
  auto measure = [&](const Tracer& tracer, const Vec3& a, const Vec3& b, std::uint64_t seed,
                     const FacetTable& table) {
    G2Options g = go;
    g.seed = seed;
    const double unit = 2.0 * static_cast<double>(g.rays);
    g.progress = [&](double f) { progress.update(f * unit); };
    G2Result r = measure_g2(tracer, a, b, g, &table);
    progress.completed += unit;
    progress.update();
    return r;
  };
  // The averaged G2 of each surface per pair, for the nominal forms over the ensemble.
  std::vector<std::vector<Estimate>> g2_by_pair(g2_pairs().size());
  for (std::size_t k = 0; k < K; ++k) {
    const Microsurface& s = set.surfaces[k];
    const std::string label = surface_label(set, k);
    Tracer tracer(s);
    const FacetTable table = build_facet_table(s, binning);
    progress.completed += 0.1 * static_cast<double>(s.num_facets());
    Json rows = Json::array();
    for (std::size_t ip = 0; ip < g2_pairs().size(); ++ip) {
      const G2Pair& p = g2_pairs()[ip];
      const Vec3 vo = direction_from_angles(rad(p.theta_o), rad(p.phi_o));
      const Vec3 vi = direction_from_angles(rad(p.theta_i), rad(p.phi_i));
      const G2Result a = measure(tracer, vo, vi, o.seed, table);
      const std::string dir = "o " + angle(p.theta_o) + "/" + angle(p.phi_o) + " i " +
                              angle(p.theta_i) + "/" + angle(p.phi_i);
      const std::string where = (label.empty() ? "" : label + ", ") + dir;
      const Json ang = {{"theta_o_deg", p.theta_o}, {"phi_o_deg", p.phi_o},
                        {"theta_i_deg", p.theta_i}, {"phi_i_deg", p.phi_i}};
      const Estimate ga = floored(a.g2(), a.samples);
      g2_by_pair[ip].push_back(ga);
      // Approximate models of the averaged G2: Smith forms with Lambda from the facets and the
      // V-cavity averaged over the same facets (the surface's own statistics: ray-count error).
      auto model_row = [&](const std::string& name, double value, const std::string& ref) {
        Row r = make_row(set, "", "g2", name, Kind::Model, ref);
        push_measured(out, std::move(r), where, ga.mean,
                      ga.stderr_, value, "rays",
                      set.name + "/g2_" + name, ang);
      };
      const models::G2Forms fn = a.smith_numeric();
      model_row("separable_numeric", fn.separable, "001 eq. (20), Lambda from the facets");
      model_row("height_correlated_numeric", fn.height_correlated, "001 eq. (21), Lambda from the facets");
      model_row("direction_correlated_numeric", fn.direction_correlated, "001 eq. (22), Lambda from the facets");
      model_row("height_direction_correlated_numeric", fn.height_direction_correlated,
                "001 eq. (23), Lambda from the facets");
      model_row("vcavity", a.vcavity, "001 eq. (24)-(25), averaged over the facets facing both");
      Table g2_rows = g2_table();
      rows.push_back(add_row(g2_rows, a, s));
    }
    Json hotspot = Json::array();
    // Hotspot (000 eq. 16: G2(v,m,v) = G1(v,m)): G2 at o = i against `measure g1` run
    // independently (another seed: independent points and rays), estimator (b) with the same
    // weights A_f max(0, v.m_f), per normal bin and on average. Beside it, Smith's
    // direction-correlated form (001 eq. 22), which is exactly G1 at o = i.
    for (double t : g2_hotspot_theta()) {
      const Vec3 v = direction_from_angles(rad(t), 0.0);
      const G2Result h = measure(tracer, v, v, o.seed, table);
      G1Options g1o;
      g1o.rays = go.rays;
      g1o.seed = o.seed + 0x9e3779b9ULL;
      g1o.split = o.split;
      g1o.normal_theta_bins = go.normal_theta_bins;
      g1o.normal_phi_bins = go.normal_phi_bins;
      const double unit = 2.0 * static_cast<double>(g1o.rays);
      g1o.progress = [&](double f) { progress.update(f * unit); };
      const G1Result g = measure_g1(tracer, v, g1o, &table);
      progress.completed += unit;
      progress.update();
      const std::string where = (label.empty() ? "" : label + ", ") + "theta " + angle(t);
      const Json ang = {{"theta_deg", t}};
      const Estimate g2 = floored(h.g2(), h.samples), g1 = floored(g.g1_area_sampling(), g.sample_rays);
      Row r = make_row(set, "", "g2_hotspot", "g1_independent", Kind::Identity,
                       "000 eq. 16: G2(v,m,v) = G1(v,m); G1 by an independent measure g1 run");
      push_measured(out, std::move(r), where, g2.mean, std::hypot(g2.stderr_, g1.stderr_), g1.mean,
                    "rays", set.name + "/g2_hotspot", ang);
      Row dc = make_row(set, "", "g2_hotspot", "direction_correlated_numeric", Kind::Model,
                        "001 eq. (22) at o = i: 1/(1 + Lambda), Lambda from the facets");
      push_measured(out, std::move(dc), where, g2.mean, g2.stderr_,
                    h.smith_numeric().direction_correlated, "rays",
                    set.name + "/g2_hotspot_direction_correlated", ang);
      Json hot = {{"theta_deg", t}, {"g2", g2.mean}, {"g2_stderr", g2.stderr_},
                  {"g1_independent", g1.mean}, {"g1_independent_stderr", g1.stderr_},
                  {"direction_correlated_numeric", h.smith_numeric().direction_correlated},
                  {"bins", Json::array()}};
      for (int b = 0; b < binning.size(); ++b) {
        const G2NormalBin& hb = h.bins[b];
        const G1NormalBin& gb = g.bins[b];
        if (hb.samples < o.min_bin_count || gb.samples < o.min_bin_count) continue;
        const int it = b / binning.n_phi(), iph = b % binning.n_phi();
        const double tlo = deg(binning.theta_lo(it)), thi = deg(binning.theta_hi(it));
        const double plo = deg(binning.phi_lo(iph)), phi_hi = deg(binning.phi_hi(iph));
        const Estimate e2 = floored(h.bin_g2(b), hb.samples);
        const Estimate e1 = floored(g.bin_g1_area_sampling(b), gb.samples);
        Json bx = ang;
        bx["theta_m_range_deg"] = {tlo, thi};
        bx["phi_m_range_deg"] = {plo, phi_hi};
        Row rb = make_row(set, "", "g2_hotspot_bin", "g1_bin_independent", Kind::Identity,
                          "000 eq. 16: G2(v,m,v) = G1(v,m) per normal bin");
        push_measured(out, std::move(rb),
                      where + ", m in [" + angle(tlo) + "," + angle(thi) + "]x[" + angle(plo) + "," +
                          angle(phi_hi) + "]",
                      e2.mean, std::hypot(e2.stderr_, e1.stderr_), e1.mean, "rays",
                      set.name + "/g2_hotspot_bin/theta " + angle(t), bx);
        hot["bins"].push_back({{"theta_m_range_deg", {tlo, thi}}, {"phi_m_range_deg", {plo, phi_hi}},
                               {"g2", e2.mean}, {"g2_stderr", e2.stderr_},
                               {"g1_independent", e1.mean}, {"g1_independent_stderr", e1.stderr_}});
      }
      hotspot.push_back(hot);
    }
    per_surface.push_back({{"label", set.labels[k]}, {"rows", rows}, {"hotspot", hotspot}});
  }
  // The four Smith forms of the nominal NDF (001 eq. 20-23 with its Lambda): a statistic of
  // the generated surfaces, compared over the ensemble.
  const Microsurface& s0 = set.surfaces[0];
  if (s0.nominal)
    for (std::size_t ip = 0; ip < g2_pairs().size(); ++ip) {
      const G2Pair& p = g2_pairs()[ip];
      const Vec3 vo = direction_from_angles(rad(p.theta_o), rad(p.phi_o));
      const Vec3 vi = direction_from_angles(rad(p.theta_i), rad(p.phi_i));
      const double phi = std::acos(std::clamp(
          Vec2(vo.x(), vo.y()).normalized().dot(Vec2(vi.x(), vi.y()).normalized()), -1.0, 1.0));
      const models::G2Forms fm =
          models::g2_forms_from_lambda(s0.nominal->Lambda(vo), s0.nominal->Lambda(vi), phi);
      const std::string dir = "o " + angle(p.theta_o) + "/" + angle(p.phi_o) + " i " +
                              angle(p.theta_i) + "/" + angle(p.phi_i);
      const Json ang = {{"theta_o_deg", p.theta_o}, {"phi_o_deg", p.phi_o},
                        {"theta_i_deg", p.theta_i}, {"phi_i_deg", p.phi_i}};
      auto nominal_row = [&](const std::string& name, double value, const std::string& ref) {
        Row r = make_row(set, "", "g2", name, Kind::Model, ref);
        push_nominal(out, std::move(r), dir, g2_by_pair[ip], value, set.name + "/g2_" + name, ang);
      };
      nominal_row("separable_nominal", fm.separable, "001 eq. (20), nominal NDF");
      nominal_row("height_correlated_nominal", fm.height_correlated, "001 eq. (21), nominal NDF");
      nominal_row("direction_correlated_nominal", fm.direction_correlated, "001 eq. (22), nominal NDF");
      nominal_row("height_direction_correlated_nominal", fm.height_direction_correlated,
                  "001 eq. (23), nominal NDF");
    }
  out.measurements = per_surface;
}

// ---------------------------------------------------------------------------------------------
// VNDF (000 eq. 3b, 001 eq. 13): the histogram of first-hit normals against the nominal D_v
// (approximate model), and the nominal NDF's VNDF sampler against its own D_v (identity: the
// sampler must reproduce its model; chi-square row: measured chi2/dof, model 1, stderr
// sqrt(2/dof), the normal approximation of chi2/dof). The nominal D_v is a statistic of the
// generated surfaces: over an ensemble, the bin densities (bins holding at least
// kVndfMinBinMass of the nominal D_v) are compared with the between-surface error; the
// chi-square of one surface's histogram against it (which counts surface-to-surface variation
// as a deviation) is an info row.
constexpr double kVndfMinBinMass = 0.01;

double vndf_work(const SurfaceSet& set) {
  const double n = static_cast<double>(share_of_rays(set.options, 4));
  const double dirs = static_cast<double>(set.options.theta_deg.size() * set.options.phi_deg.size());
  double w = 0;
  for (const auto& s : set.surfaces) w += 0.1 * static_cast<double>(s.num_facets()) + dirs * 2.0 * n;
  return w;
}

void check_vndf(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  const Options& o = set.options;
  VndfOptions vo;
  vo.rays = share_of_rays(o, 4);
  vo.seed = o.seed;
  vo.split = o.split;
  const DirectionBinning binning = vndf_binning(vo);
  Json per_surface = Json::array();
  // Per direction and bin, the density of each surface (ensemble rows below).
  std::map<std::pair<double, double>, std::vector<std::vector<Estimate>>> dv_by_direction;
  for (std::size_t k = 0; k < set.surfaces.size(); ++k) {
    const Microsurface& s = set.surfaces[k];
    const std::string label = surface_label(set, k);
    Tracer tracer(s);
    const FacetTable table = build_facet_table(s, binning);
    progress.completed += 0.1 * static_cast<double>(s.num_facets());
    Json rows = Json::array();
    for (double p : o.phi_deg)
      for (double t : o.theta_deg) {
        const Vec3 v = direction_from_angles(rad(t), rad(p));
        const double unit = static_cast<double>(vo.rays);
        vo.progress = [&](double f) { progress.update(f * unit); };
        const VndfResult r = measure_vndf(tracer, v, vo, &table);
        progress.completed += unit;
        const std::string where = (label.empty() ? "" : label + ", ") + "theta " + angle(t) + " phi " + angle(p);
        const Json ang = {{"theta_deg", t}, {"phi_deg", p}};
        std::optional<SamplerTest> sampler;
        if (s.nominal) {
          const std::vector<double> model =
              bin_integrals(r.binning, [&](const Vec3& m) { return s.nominal->D_visible(r.v, m); });
          const GofResult g = histogram_gof(r.bin_hits, r.hits, model, vo.family_alpha);
          Row m = make_row(set, "", "vndf_chi2_per_dof", "nominal", Kind::Info,
                           "001 eq. (13): D_v of the nominal NDF, bin integrals");
          m.condition += " " + where;
          set_chi2(m, g.chi2, g.dof);
          m.error = "rays";
          m.group = set.name + "/vndf_nominal";
          m.extra = ang;
          m.extra["chi2"] = g.chi2;
          m.extra["dof"] = g.dof;
          m.extra["p_value"] = g.p_value;
          m.error = "rays (one surface: surface-to-surface variation not included)";
          out.rows.push_back(m);
          auto& dv = dv_by_direction[{t, p}];
          dv.resize(static_cast<std::size_t>(binning.size()));
          for (int b = 0; b < binning.size(); ++b) dv[b].push_back(floored(r.dv(b), r.hits, 1.0 / binning.solid_angle(b)));
          // The sampler only depends on the nominal NDF: tested once per direction.
          if (k == 0) {
            sampler = test_vndf_sampler(*s.nominal, v, vo.rays, binning, o.seed ^ 0x5a5a5a5aULL);
            Row sr = make_row(set, "", "vndf_sampler_chi2_per_dof", "sampler_model", Kind::Identity,
                              "models/ndf.hpp VNDF sampler vs its own D_v (001 eq. 13)");
            sr.condition = set.name + " nominal sampler, theta " + angle(t) + " phi " + angle(p);
            set_chi2(sr, sampler->gof.chi2, sampler->gof.dof);
            sr.error = "samples";
            sr.group = set.name + "/vndf_sampler";
            sr.extra = ang;
            sr.extra["chi2"] = sampler->gof.chi2;
            sr.extra["dof"] = sampler->gof.dof;
            sr.extra["p_value"] = sampler->gof.p_value;
            out.rows.push_back(sr);
          }
        }
        progress.completed += unit;
        progress.update();
        Table vndf_rows = vndf_table(vo.family_alpha);
        Json& row = add_row(vndf_rows, r, s, vo, sampler);
        row["theta_deg"] = t;
        row["phi_deg"] = p;
        rows.push_back(row);
      }
    per_surface.push_back({{"label", set.labels[k]}, {"rows", rows}});
  }
  if (set.surfaces.size() > 1 && set.surfaces[0].nominal)
    for (double p : o.phi_deg)
      for (double t : o.theta_deg) {
        const Vec3 v = direction_from_angles(rad(t), rad(p));
        const std::vector<double> model =
            bin_integrals(binning, [&](const Vec3& m) { return set.surfaces[0].nominal->D_visible(v, m); });
        const std::string dir = "theta " + angle(t) + " phi " + angle(p);
        for (int b = 0; b < binning.size(); ++b) {
          if (model[b] < kVndfMinBinMass) continue;
          const int it = b / binning.n_phi(), iph = b % binning.n_phi();
          const double tlo = deg(binning.theta_lo(it)), thi = deg(binning.theta_hi(it));
          const double plo = deg(binning.phi_lo(iph)), phi_hi = deg(binning.phi_hi(iph));
          Row r = make_row(set, "", "vndf_bin", "nominal", Kind::Model,
                           "001 eq. (13): D_v of the nominal NDF, bin average");
          push_nominal(out, std::move(r),
                       dir + ", m in [" + angle(tlo) + "," + angle(thi) + "]x[" + angle(plo) + "," +
                           angle(phi_hi) + "]",
                       dv_by_direction[{t, p}][b], model[b] / binning.solid_angle(b),
                       set.name + "/vndf_nominal_bins/" + dir,
                       {{"theta_deg", t}, {"phi_deg", p}, {"theta_m_range_deg", {tlo, thi}},
                        {"phi_m_range_deg", {plo, phi_hi}}});
        }
      }
  out.measurements = per_surface;
}

// ---------------------------------------------------------------------------------------------
// BSDF albedos with a mirror material: total albedo = 1 (energy conservation, exact: every
// path leaves, lost and unterminated paths counted), the order-1 albedo against the
// single-scattering albedo of the nominal NDF (Smith height-correlated,
// models/microfacet_bsdf.hpp) and the per-order albedos against the Smith random walk
// (models/smith_random_walk.hpp): nominal models, so compared over an ensemble with the
// between-surface error (the walk's own error added), info rows for one surface.
const std::vector<double>& bsdf_theta() {
  static const std::vector<double> t = {30, 70};
  return t;
}

double bsdf_work(const SurfaceSet& set) {
  const double n = static_cast<double>(share_of_rays(set.options, 4));
  // Per surface and angle the measured paths (x2 for the tracing cost); the model walks once.
  return static_cast<double>(bsdf_theta().size()) *
         (2.0 * static_cast<double>(set.surfaces.size()) + (set.surfaces[0].nominal ? 1.0 : 0.0)) * n;
}

void check_bsdf_albedo(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  const Options& o = set.options;
  const std::size_t S = set.surfaces.size();
  constexpr int K = 4;  // orders 1, 2, 3, 4+
  Json per_surface = Json::array();
  // Per angle: per order (0..K, K = total) the albedo of each surface, and the walk's albedo.
  std::vector<std::vector<std::vector<Estimate>>> albedo(bsdf_theta().size(),
                                                         std::vector<std::vector<Estimate>>(K + 1));
  std::vector<std::vector<Estimate>> walk(bsdf_theta().size());
  std::vector<Vec3> wi(bsdf_theta().size());
  for (std::size_t k = 0; k < S; ++k) {
    const Microsurface& s = set.surfaces[k];
    const std::string label = surface_label(set, k);
    Tracer tracer(s);
    Json rows = Json::array();
    for (std::size_t ia = 0; ia < bsdf_theta().size(); ++ia) {
      const double t = bsdf_theta()[ia];
      BsdfOptions bo;
      bo.material = models::Material::mirror();
      bo.theta_i = rad(t);
      bo.orders = K;
      bo.rays = share_of_rays(o, 4);
      bo.seed = o.seed;
      bo.split = o.split;
      bo.resolution = 16;
      // The walk depends only on the nominal NDF: run once, with the first surface.
      bo.model_walks = s.nominal && k == 0 ? bo.rays : 0;
      const double unit = (bo.model_walks > 0 ? 3.0 : 2.0) * static_cast<double>(bo.rays);
      bo.progress = [&](double f) { progress.update(f * unit); };
      const BsdfResult r = measure_bsdf(tracer, bo);
      progress.completed += unit;
      progress.update();
      const std::string where = (label.empty() ? "" : label + ", ") + "mirror, theta_i " + angle(t);
      const Json ang = {{"theta_i_deg", t}};
      // Finite objects against their visible area ratio; V-grooves and V-cavity ensembles
      // against the closed forms (validate/bsdf_object_rows.hpp).
      append_bsdf_object_rows(r, s, make_row(set, "", "", "", Kind::Identity, ""), where,
                              set.name, ang, out.rows);
      // Energy conservation: every path of a mirror carries weight 1 and leaves (or is lost).
      const Estimate up = r.albedo(0, K), down = r.albedo(1, K);
      Row e = albedo_total_row(r.measured.paths, r.measured.lost, r.measured.unterminated, up.mean,
                               down.mean);
      e.entry = set.name;
      e.condition = set.name + " " + where;
      e.group = set.name + "/albedo_total";
      e.extra["theta_i_deg"] = t;
      if (mirror_total_is_one(s)) out.rows.push_back(e);
      Json row = {{"theta_i_deg", t}, {"paths", r.measured.paths}, {"lost", r.measured.lost},
                  {"unterminated", r.measured.unterminated}, {"albedo", Json::array()},
                  {"albedo_stderr", Json::array()}};
      for (int j = 0; j <= K; ++j) {
        const Estimate a = floored(r.albedo(0, j), r.measured.paths);
        row["albedo"].push_back(a.mean);
        row["albedo_stderr"].push_back(a.stderr_);
        albedo[ia][j].push_back(a);
        if (bo.model_walks > 0) walk[ia].push_back(r.model_albedo(0, j));
      }
      wi[ia] = r.wi;
      rows.push_back(row);
    }
    per_surface.push_back({{"label", set.labels[k]}, {"rows", rows}});
  }
  const Microsurface& s0 = set.surfaces[0];
  if (s0.nominal) {
    for (std::size_t ia = 0; ia < bsdf_theta().size(); ++ia) {
      const double t = bsdf_theta()[ia];
      const std::string where = "mirror, theta_i " + angle(t);
      const Json ang = {{"theta_i_deg", t}};
      models::MicrofacetBsdf ss;
      ss.ndf = *s0.nominal;
      ss.material = models::Material::mirror();
      ss.masking = models::Masking::SmithHeightCorrelated;
      const double single = models::single_scattering_albedo(ss, wi[ia]).reflected;
      Row m = make_row(set, "", "albedo_order_1", "single_scattering_smith", Kind::Model,
                       "models/microfacet_bsdf.hpp single_scattering_albedo (001 eq. 21 G2)");
      push_nominal(out, std::move(m), where, albedo[ia][0], single,
                   set.name + "/albedo_single_scattering", ang);
      Json mj = {{"single_scattering_model", single}, {"smith_walk_albedo", Json::array()},
                 {"smith_walk_albedo_stderr", Json::array()}};
      for (int j = 0; j <= K; ++j) {
        const Estimate w = walk[ia][j];
        // The walk's Monte Carlo error enters as a floor of every surface's error (it is
        // common to all K comparisons, so it is added to the mean's error below).
        Row rw = make_row(set, "", "albedo_" + order_key(j, K), "smith_random_walk", Kind::Model,
                          "models/smith_random_walk.hpp (Heitz et al. 2016), nominal NDF");
        Json ex = ang;
        ex["order"] = order_key(j, K);
        push_nominal(out, std::move(rw), where, albedo[ia][j], w.mean,
                     set.name + "/albedo_smith_walk", ex);
        if (out.rows.back().stderr_) out.rows.back().stderr_ = std::hypot(*out.rows.back().stderr_, w.stderr_);
        mj["smith_walk_albedo"].push_back(w.mean);
        mj["smith_walk_albedo_stderr"].push_back(w.stderr_);
      }
      // The models beside every surface's row of this angle (as in a single-surface run).
      for (auto& ps : per_surface) ps["rows"][ia].update(mj);
    }
  }
  out.measurements = per_surface;
}

// An info row when the set's coarsest surface is coarser than the converged level of the study
// for the quantities of `check` (README "Converged surfaces"): the rows then describe the
// triangulated grid more than the continuous surface it stands for.
std::optional<Row> discretization_row(const SurfaceSet& set, const std::string& check) {
  const auto level = converged_level(check);
  if (!level) return std::nullopt;
  std::optional<Discretization> coarsest;
  for (const Microsurface& m : set.surfaces) {
    const auto d = discretization_of(m.description);
    if (!d) continue;
    if (!coarsest) coarsest = d;
    coarsest->cells_per_correlation_length =
        std::min(coarsest->cells_per_correlation_length, d->cells_per_correlation_length);
    coarsest->correlation_lengths_per_tile =
        std::min(coarsest->correlation_lengths_per_tile, d->correlation_lengths_per_tile);
  }
  if (!coarsest) return std::nullopt;
  const bool coarse_grid = coarsest->cells_per_correlation_length < level->cells_per_correlation_length * (1 - 1e-9);
  const bool small_tile = coarsest->correlation_lengths_per_tile < level->correlation_lengths_per_tile * (1 - 1e-9);
  if (!coarse_grid && !small_tile) return std::nullopt;
  Row r = make_row(set, "", coarse_grid ? "cells_per_correlation_length" : "correlation_lengths_per_tile",
                   "converged_level", Kind::Info, "discretization study (analysis/convergence.sh)");
  r.measured = coarse_grid ? coarsest->cells_per_correlation_length : coarsest->correlation_lengths_per_tile;
  r.model = coarse_grid ? level->cells_per_correlation_length : level->correlation_lengths_per_tile;
  r.condition += ": coarser than the converged level for " + check + " (" + level->what + "): " +
                 num(coarsest->cells_per_correlation_length, 3) + " cells per l (converged " +
                 num(level->cells_per_correlation_length, 3) + "), " +
                 num(coarsest->correlation_lengths_per_tile, 4) + " l per tile (converged " +
                 num(level->correlation_lengths_per_tile, 4) + ")";
  r.error = "none";
  r.extra = {{"check", check},
             {"cells_per_correlation_length", coarsest->cells_per_correlation_length},
             {"correlation_lengths_per_tile", coarsest->correlation_lengths_per_tile},
             {"converged_cells_per_correlation_length", level->cells_per_correlation_length},
             {"converged_correlation_lengths_per_tile", level->correlation_lengths_per_tile}};
  return r;
}

}  // namespace

const std::vector<Check>& checks() {
  static const std::vector<Check> registry = {
      {"d_identities", "000 eq. 1b and 1c from the facets (exact, to rounding)",
       [](const SurfaceSet&) { return true; },
       [](const SurfaceSet& s) {
         double w = 0;
         for (const auto& m : s.surfaces) w += 0.1 * static_cast<double>(m.num_facets());
         return w;
       },
       check_d_identities},
      {"d_nominal", "D per theta ring and the fitted alpha against the generator's nominal NDF",
       [](const SurfaceSet& s) { return s.surfaces[0].nominal.has_value(); },
       [](const SurfaceSet& s) {
         double w = 0;
         for (const auto& m : s.surfaces) w += 0.2 * static_cast<double>(m.num_facets());
         return w;
       },
       check_d_nominal},
      {"g1", "G1: both estimators, visible area ratio, Smith from the facets and nominal, per-bin "
             "G1(v,m) against Smith and the V-cavity model",
       [](const SurfaceSet&) { return true; }, g1_work, check_g1},
      {"g2", "G2: symmetry and hotspot identities; the four Smith forms (facets and nominal) and "
             "the V-cavity model for the averaged G2",
       [](const SurfaceSet&) { return true; }, g2_work, check_g2},
      {"vndf", "VNDF histogram against the nominal D_v (chi-square), and the nominal NDF's VNDF "
               "sampler against its own D_v (identity)",
       [](const SurfaceSet& s) { return s.surfaces[0].nominal.has_value(); }, vndf_work, check_vndf},
      {"bsdf_albedo", "mirror BSDF albedos: total = 1 (energy conservation; finite objects: the "
                      "visible area ratio), order 1 against the single-scattering model, per order "
                      "against the Smith random walk and the V-groove / V-cavity closed forms",
       [](const SurfaceSet&) { return true; }, bsdf_work, check_bsdf_albedo},
  };
  return registry;
}

Result run(const std::vector<SurfaceSet>& sets, double significance,
           const std::function<void(double)>& report) {
  if (!(significance > 0 && significance < 1))
    throw UsageError("--significance must be in (0, 1) (got " + num(significance) + ")");
  auto t0 = std::chrono::steady_clock::now();
  // Resolve the checks of every set first: an unknown name fails before any work.
  std::vector<std::vector<const Check*>> todo(sets.size());
  Progress progress;
  progress.report = report;
  for (std::size_t i = 0; i < sets.size(); ++i) {
    const SurfaceSet& set = sets[i];
    if (set.surfaces.empty()) throw UsageError("validation entry " + set.name + " has no surface");
    if (set.labels.size() != set.surfaces.size())
      throw RuntimeFailure("validation entry " + set.name + ": one label per surface expected");
    const Options& o = set.options;
    if (o.theta_deg.empty() || o.phi_deg.empty())
      throw UsageError("validation entry " + set.name + ": no view direction (--theta, --phi)");
    for (double t : o.theta_deg)
      if (!(t >= 0 && t < 90)) throw UsageError("--theta must be in [0, 90) degrees (got " + num(t) + ")");
    if (o.rays == 0) throw UsageError("--rays must be positive");
    for (const std::string& name : set.options.checks) {
      auto it = std::find_if(checks().begin(), checks().end(), [&](const Check& c) { return c.name == name; });
      if (it == checks().end()) {
        std::string known;
        for (const Check& c : checks()) known += (known.empty() ? "" : ", ") + c.name;
        throw UsageError("unknown check '" + name + "' (known: " + known + ")");
      }
    }
    for (const Check& c : checks()) {
      const bool wanted = set.options.checks.empty() ||
                          std::find(set.options.checks.begin(), set.options.checks.end(), c.name) !=
                              set.options.checks.end();
      if (wanted && c.applies(set)) {
        todo[i].push_back(&c);
        progress.total += c.work(set);
      }
    }
  }
  Result result;
  result.significance = significance;
  for (std::size_t i = 0; i < sets.size(); ++i) {
    const SurfaceSet& set = sets[i];
    EntryResult e;
    e.name = set.name;
    for (std::size_t k = 0; k < set.surfaces.size(); ++k)
      e.surfaces.push_back({{"label", set.labels[k]}, {"description", set.surfaces[k].description},
                            {"facets", set.surfaces[k].num_facets()},
                            {"periodic", set.surfaces[k].macro().periodic}});
    const Options& o = set.options;
    e.parameters = {{"theta_deg", o.theta_deg}, {"phi_deg", o.phi_deg}, {"rays", o.rays},
                    {"seed", o.seed}, {"ndf_theta_bins", o.ndf_theta_bins},
                    {"ndf_phi_bins", o.ndf_phi_bins}, {"min_ring_mass", o.min_ring_mass},
                    {"min_bin_count", o.min_bin_count}, {"checks", Json::array()}};
    for (const Check* c : todo[i]) {
      e.parameters["checks"].push_back(c->name);
      CheckOutput out;
      c->run(set, progress, out);
      result.rows.insert(result.rows.end(), out.rows.begin(), out.rows.end());
      e.measurements[c->name] = out.measurements;
      if (auto row = discretization_row(set, c->name)) result.rows.push_back(*row);
    }
    result.entries.push_back(std::move(e));
  }
  result.z_threshold = assign_verdicts(result.rows, significance);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

Json row_to_json(const Row& r) {
  Json j;
  j["quantity"] = r.quantity;
  j["model_name"] = r.model_name;
  j["condition"] = r.condition;
  j["entry"] = r.entry;
  j["kind"] = to_string(r.kind);
  j["measured"] = r.measured;
  j["stderr"] = r.stderr_ ? Json(*r.stderr_) : Json(nullptr);
  j["model"] = r.model ? Json(*r.model) : Json(nullptr);
  j["z"] = r.z && std::isfinite(*r.z) ? Json(*r.z) : Json(nullptr);
  if (r.z && !std::isfinite(*r.z)) j["z_infinite"] = true;
  j["rel_dev"] = r.rel_dev ? Json(*r.rel_dev) : Json(nullptr);
  j["verdict"] = r.verdict;
  if (r.kind == Kind::Deterministic) j["tolerance"] = r.tolerance;
  j["t_dof"] = r.dof ? Json(*r.dof) : Json(nullptr);
  j["z_threshold"] = r.threshold ? Json(*r.threshold) : Json(nullptr);
  j["error"] = r.error;
  j["reference"] = r.reference;
  j["group"] = r.group;
  for (auto it = r.extra.begin(); it != r.extra.end(); ++it) j[it.key()] = it.value();
  return j;
}

Json verdict_rules_json(double significance, double z_threshold, std::size_t comparisons) {
  return {
      {"identity", "exact identity measured by Monte Carlo: pass when |z| <= the row's z_threshold, else FAIL"},
      {"deterministic", "exact identity without sampling: pass when |measured - model| <= tolerance "
                        "(bound on double rounding of the facet sums), else FAIL"},
      {"model", "approximate model: agrees when |z| <= the row's z_threshold, else 'deviates "
                "(finding)'; a deviation is a result about the model, not an error. Nominal models "
                "(the generator's NDF) are model rows only over ensembles of surfaces (between-surface "
                "error), info rows for one surface"},
      {"info", "measured without a model or without an error bar: 'measured'"},
      {"z", "(measured - model) / stderr"},
      {"rel_dev", "(measured - model) / |model|"},
      {"z_threshold", "Sidak: per-row rate 1 - (1 - significance)^(1/comparisons) over the "
                      "'comparisons' z-tested rows of the run; the two-sided normal quantile at that "
                      "rate (z_threshold_value), or for rows with an error from K surfaces (t_dof = "
                      "K - 1) the two-sided Student t quantile with K - 1 degrees of freedom"},
      {"t_dof", "degrees of freedom of a row's error: K - 1 for the spread of K surfaces, null for "
              "ray-count errors (normal)"},
      {"significance", significance},
      {"comparisons", comparisons},
      {"z_threshold_value", z_threshold},
      {"stderr_floor", "errors of proportions from n samples are at least that of (n+1/2)/(n+1) "
                       "(about 0.7/n): a proportion of 0 or 1 is known only to ~1/n"},
      {"exit_code", "1 when any row is FAIL, else 0"}};
}

Json result_to_json(const Result& r) {
  Json j;
  std::size_t tested = 0;
  for (const Row& row : r.rows) tested += row.z.has_value();
  j["significance"] = r.significance;
  j["z_threshold"] = r.z_threshold;
  j["comparisons"] = tested;
  j["verdict_rules"] = verdict_rules_json(r.significance, r.z_threshold, tested);
  j["summary"] = {{"rows", r.rows.size()},
                  {"pass", r.count("pass")},
                  {"fail", r.count("FAIL")},
                  {"agrees", r.count("agrees")},
                  {"deviates", r.count("deviates (finding)")},
                  {"measured", r.count("measured")}};
  Json entries = Json::array();
  for (const EntryResult& e : r.entries)
    entries.push_back({{"name", e.name}, {"surfaces", e.surfaces}, {"parameters", e.parameters},
                       {"measurements", e.measurements}});
  j["entries"] = entries;
  Json rows = Json::array();
  for (const Row& row : r.rows) rows.push_back(row_to_json(row));
  j["rows"] = rows;
  j["seconds"] = r.seconds;
  return j;
}

std::string format_table(const Result& r) {
  struct Line {
    std::string quantity, condition, measured, model, z, thr, rel, verdict;
  };
  std::vector<Line> lines;
  lines.push_back({"quantity", "condition", "measured +- stderr", "model", "z", "|z|max", "rel_dev", "verdict"});
  // Group rows: a group is shown once, where its first row is, by its worst row.
  std::vector<std::vector<const Row*>> blocks;
  std::map<std::string, std::size_t> group_block;
  for (const Row& row : r.rows) {
    if (row.group.empty()) {
      blocks.push_back({&row});
      continue;
    }
    auto [it, fresh] = group_block.try_emplace(row.group, blocks.size());
    if (fresh) blocks.emplace_back();
    blocks[it->second].push_back(&row);
  }
  for (const auto& members : blocks) {
    // The worst row: a FAIL first, then the largest |z| (deterministic rows: |d| / tolerance).
    auto badness = [](const Row* x) {
      double b = -1;
      if (x->z) b = std::abs(*x->z);
      else if (x->kind == Kind::Deterministic && x->model)
        b = std::abs(x->measured - *x->model) / std::max(x->tolerance, 1e-300);
      return std::make_pair(x->verdict == "FAIL", b);
    };
    const Row* worst = members[0];
    std::size_t deviating = 0;
    for (const Row* m : members) {
      if (m->verdict == "FAIL" || m->verdict == "deviates (finding)") ++deviating;
      if (badness(m) > badness(worst)) worst = m;
    }
    Line l;
    l.quantity = worst->quantity + (worst->model_name.empty() ? "" : " vs " + worst->model_name);
    l.condition = worst->condition;
    if (members.size() > 1)
      l.condition += "  [worst of " + std::to_string(members.size()) + ", " +
                     std::to_string(deviating) + " outside]";
    l.measured = num(worst->measured) + (worst->stderr_ ? " +- " + num(*worst->stderr_, 2) : "");
    l.model = worst->model ? num(*worst->model) : "-";
    l.z = worst->z ? (std::isfinite(*worst->z) ? fixed(*worst->z, 2) : (*worst->z > 0 ? "inf" : "-inf"))
                   : "-";
    l.thr = worst->threshold ? fixed(*worst->threshold, 2) + (worst->dof ? " t" + std::to_string(*worst->dof) : "")
                             : "-";
    l.rel = worst->rel_dev ? fixed(100 * *worst->rel_dev, 3) + "%" : "-";
    if (worst->kind == Kind::Deterministic && worst->model)
      l.z = "|d|=" + num(std::abs(worst->measured - *worst->model), 2);
    l.verdict = worst->verdict;
    lines.push_back(l);
  }
  std::size_t w[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (const Line& l : lines) {
    const std::string* f[8] = {&l.quantity, &l.condition, &l.measured, &l.model, &l.z, &l.rel, &l.verdict, &l.thr};
    for (int c = 0; c < 8; ++c) w[c] = std::max(w[c], f[c]->size());
  }
  std::ostringstream os;
  for (const Line& l : lines) {
    os << std::left << std::setw(static_cast<int>(w[0])) << l.quantity << "  "
       << std::setw(static_cast<int>(w[1])) << l.condition << "  " << std::right
       << std::setw(static_cast<int>(w[2])) << l.measured << "  " << std::setw(static_cast<int>(w[3]))
       << l.model << "  " << std::setw(static_cast<int>(w[4])) << l.z << "  "
       << std::setw(static_cast<int>(w[7])) << l.thr << "  " << std::setw(static_cast<int>(w[5])) << l.rel << "  " << std::left << l.verdict << "\n";
  }
  return os.str();
}

// ---------------------------------------------------------------------------------------------
// Suites.

namespace {
[[noreturn]] void suite_error(const std::string& file, const std::string& what) {
  throw UsageError("--suite " + file + ": " + what);
}

// A positive integer (JSON integer, or a number with an integral value such as 1e6).
std::uint64_t get_count(const Json& j, const char* key, const std::string& file, const std::string& where) {
  const Json& x = j[key];
  if (!x.is_number() || !(x.get<double>() >= 1) || x.get<double>() != std::floor(x.get<double>()) ||
      x.get<double>() > 9e18)
    suite_error(file, where + ": " + key + " must be a positive integer");
  return x.is_number_unsigned() ? x.get<std::uint64_t>() : static_cast<std::uint64_t>(x.get<double>());
}

void read_options(const Json& j, Options& o, const std::string& file, const std::string& where) {
  try {
    if (j.contains("theta_deg")) o.theta_deg = j["theta_deg"].get<std::vector<double>>();
    if (j.contains("phi_deg")) o.phi_deg = j["phi_deg"].get<std::vector<double>>();
    if (j.contains("rays")) o.rays = get_count(j, "rays", file, where);
    if (j.contains("seed")) o.seed = j["seed"].is_number_unsigned() ? j["seed"].get<std::uint64_t>()
                                                                    : get_count(j, "seed", file, where);
    if (j.contains("checks")) o.checks = j["checks"].get<std::vector<std::string>>();
    if (j.contains("ndf_theta_bins")) o.ndf_theta_bins = static_cast<int>(get_count(j, "ndf_theta_bins", file, where));
    if (j.contains("ndf_phi_bins")) o.ndf_phi_bins = static_cast<int>(get_count(j, "ndf_phi_bins", file, where));
    if (j.contains("min_ring_mass")) o.min_ring_mass = j["min_ring_mass"].get<double>();
    if (j.contains("min_bin_count")) o.min_bin_count = get_count(j, "min_bin_count", file, where);
  } catch (const Json::exception& e) {
    suite_error(file, where + ": " + e.what());
  }
  for (double t : o.theta_deg)
    if (!(t >= 0 && t < 90)) suite_error(file, where + ": theta_deg must be in [0, 90) degrees");
  if (o.theta_deg.empty() || o.phi_deg.empty()) suite_error(file, where + ": empty theta_deg or phi_deg");
  if (o.ndf_theta_bins > 3600 || o.ndf_phi_bins > 7200)
    suite_error(file, where + ": ndf_theta_bins in [1, 3600], ndf_phi_bins in [1, 7200]");
  if (!(o.min_ring_mass >= 0)) suite_error(file, where + ": min_ring_mass must be >= 0");
}

bool is_option_key(const std::string& k) {
  static const char* keys[] = {"theta_deg", "phi_deg", "rays", "seed", "checks", "ndf_theta_bins",
                               "ndf_phi_bins", "min_ring_mass", "min_bin_count"};
  return std::find(std::begin(keys), std::end(keys), k) != std::end(keys);
}
}  // namespace

Suite load_suite(const std::string& path) {
  namespace fs = std::filesystem;
  std::ifstream in(path);
  if (!in) throw UsageError("--suite " + path + ": cannot read the file");
  Json j;
  try {
    j = Json::parse(in, nullptr, true, /*ignore_comments=*/true);
  } catch (const Json::exception& e) {
    suite_error(path, std::string("not valid JSON (") + e.what() + ")");
  }
  if (!j.is_object()) suite_error(path, "expected a JSON object");
  Suite s;
  s.file = path;
  s.name = j.value("name", fs::path(path).stem().string());
  s.description = j.value("description", "");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "name" && it.key() != "description" && it.key() != "significance" &&
        it.key() != "defaults" && it.key() != "entries")
      suite_error(path, "unknown field '" + it.key() + "'");
  if (j.contains("significance")) {
    if (!j["significance"].is_number()) suite_error(path, "significance must be a number");
    s.significance = j["significance"].get<double>();
    if (!(s.significance > 0 && s.significance < 1)) suite_error(path, "significance must be in (0, 1)");
  }
  Options defaults;
  if (j.contains("defaults")) {
    if (!j["defaults"].is_object()) suite_error(path, "defaults must be an object");
    for (auto it = j["defaults"].begin(); it != j["defaults"].end(); ++it)
      if (!is_option_key(it.key())) suite_error(path, "defaults: unknown field '" + it.key() + "'");
    read_options(j["defaults"], defaults, path, "defaults");
  }
  if (!j.contains("entries") || !j["entries"].is_array() || j["entries"].empty())
    suite_error(path, "needs a non-empty 'entries' array");
  // Presets are looked up beside the suite file, then in its parent folder (surfaces/).
  const fs::path dir = fs::path(path).parent_path();
  for (const Json& e : j["entries"]) {
    SuiteEntry entry;
    if (!e.is_object() || !e.contains("name") || !e["name"].is_string())
      suite_error(path, "every entry needs a string 'name'");
    entry.name = e["name"].get<std::string>();
    const std::string where = "entry " + entry.name;
    for (auto it = e.begin(); it != e.end(); ++it)
      if (it.key() != "name" && it.key() != "generate" && it.key() != "preset" &&
          it.key() != "args" && it.key() != "seeds" && it.key() != "format" &&
          !is_option_key(it.key()))
        suite_error(path, where + ": unknown field '" + it.key() + "'");
    if (!e.contains("generate") || !e["generate"].is_string())
      suite_error(path, where + ": needs 'generate' (a generator kind, as in microsim generate KIND)");
    entry.generate = e["generate"].get<std::string>();
    if (e.contains("preset")) {
      if (!e["preset"].is_string()) suite_error(path, where + ": preset must be a string");
      fs::path p = e["preset"].get<std::string>();
      if (p.is_relative()) {
        fs::path a = dir / p, b = dir.parent_path() / p;
        p = fs::exists(a) ? a : b;
      }
      if (!fs::exists(p)) suite_error(path, where + ": preset " + e["preset"].get<std::string>() + " not found");
      entry.preset = fs::absolute(p).lexically_normal().string();
    }
    if (e.contains("args")) {
      if (!e["args"].is_object()) suite_error(path, where + ": args must be an object");
      for (auto it = e["args"].begin(); it != e["args"].end(); ++it) {
        std::string value = it.value().is_string() ? it.value().get<std::string>() : it.value().dump();
        if (it.value().is_boolean()) value = it.value().get<bool>() ? "true" : "false";
        entry.args.emplace_back(it.key(), value);
      }
    }
    if (e.contains("seeds")) {
      try {
        entry.seeds = e["seeds"].get<std::vector<std::uint64_t>>();
      } catch (const Json::exception&) {
        suite_error(path, where + ": seeds must be an array of non-negative integers");
      }
    }
    if (e.contains("format")) {
      entry.format = e["format"].is_string() ? e["format"].get<std::string>() : "";
      if (entry.format != "exr" && entry.format != "ply" && entry.format != "obj" && entry.format != "off")
        suite_error(path, where + ": format must be exr, ply, obj or off");
    }
    entry.options = defaults;
    read_options(e, entry.options, path, where);
    s.entries.push_back(entry);
  }
  return s;
}

std::string find_suite(const std::string& name, const std::vector<std::string>& dirs) {
  namespace fs = std::filesystem;
  if (fs::is_regular_file(name)) return name;
  for (const std::string& d : dirs) {
    fs::path p = fs::path(d) / (name + ".json");
    if (fs::is_regular_file(p)) return p.string();
  }
  std::string known;
  for (const std::string& d : dirs)
    for (const std::string& n : list_suites(d)) known += (known.empty() ? "" : ", ") + n;
  throw UsageError("--suite " + name + ": no such suite (known: " + (known.empty() ? "none" : known) + ")");
}

std::vector<std::string> list_suites(const std::string& dir) {
  namespace fs = std::filesystem;
  std::vector<std::string> names;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return names;
  for (const auto& f : fs::directory_iterator(dir, ec))
    if (f.path().extension() == ".json") names.push_back(f.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace microsim::validation
