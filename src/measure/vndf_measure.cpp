#include "microsim/measure/vndf_measure.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <chrono>

#include "microsim/measure/sampling.hpp"
#include "microsim/measure/stats.hpp"
#include "vndf_estimator.hpp"
#include "microsim/measure/facet_table.hpp"

namespace microsim {

namespace {
// Origins first .. first + origins.size() - 1 of the stream, i.i.d. uniform in the unit square,
// sorted in Morton order with their coordinates as tie-breaks (VndfOrigin's order).
void draw_sorted_origins(std::uint64_t seed, std::uint64_t stream, std::uint64_t first,
                         std::vector<VndfOrigin>& origins) {
  tbb::parallel_for(std::uint64_t(0), static_cast<std::uint64_t>(origins.size()), [&](std::uint64_t j) {
    CounterRng rng(seed, stream, first + j);
    const double a = rng.uniform(), b = rng.uniform();
    origins[j] = VndfOrigin::of(a, b);
  });
  tbb::parallel_sort(origins.begin(), origins.end());
}
}  // namespace

std::vector<double> bin_integrals(const DirectionBinning& bins,
                                  const std::function<double(const Vec3&)>& f) {
  const int sub = 4;
  const double theta_max = bins.theta_hi(bins.n_theta() - 1);
  DirectionBinning fine(bins.n_theta() * sub, bins.n_phi() * sub, theta_max);
  std::vector<double> p(bins.size(), 0.0);
  for (int it = 0; it < fine.n_theta(); ++it)
    for (int ip = 0; ip < fine.n_phi(); ++ip) {
      const int fb = fine.index(it, ip);
      p[bins.index(it / sub, ip / sub)] += fine.bin_average(fb, f) * fine.solid_angle(fb);
    }
  return p;
}

GofResult histogram_gof(const std::vector<std::uint64_t>& counts, std::uint64_t total,
                        const std::vector<double>& probs, double family_alpha) {
  GofResult g;
  const double n = static_cast<double>(total);
  double rest_p = 1.0, rest_c = n;
  for (std::size_t b = 0; b < probs.size(); ++b) {
    const double e = n * probs[b];
    if (e < 5) continue;
    const double c = static_cast<double>(counts[b]);
    g.chi2 += (c - e) * (c - e) / e;
    ++g.cells;
    rest_p -= probs[b];
    rest_c -= c;
    const double z = (c - e) / std::sqrt(e * (1 - probs[b]));
    g.max_abs_z = std::max(g.max_abs_z, std::abs(z));
    ++g.bins_tested;
  }
  // Everything else (small bins, outside the binned range) pooled into one cell.
  const double e_rest = n * std::max(0.0, rest_p);
  if (e_rest >= 1) {
    g.chi2 += (rest_c - e_rest) * (rest_c - e_rest) / e_rest;
    ++g.cells;
  }
  g.dof = std::max(0, g.cells - 1);
  g.p_value = chi2_p_value(g.chi2, g.dof);
  g.sidak_z = sidak_z(family_alpha, std::max(1, g.bins_tested));
  return g;
}

namespace {

// A whole surface as the estimator's one part, traced in the world frame. Its rays are drawn in
// batches of at most 2^22 (16 bytes per origin); every origin is an independent draw, so
// batching changes nothing statistically. Each batch is sorted in Morton order of the origins
// for coherence (the order does not change the statistics), and this process traces the rays at
// its share of the positions of the sorted batches (every process draws and sorts every batch:
// the sort is cheap beside the tracing).
class SurfaceRays : public VndfRays {
 public:
  SurfaceRays(const Tracer& tracer, const DirectionBinning& binning, std::uint64_t seed, std::uint64_t stream)
      : tracer_(tracer), binning_(binning), seed_(seed), stream_(stream) {}
  std::size_t parts() const override { return 1; }
  std::unique_ptr<Scene> scene(std::size_t) const override { return make_scene(tracer_); }
  Vec3 to_local(std::size_t, const Vec3& w) const override { return w; }
  std::uint64_t batch() const override { return std::uint64_t(1) << 22; }
  std::vector<std::vector<VndfOrigin>> origins(UnitRange rays, UnitRange share) const override {
    std::vector<std::vector<VndfOrigin>> out(1);
    std::vector<VndfOrigin>& sorted = out[0];
    sorted.resize(rays.size());
    draw_sorted_origins(seed_, stream_, rays.first, sorted);
    // This process's share of the positions [first, end) of the sorted batch: one slice.
    const auto at = [&](std::uint64_t n) { return static_cast<std::ptrdiff_t>(std::clamp(n, rays.first, rays.end) - rays.first); };
    sorted.erase(sorted.begin() + at(share.end), sorted.end());
    sorted.erase(sorted.begin(), sorted.begin() + at(share.first));
    return out;
  }
  // The bin of the hit's normal.
  int bin(std::size_t, const Scene&, const TraceHit& h) const override { return binning_.bin_of(h.normal); }

