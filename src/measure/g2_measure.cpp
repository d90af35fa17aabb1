#include "microsim/measure/g2_measure.hpp"
#include "microsim/io/checks.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>

#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/measure/stats.hpp"
#include "estimator_steps.hpp"

namespace microsim {

namespace {

struct Tally {
  std::vector<std::uint64_t> samples, vis_o, vis_i, vis_both;
  TraceCounters counters;
  explicit Tally(int nbins = 0) : samples(nbins), vis_o(nbins), vis_i(nbins), vis_both(nbins) {}
};

constexpr std::uint64_t kChunk = 1 << 13;

}  // namespace

models::G2Forms G2Result::smith_numeric() const {
  return models::g2_forms_from_lambda(lambda_o, lambda_i, models::azimuth_difference(o, i));
}

namespace {
// Fields of G2Forms as an array (for the delta method).
std::array<double, 4> as_array(const models::G2Forms& f) {
  return {f.separable, f.height_correlated, f.direction_correlated, f.height_direction_correlated};
}
models::G2Forms from_array(const std::array<double, 4>& a) {
  return {a[0], a[1], a[2], a[3]};
}
}  // namespace

Estimate G2Result::g2() const {
  std::vector<std::uint64_t> x(replicates, 0);
  for (const G2NormalBin& nb : bins)
    for (int q = 0; q < replicates; ++q) x[q] += nb.visible_both_r[q];
  return replicate_mean(x, static_cast<double>(replicates) / samples);
}
Estimate G2Result::g1_o() const {
  std::vector<std::uint64_t> x(replicates, 0);
  for (const G2NormalBin& nb : bins)
    for (int q = 0; q < replicates; ++q) x[q] += nb.visible_o_r[q];
  return replicate_mean(x, static_cast<double>(replicates) / samples);
}
Estimate G2Result::g1_i() const {
  std::vector<std::uint64_t> x(replicates, 0);
  for (const G2NormalBin& nb : bins)
    for (int q = 0; q < replicates; ++q) x[q] += nb.visible_i_r[q];
  return replicate_mean(x, static_cast<double>(replicates) / samples);
}
Estimate G2Result::bin_g2(int b) const { return replicate_ratio(bins[b].visible_both_r, bins[b].samples_r); }
Estimate G2Result::bin_g1_o(int b) const { return replicate_ratio(bins[b].visible_o_r, bins[b].samples_r); }
Estimate G2Result::bin_g1_i(int b) const { return replicate_ratio(bins[b].visible_i_r, bins[b].samples_r); }

namespace {
// A bin's counts: samples, visible from o, from i, from both.
struct BinCounts {
  double n = 0, o = 0, i = 0, both = 0;
};
BinCounts counts_without(const G2NormalBin& nb, int rep) {  // rep < 0: all replicates
  BinCounts c{static_cast<double>(nb.samples), static_cast<double>(nb.visible_o),
              static_cast<double>(nb.visible_i), static_cast<double>(nb.visible_both)};
  if (rep >= 0) {
    c.n -= nb.samples_r[rep];
    c.o -= nb.visible_o_r[rep];
    c.i -= nb.visible_i_r[rep];
    c.both -= nb.visible_both_r[rep];
  }
  return c;
}
// The four forms from the bin's g1_o, g1_i, and g2 minus each.
void forms_and_diff(const BinCounts& c, double phi, std::array<double, 4>& value,
                    std::array<double, 4>& diff) {
  value = as_array(models::g2_forms_from_g1(c.o / c.n, c.i / c.n, phi));
  for (int k = 0; k < 4; ++k) diff[k] = c.both / c.n - value[k];
}
}  // namespace

G2Result::FormsFromG1 G2Result::bin_forms_from_g1(int b) const {
  FormsFromG1 out;
  const G2NormalBin& nb = bins[b];
  if (nb.samples == 0) return out;
  const double phi = models::azimuth_difference(o, i);
  std::array<double, 4> value, diff, v, d;
  forms_and_diff(counts_without(nb, -1), phi, value, diff);
  std::array<std::vector<double>, 4> without;
  for (int q = 0; q < replicates; ++q) {
    const BinCounts c = counts_without(nb, q);
    if (!(c.n > 0)) continue;  // the bin's only samples were in replicate q
    forms_and_diff(c, phi, v, d);
    for (int k = 0; k < 4; ++k) without[k].push_back(d[k]);
  }
  std::array<double, 4> se{};
  for (int k = 0; k < 4; ++k) se[k] = jackknife(diff[k], without[k]).stderr_;
  out.value = from_array(value);
  out.diff = from_array(diff);
  out.diff_stderr = from_array(se);
  return out;
}

G2Result::FormsFromG1 G2Result::forms_from_g1() const {
  const double phi = models::azimuth_difference(o, i);
  // sum_b w_b (value_b, diff_b) over the bins with samples, without replicate `rep` (< 0: none).
  auto average = [&](int rep, std::array<double, 4>& value, std::array<double, 4>& diff) {
    value = {};
    diff = {};
    std::array<double, 4> v, d;
    for (int b = 0; b < binning.size(); ++b) {
      if (bins[b].weight <= 0 || bins[b].samples == 0) continue;
      const BinCounts c = counts_without(bins[b], rep);
      if (!(c.n > 0)) continue;
      forms_and_diff(c, phi, v, d);
      const double w = bins[b].weight / weight;
      for (int k = 0; k < 4; ++k) {
        value[k] += w * v[k];
        diff[k] += w * d[k];
      }
    }
  };
  std::array<double, 4> value, diff, v, d;
  average(-1, value, diff);
  std::array<std::vector<double>, 4> without;
  for (int q = 0; q < replicates; ++q) {
    average(q, v, d);
    for (int k = 0; k < 4; ++k) without[k].push_back(d[k]);
  }
  std::array<double, 4> se{};
  for (int k = 0; k < 4; ++k) se[k] = jackknife(diff[k], without[k]).stderr_;
  FormsFromG1 out;
  out.value = from_array(value);
  out.diff = from_array(diff);
  out.diff_stderr = from_array(se);
  return out;
}

DirectionBinning g2_normal_binning(const G2Options& o) {
  return DirectionBinning(o.normal_theta_bins, o.normal_phi_bins, kPi);
}

namespace {

// The exact facet sums of r.bins at (r.o, r.i), r.total_area, r.front_area, r.lambda_o and
// r.lambda_i; returns the V-cavity sum over every bin.
double sum_g2_facets_per_bin(G2Result& r, const FacetTable& ft, const Microsurface& s) {
  const int nbins = r.binning.size();
  const Vec3 o = r.o, i = r.i;
  // Exact facet sums. Per bin: area, area facing both, weight w_f, w-weighted normal (3),
  // V-cavity sum; then the back-facing projected areas toward o and toward i (Smith Lambda
  // from facets). The CDF of w_f places the samples.
  using Sums = std::vector<double>;
  constexpr std::size_t kW = 7;
  const std::size_t width = kW * static_cast<std::size_t>(nbins) + 2;
  // w_f: symmetric in (o, i); A_f (v.m) at o = i = v.
  const auto weight_of = [&](const Vec3& m, double a) {
    const double om = o.dot(m), im = i.dot(m);
    return om > 0 && im > 0 ? 0.5 * a * (om + im) : 0.0;
  };
  Sums sums = sum_over_facets(s.num_facets(), width, [&](std::size_t k, double* acc) {
    Vec3 m;
    double a;
    ft.normal_area(k, m, a);
    const double om = o.dot(m), im = i.dot(m);
    const bool front = om > 0 && im > 0;
    const double wf = weight_of(m, a);
    double* bin = acc + kW * static_cast<std::size_t>(ft.bin(k));
    bin[0] += a;
    if (front) {
      bin[1] += a;
      bin[2] += wf;
      bin[3] += wf * m.x();
      bin[4] += wf * m.y();
      bin[5] += wf * m.z();
      bin[6] += wf * models::vcavity_G2(o, i, m);
    }
    acc[width - 2] += a * std::max(0.0, -om);
    acc[width - 1] += a * std::max(0.0, -im);
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

// Chunk tallies of replicates r0, r0 + 1, ... (chunks_per_replicate nc each) into the
// per-replicate counts of r.bins and r.counters.
void add_g2_parts(G2Result& r, const std::vector<Tally>& parts, int r0, std::uint64_t nc) {
  for (std::size_t c = 0; c < parts.size(); ++c) {
    const int rep = r0 + static_cast<int>(c / nc);
    for (int b = 0; b < r.binning.size(); ++b) {
      G2NormalBin& nb = r.bins[b];
      nb.samples_r[rep] += parts[c].samples[b];
      nb.visible_o_r[rep] += parts[c].vis_o[b];
      nb.visible_i_r[rep] += parts[c].vis_i[b];
      nb.visible_both_r[rep] += parts[c].vis_both[b];
    }
    r.counters += parts[c].counters;
  }
}

}  // namespace

G2Result measure_g2(const Tracer& tracer, const Vec3& o_in, const Vec3& i_in, const G2Options& opt,
                    const FacetTable* table) {
  const Microsurface& s = tracer.surface();
  G2Result r = start_g2(o_in, i_in, opt, s.macro().area);
  auto t0 = std::chrono::steady_clock::now();
  const int nbins = r.binning.size();
  const Vec3 o = r.o, i = r.i;

  FacetTable own;
  const FacetTable& ft = facet_table_for(s, r.binning, table, own);
  const std::size_t nf = s.num_facets();
  const double vcav_total = sum_g2_facets_per_bin(r, ft, s);
  const auto weight = [&](std::size_t k) {  // w_f from 2 A_f m_f, without a square root
    const Vec3 c = ft.cross(k);
    const double oc = o.dot(c), ic = i.dot(c);
    return oc > 0 && ic > 0 ? 0.25 * (oc + ic) : 0.0;
  };
  const BlockFacetSampler sampler(nf, weight);  // places the samples
  r.weight = sampler.total();
  if (!(r.weight > 0)) throw RuntimeFailure("no facet faces both directions");
  r.vcavity = vcav_total / r.weight;

  const std::uint64_t stream = pair_stream(o, i, 0xC2000000ull);
  const ReplicatePlan plan = plan_g2(r, opt);
  const int R = plan.replicates;
  const std::uint64_t n_rep = plan.per_replicate();
  std::atomic<std::uint64_t> done{0};
  const double front = r.weight;
  // Per replicate a stratified pass along the CDF of w_f (facet order is spatially coherent).
  // The progress callback runs on the calling thread only: between two halves of the work.
  auto body = [&](int rep, std::uint64_t j, Tally& t) {
    CounterRng rng(opt.seed, ReplicatePlan::stream(stream, rep), j);
    const double u = (static_cast<double>(j) + rng.uniform()) / n_rep * front;
    const std::size_t k = sampler.draw(u, weight);
    const Triangle f = s.facet(k);
    const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
    const Vec3 p = f.point(r1 * (1 - r2), r1 * r2);
    const SourcePlane plane = SourcePlane::of(f);
    const int b = ft.bin(k);
    // A facet pressed against an opposite-facing twin (touching walls, [GeomBSDF24, Fig. 6]) is hidden
    // from every direction, as in measure_g1: its occlusion rays would start inside the
    // neighbour and skip the twin at distance zero.
    const bool buried = ft.buried(k);
    const bool vo = !buried && !tracer.occluded(p, o, &plane, t.counters);
    const bool vi = o == i ? vo : !buried && !tracer.occluded(p, i, &plane, t.counters);
    ++t.samples[b];
    t.vis_o[b] += vo;
    t.vis_i[b] += vi;
    t.vis_both[b] += vo && vi;
    if ((j + 1) % kChunk == 0 || j + 1 == n_rep) done += (j % kChunk) + 1;
  };
  for (int b = 0; b < nbins; ++b) {
    G2NormalBin& nb = r.bins[b];
    for (auto* v : {&nb.samples_r, &nb.visible_o_r, &nb.visible_i_r, &nb.visible_both_r})
      v->assign(R, 0);
  }
  const std::uint64_t nc = chunks_per_replicate(n_rep, kChunk);
  // Two halves of the replicates (progress between them); chunk tallies merged per replicate
  // in chunk order: identical for any thread count.
  const UnitRange reps = share_of(opt.split, static_cast<std::uint64_t>(R));
  const int share0 = static_cast<int>(reps.first), share1 = static_cast<int>(reps.end);
  const int halves[3] = {share0, share0 + (share1 - share0) / 2, share1};
  // The larger half's chunk tallies are held at once: refused before the work when they would
  // not fit in memory (rather than ending in std::bad_alloc).
  require_memory(static_cast<double>(share1 - halves[1]) * nc * (sizeof(Tally) + 4.0 * nbins * sizeof(std::uint64_t)),
                 "{rays} " + std::to_string(opt.rays) + " (tallies of " + std::to_string(nc) +
                     " chunks per replicate, " + std::to_string(nbins) + " normal bins)");
  for (int h = 0; h < 2; ++h) {
    const int r0 = halves[h], r1 = halves[h + 1];
    if (r1 <= r0) continue;
    std::vector<Tally> parts = run_replicate_chunks<Tally>(
        r1 - r0, n_rep, kChunk, [&] { return Tally(nbins); },
        [&](int rep, std::uint64_t j, Tally& t) { body(r0 + rep, j, t); });
    add_g2_parts(r, parts, r0, nc);
    if (opt.progress) opt.progress(static_cast<double>(done.load()) / (n_rep * (share1 - share0)));
  }
  finish_g2(r, opt, reps);
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
  const auto fv = as_array(fg.value), fd = as_array(fg.diff), fs = as_array(fg.diff_stderr);
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
