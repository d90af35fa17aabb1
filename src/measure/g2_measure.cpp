#include "microsim/measure/g2_measure.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <chrono>

#include "microsim/measure/sampling.hpp"

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

DirectionBinning g2_normal_binning(const G2Options& o) {
  return DirectionBinning(o.normal_theta_bins, o.normal_phi_bins, kPi);
}

G2Result measure_g2(const Tracer& tracer, const Vec3& o_in, const Vec3& i_in, const G2Options& opt,
                    const FacetTable* table) {
  const Microsurface& s = tracer.surface();
  if (!(o_in.z() > 0)) throw UsageError("--theta-o must be in [0, 90) degrees");
  if (!(i_in.z() > 0)) throw UsageError("--theta-i must be in [0, 90) degrees");
  if (opt.rays == 0) throw UsageError("--rays must be positive");
  auto t0 = std::chrono::steady_clock::now();
  G2Result r;
  r.o = o_in.normalized();
  r.i = i_in.normalized();
  r.macro_area = s.macro().area;
  r.binning = g2_normal_binning(opt);
  const int nbins = r.binning.size();
  r.bins.assign(nbins, G2NormalBin{});
  const Vec3 o = r.o, i = r.i;

  FacetTable own;
  if (!table) {
    own = build_facet_table(s, r.binning);
    table = &own;
  }
  const FacetTable& ft = *table;
  const std::size_t nf = s.num_facets();
  if (ft.area.size() != nf) throw RuntimeFailure("facet table does not match the surface");

  // Exact facet sums. Per bin: area, area facing both, area-weighted normal (3), V-cavity sum;
  // then the back-facing projected areas toward o and toward i (Smith Lambda from facets).
  std::vector<double> cdf(nf);
  using Sums = std::vector<double>;
  const std::size_t width = 6 * static_cast<std::size_t>(nbins) + 2;
  Sums sums = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, nf, std::max<std::size_t>(1 << 15, nf / 64)), Sums{},
      [&](const tbb::blocked_range<std::size_t>& range, Sums acc) {
        if (acc.empty()) acc.assign(width, 0.0);
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          const double a = ft.area[k];
          const Vec3 m = ft.normal[k].cast<double>();
          const double om = o.dot(m), im = i.dot(m);
          const bool front = om > 0 && im > 0;
          cdf[k] = front ? a : 0.0;
          double* bin = acc.data() + 6 * static_cast<std::size_t>(ft.bin[k]);
          bin[0] += a;
          if (front) {
            bin[1] += a;
            bin[2] += a * m.x();
            bin[3] += a * m.y();
            bin[4] += a * m.z();
            bin[5] += a * models::vcavity_G2(o, i, m);
          }
          acc[width - 2] += a * std::max(0.0, -om);
          acc[width - 1] += a * std::max(0.0, -im);
        }
        return acc;
      },
      [](Sums a, const Sums& b) {
        if (a.empty()) return b;
        for (std::size_t k = 0; k < b.size(); ++k) a[k] += b[k];
        return a;
      });
  if (sums.empty()) sums.assign(width, 0.0);
  double vcav_total = 0;
  for (int b = 0; b < nbins; ++b) {
    const double* bin = sums.data() + 6 * static_cast<std::size_t>(b);
    G2NormalBin& nb = r.bins[b];
    nb.area = bin[0];
    nb.front_area = bin[1];
    nb.mean_normal = Vec3(bin[2], bin[3], bin[4]);
    if (nb.mean_normal.norm() > 0) nb.mean_normal.normalize();
    nb.vcavity_sum = bin[5];
    r.total_area += bin[0];
    vcav_total += bin[5];
  }
  // Lambda(v) = sum_f A_f max(0, -v.m_f) / ((v.n) A)   (DESIGN.md, 001 App. A)
  const Vec3 n = s.macro().normal;
  r.lambda_o = sums[width - 2] / (o.dot(n) * s.macro().area);
  r.lambda_i = sums[width - 1] / (i.dot(n) * s.macro().area);
  for (std::size_t k = 1; k < nf; ++k) cdf[k] += cdf[k - 1];  // sequential: deterministic
  r.front_area = nf ? cdf[nf - 1] : 0.0;
  if (!(r.front_area > 0)) throw RuntimeFailure("no facet faces both directions");
  r.vcavity = vcav_total / r.front_area;

  // Random stream from the unordered pair {o, i}: swapping the directions traces the same points.
  const std::uint64_t ko = direction_stream_key(o), ki = direction_stream_key(i);
  const std::uint64_t stream = 0xC2000000ull ^ mix64(std::min(ko, ki) ^ mix64(std::max(ko, ki)));
  const Strata strata(opt.rays);
  const std::uint64_t total = strata.total();
  r.samples = total;
  const std::uint64_t nchunks = (total + kChunk - 1) / kChunk;
  std::vector<Tally> parts(nchunks, Tally(nbins));
  std::atomic<std::uint64_t> done{0};
  const double front = r.front_area;
  // The progress callback runs on the calling thread only: between two halves of the work.
  auto run = [&](std::uint64_t c0, std::uint64_t c1) {
    tbb::parallel_for(c0, c1, [&](std::uint64_t c) {
      Tally& t = parts[c];
      const std::uint64_t end = std::min(total, (c + 1) * kChunk);
      for (std::uint64_t j = c * kChunk; j < end; ++j) {
        CounterRng rng(opt.seed, stream, j);
        // Strata along the area CDF (facet order is spatially coherent).
        const double u = (static_cast<double>(j) + rng.uniform()) / total * front;
        std::size_t k = std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin();
        k = std::min(k, nf - 1);
        while (k > 0 && cdf[k] == cdf[k - 1]) --k;  // never land on a zero-weight facet
        const Triangle f = s.facet(k);
        const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
        const Vec3 p = f.point(r1 * (1 - r2), r1 * r2);
        const SourcePlane plane = SourcePlane::of(f);
        const int b = ft.bin[k];
        const bool vo = !tracer.occluded(p, o, &plane, t.counters);
        const bool vi = !tracer.occluded(p, i, &plane, t.counters);
        ++t.samples[b];
        t.vis_o[b] += vo;
        t.vis_i[b] += vi;
        t.vis_both[b] += vo && vi;
      }
      done += end - c * kChunk;
    });
    if (opt.progress) opt.progress(static_cast<double>(done.load()) / total);
  };
  run(0, nchunks / 2);
  run(nchunks / 2, nchunks);
  for (const Tally& t : parts) {  // merged in chunk order: identical for any thread count
    for (int b = 0; b < nbins; ++b) {
      r.bins[b].samples += t.samples[b];
      r.bins[b].visible_o += t.vis_o[b];
      r.bins[b].visible_i += t.vis_i[b];
      r.bins[b].visible_both += t.vis_both[b];
    }
    r.counters += t.counters;
  }
  for (const G2NormalBin& nb : r.bins) {
    r.visible_o += nb.visible_o;
    r.visible_i += nb.visible_i;
    r.visible_both += nb.visible_both;
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

Json g2_row_json(const G2Result& r, const Microsurface& s) {
  Json row;
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
        g2.stderr_ > 0 ? (g2.mean - value) / g2.stderr_ : 0.0;
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
  row["area_samples"] = r.samples;
  row["occlusion_rays"] = r.counters.rays;
  row["lost_rays"] = r.counters.lost_below + r.counters.unresolved;
  row["backface_hits"] = r.counters.backface_hits;
  row["seconds"] = r.seconds;
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
    if (nb.front_area > 0 && nb.samples > 0) {
      const Estimate e2 = r.bin_g2(b), eo = r.bin_g1_o(b), ei = r.bin_g1_i(b);
      jb["g2"] = e2.mean;
      jb["g2_stderr"] = e2.stderr_;
      jb["g1_o"] = eo.mean;
      jb["g1_o_stderr"] = eo.stderr_;
      jb["g1_i"] = ei.mean;
      jb["g1_i_stderr"] = ei.stderr_;
      jb["vcavity"] = nb.vcavity_sum / nb.front_area;
      jb["samples"] = nb.samples;
    } else {  // no facet of the bin faces both directions: G2 = 0 by definition
      for (const char* k : {"g2", "g2_stderr", "g1_o", "g1_o_stderr", "g1_i", "g1_i_stderr",
                            "vcavity"})
        jb[k] = 0.0;
      jb["samples"] = nb.samples;
    }
    bins.push_back(jb);
  }
  row["bins"] = bins;
  return row;
}

}  // namespace microsim