 private:
  const Tracer& tracer_;
  const DirectionBinning& binning_;
  std::uint64_t seed_, stream_;
};

}  // namespace

VndfResult measure_vndf(const Tracer& tracer, const Vec3& v_in, const VndfOptions& o,
                        const FacetTable* table) {
  const Microsurface& s = tracer.surface();
  VndfResult r = start_vndf(v_in, o, s.macro().area);
  auto t0 = std::chrono::steady_clock::now();
  const Vec3 v = r.v;
  const int nbins = r.binning.size();
  FacetTable own;
  const FacetTable& ft = facet_table_for(s, r.binning, table, own);
  const std::vector<double> sums = sum_over_facets(s.num_facets(), nbins + 1, [&](std::size_t k, double* acc) {
    Vec3 m;
    double a;
    ft.normal_area(k, m, a);
    const double proj = std::max(0.0, a * m.dot(v));
    const int b = ft.bin(k);
    acc[b >= 0 ? b : nbins] += proj;
  });
  r.front_projected.assign(sums.begin(), sums.begin() + nbins);
  for (double x : sums) r.front_projected_total += x;
  if (!(r.front_projected_total > 0)) throw RuntimeFailure("no facet faces the direction");
  r.window_area_perp = make_scene(tracer)->ray_window(v).area_perp;
  // Origins i.i.d. uniform over the window (not stratified): the bin counts are then exactly
  // multinomial, so the binomial standard errors and the chi-square p-values are calibrated
  // (stratified origins would make them conservative bounds, with chi-square far below its
  // degrees of freedom and no power).
  trace_vndf_rays(SurfaceRays(tracer, r.binning, o.seed, 0xD000 + direction_stream_key(v)), r, o);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

SamplerTest test_vndf_sampler(const models::Ndf& ndf, const Vec3& v_in, std::uint64_t n,
                              const DirectionBinning& bins, std::uint64_t seed,
                              double family_alpha) {
  SamplerTest t;
  const Vec3 v = v_in.normalized();
  t.n = n;
  const std::uint64_t stream = 0xE000 + direction_stream_key(v);
  TraceCounters unused;
  std::vector<std::uint64_t> counts;
  histogram_chunks(n, bins.size(), counts, unused,
                   [&](std::uint64_t j, std::vector<std::uint64_t>& c, TraceCounters&) {
                     CounterRng rng(seed, stream, j);
                     const double u1 = rng.uniform(), u2 = rng.uniform();
                     const int b = bins.bin_of(ndf.sample_visible_normal(v, u1, u2));
                     ++c[b >= 0 ? b : bins.size()];
                   });
  t.counts.assign(counts.begin(), counts.begin() + bins.size());
  t.outside = counts[bins.size()];
  t.probabilities = bin_integrals(bins, [&](const Vec3& m) { return ndf.D_visible(v, m); });  // [Heitz14, eq. 13]
  t.gof = histogram_gof(t.counts, n, t.probabilities, family_alpha);
  return t;
}

// Ensemble rows: per-bin D_v averaged over surfaces with the between-surface standard error,
// and the per-bin z against the nominal model with that error (Sidak threshold over the bins
// holding at least 0.2% of the visible normals; Student t with K - 1 degrees of freedom, since
// the error is the spread of K surfaces).
Table vndf_table(double family_alpha) {
  Table t;
  t.error = ErrorKind::Binomial;  // i.i.d. origins: multinomial bin counts
  const ErrorKind N = ErrorKind::None;
  t.spec.columns = {
      {"theta_deg", Merge::Copy, N, "deg", "view zenith angle"},
      {"phi_deg", Merge::Copy, N, "deg", "view azimuth"},
      {"surfaces", Merge::Count, N, "count", "number of surfaces K averaged (ensembles only), with t_dof = K - 1 after it"},
      {"rays", Merge::Mean, N, "count", "rays cast along -v from i.i.d. uniform origins"},
      {"visible_area_ratio", Merge::Spread, N, "1", "visible projected area / ((v.n) A), from the share of rays that hit"},
      {"tv_distance", Merge::Spread, N, "1",
       "total variation distance between the measured and the nominal bin probabilities (null without a nominal NDF)"},
      {"chi2_smith_numeric", Merge::Mean, N, "1",
       "Pearson chi-square of the hit histogram against Smith's D_v from the surface's own facets"},
      {"sampler_samples", Merge::Copy, N, "count", "normals drawn by the nominal NDF's VNDF sampler (when tested)"},
      {"sampler_chi2", Merge::Copy, N, "1", "Pearson chi-square of the sampler's histogram against the nominal D_v"},
      {"sampler_dof", Merge::Copy, N, "count", "degrees of freedom of sampler_chi2"},
      {"sampler_p_value", Merge::Copy, N, "1", "upper tail probability of sampler_chi2"},
      {"sampler_max_abs_z", Merge::Copy, N, "1", "largest per-bin |z| of the sampler's histogram"},
      {"sampler_pass", Merge::Copy, N, "", "true when the sampler's histogram passes the Sidak-corrected per-bin test"}};
  t.spec.bin_columns = {
      {"theta_m_range_deg", Merge::Key, N, "deg", "zenith range [lo, hi] of the normal bin"},
      {"phi_m_range_deg", Merge::Key, N, "deg", "azimuth range [lo, hi] of the normal bin"},
      {"dv", Merge::Spread, ErrorKind::Binomial, "1/sr",
       "measured D_v: share of the front-face first hits whose normal is in the bin / solid angle of the bin"},
      {"dv_smith_numeric", Merge::Spread, N, "1/sr",
       "Smith's D_v from the surface's own facets: sum_f in bin A_f max(0, v.m_f) / sum_f A_f max(0, v.m_f) / solid angle"},
      {"dv_model", Merge::Copy, N, "1/sr",
       "bin average of the nominal NDF's D_v(m) = G1(v) max(0, v.m) D(m) / (v.n) (null without one)"}};
  t.spec.bin_comparisons = {{"dv", "dv_model", ModelKind::Nominal, "z", "rel_dev", ""}};
  t.spec.row_fields = {
      {"replicates", Merge::Copy, N, "", "null: the ray origins are i.i.d. (no replicates; the binomial error is exact)"},
      {"hits", Merge::Copy, N, "count", "rays whose first hit is a front face (the histogram's total)"},
      {"hits_below_horizon", Merge::Copy, N, "count", "of which with a normal below the horizon (in no bin)"}};
  for (const std::string model : {"", "_smith_numeric"}) {
    const std::string against = model.empty() ? "the nominal D_v (null without one)" : "dv_smith_numeric";
    if (model.empty())
      t.spec.row_fields.push_back({"chi2", Merge::Copy, N, "1", "Pearson chi-square of the hit histogram against " + against});
    t.spec.row_fields.insert(t.spec.row_fields.end(), {
        {"dof" + model, Merge::Copy, N, "count", "degrees of freedom of chi2" + model},
        {"p_value" + model, Merge::Copy, N, "1", "upper tail probability of chi2" + model},
        {"max_abs_z" + model, Merge::Copy, N, "1", "largest per-bin |z| against " + against + " over the bins tested"},
        {"bins_tested" + model, Merge::Copy, N, "count", "bins with at least 5 expected hits"},
        {"sidak_z" + model, Merge::Copy, N, "1", "two-sided threshold of family_alpha, Sidak-corrected over the bins tested"},
        {"pass" + model, Merge::Copy, N, "", "max_abs_z" + model + " < sidak_z" + model}});
  }
  for (const Column& f : tracer_count_fields(true)) t.spec.row_fields.push_back(f);
  t.spec.bin_fields = {{"hits", Merge::Copy, N, "count", "hits whose normal is in the bin"}};
  t.spec.verdict = [family_alpha](Json& e, std::size_t surfaces) {
    const Json& bins = e["bins"];
    double max_abs_z = 0;
    int tested = 0;
    for (const auto& b : bins) {
      if (!b["dv_model"].is_number()) continue;
      const double se = b["dv_stderr"].get<double>(), model = b["dv_model"].get<double>();
      // The bin's share of the visible normals under the model: D_v times its solid angle.
      const double w = (std::cos(rad(b["theta_m_range_deg"][0].get<double>())) -
                        std::cos(rad(b["theta_m_range_deg"][1].get<double>()))) *
                       rad(b["phi_m_range_deg"][1].get<double>() - b["phi_m_range_deg"][0].get<double>());
      if (model * w >= 0.002 && se > 0 && b["z"].is_number()) {
        max_abs_z = std::max(max_abs_z, std::abs(b["z"].get<double>()));
        ++tested;
      }
    }
    if (!bins.empty() && bins[0]["dv_model"].is_number()) {
      e["bins_tested"] = tested;
      e["max_abs_z"] = max_abs_z;
      e["sidak_z"] = sidak_t(family_alpha, std::max(1, tested), static_cast<double>(surfaces - 1));
      e["pass"] = max_abs_z < e["sidak_z"].get<double>();
    }
  };
  return t;
}

namespace {

// The bins: measured D_v, Smith's from the facets and the nominal model's (`model`: its bin
// probabilities, empty without one) with the z-score under the model's binomial variance.
Json vndf_bins_json(const VndfResult& r, const Microsurface& s, const std::vector<double>& model) {
  Json bins = Json::array();
  for (int b = 0; b < r.binning.size(); ++b) {
    const int it = b / r.binning.n_phi(), ip = b % r.binning.n_phi();
    Json jb;
    jb["theta_m_range_deg"] = {deg(r.binning.theta_lo(it)), deg(r.binning.theta_hi(it))};
    jb["phi_m_range_deg"] = {deg(r.binning.phi_lo(ip)), deg(r.binning.phi_hi(ip))};
    const Estimate d = r.dv(b);
    jb["dv"] = d.mean;
    jb["dv_stderr"] = d.stderr_;
    jb["hits"] = r.bin_hits[b];
    jb["dv_smith_numeric"] = r.dv_smith_numeric(b);
    if (s.nominal) {
      const double w = r.binning.solid_angle(b);
      const double dm = model[b] / w;
      jb["dv_model"] = dm;
      // z under the model's own binomial variance (defined also where no ray landed).
      const double se = std::sqrt(model[b] * (1 - model[b]) / r.hits) / w;
      jb["z"] = z_json(d.mean, dm, se);
      jb["rel_dev"] = rel_dev_json(d.mean, dm);
    } else {
      jb["dv_model"] = nullptr;
      jb["z"] = nullptr;
      jb["rel_dev"] = nullptr;
    }
    bins.push_back(jb);
  }
  return bins;
}

}  // namespace

Json& add_row(Table& t, const VndfResult& r, const Microsurface& s, const VndfOptions& o,
              const std::optional<SamplerTest>& sampler) {
  t.rows.push_back(Json::object());
  Json& row = t.rows.back();
  row["theta_deg"] = deg(theta_of(r.v));
  row["phi_deg"] = deg(phi_of(r.v));
  row["rays"] = r.rays;
  // i.i.d. origins: multinomial counts, the binomial error is exact (no replicates needed).
  row["replicates"] = nullptr;
  row["hits"] = r.hits;
  row["hits_below_horizon"] = r.hits_below;
  row["visible_area_ratio"] = r.macro_area > 0 ? static_cast<double>(r.hits) / r.rays *
                                                     r.window_area_perp / (r.v.z() * r.macro_area)
                                               : 0.0;
  std::vector<double> model;
  auto put_gof = [&](const std::string& suffix, const GofResult& g) {
    row["chi2" + suffix] = g.chi2;
    row["dof" + suffix] = g.dof;
    row["p_value" + suffix] = g.p_value;
    row["max_abs_z" + suffix] = g.max_abs_z;
    row["bins_tested" + suffix] = g.bins_tested;
    row["sidak_z" + suffix] = g.sidak_z;
    row["pass" + suffix] = g.pass();
  };
  if (s.nominal) {
    model = bin_integrals(r.binning, [&](const Vec3& m) { return s.nominal->D_visible(r.v, m); });
    put_gof("", histogram_gof(r.bin_hits, r.hits, model, o.family_alpha));
    // Total variation distance between the measured and nominal bin probabilities.
    double tv = 0;
    for (int b = 0; b < r.binning.size(); ++b)
      tv += std::abs(static_cast<double>(r.bin_hits[b]) / r.hits - model[b]);
    row["tv_distance"] = 0.5 * tv;
  } else {
    for (const char* k : {"chi2", "dof", "p_value", "max_abs_z", "bins_tested", "sidak_z", "pass",
                          "tv_distance"})
      row[k] = nullptr;
  }
  put_gof("_smith_numeric",
          histogram_gof(r.bin_hits, r.hits, r.smith_numeric_probabilities(), o.family_alpha));
  if (sampler) {
    row["sampler_samples"] = sampler->n;
    row["sampler_chi2"] = sampler->gof.chi2;
    row["sampler_dof"] = sampler->gof.dof;
    row["sampler_p_value"] = sampler->gof.p_value;
    row["sampler_max_abs_z"] = sampler->gof.max_abs_z;
    row["sampler_pass"] = sampler->gof.pass();
  }
  // A finite object is missed by the rays of its window that pass beside it (they leave the
  // slab downward): those are misses, not lost rays.
  const std::uint64_t gone = r.counters.lost_below + r.counters.unresolved;
  const bool finite = s.macro().finite_object();
  row["lost_rays"] = !finite ? gone : r.counters.unresolved;
  row["missed_rays"] = !finite ? 0 : r.counters.lost_below;
  if (s.macro().region) {  // a measured window: rays that met its side walls (Tracer rule)
    row["side_exits"] = r.counters.side_exits;
    row["side_entries"] = r.counters.side_entries;
  }
  row["backface_hits"] = r.counters.backface_hits;
  row["trace_counters"] = fields_json(r.counters);  // every counter, as TraceCounters declares them
  row["seconds"] = r.seconds;
  row["bins"] = vndf_bins_json(r, s, model);
  return row;
}

}  // namespace microsim
