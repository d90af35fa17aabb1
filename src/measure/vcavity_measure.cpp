#include "microsim/measure/vcavity_measure.hpp"
#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "estimator_steps.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <string>

#include "microsim/models/vgroove_multiple.hpp"
#include "microsim/surface/generators.hpp"

namespace microsim {

namespace {

// Per view, replicate and normal bin: ray-cast hits, area samples and visible samples.
// Integer sums, added atomically groove by groove: exact, so identical for any thread count.
struct Counts {
  std::atomic<std::uint64_t> hits{0}, samples{0}, visible{0};
  // The counts exchanged per replicate, in measure_g1's order (its tally's for_each_field).
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f("hits", &Counts::hits);
    f("samples", &Counts::samples);
    f("visible", &Counts::visible);
  }
};

std::uint64_t stream_of(std::uint64_t base, std::size_t view) { return base + 7919 * view; }

}  // namespace

std::vector<G1Result> measure_vcavity_g1(const Microsurface& s, const std::vector<Vec3>& views,
                                         const G1Options& o) {
  if (!is_vcavity(s) || s.num_facets() % 4 != 0)
    throw UsageError("measure_vcavity_g1: not a vcavity surface (generate vcavity)");
  if (o.rays == 0) throw ParameterError("{rays} must be positive");
  for (const Vec3& v : views)
    if (!(v.z() > 1e-12 * v.norm()))
      throw ParameterError("{theta} must be in [0, 90) degrees for a vcavity ensemble (its grooves are "
                           "heightfields)");
  auto t0 = std::chrono::steady_clock::now();
  const std::size_t K = s.num_facets() / 4, nv = views.size();
  const DirectionBinning binning = g1_normal_binning(o);
  const int nbins = binning.size();

  // The ensemble's facets: groove k side 1 = m_k (stored facets 4k, 4k+1), side 0 = m'_k.
  std::vector<Vec3> normal(2 * K);
  std::vector<double> area(2 * K);
  std::vector<int> bin(2 * K);
  for (std::size_t k = 0; k < K; ++k) {
    for (int side = 0; side < 2; ++side) {
      const std::size_t f = 4 * k + (side == 1 ? 0 : 2);
      Triangle a = s.facet(f), b = s.facet(f + 1);
      normal[2 * k + side] = a.normal();
      area[2 * k + side] = a.area() + b.area();
      bin[2 * k + side] = binning.bin_of(a.normal());
    }
  }

  std::vector<G1Result> results(nv);
  std::vector<std::vector<double>> cdfs(nv, std::vector<double>(2 * K));
  // Ray casting: every groove gets the same stratified rays per replicate; area sampling:
  // per replicate a stratified pass along the ensemble's projected-area CDF.
  // (At least one ray per groove and replicate: every replicate covers every groove.)
  const std::uint64_t groove_rays =
      std::max<std::uint64_t>((o.rays + K - 1) / K, static_cast<std::uint64_t>(std::max(0, o.replicates)));
  const ReplicatePlan groove_plan(groove_rays, o.replicates);
  const int R = groove_plan.replicates;
  const ReplicatePlan sample_plan(std::max<std::uint64_t>(o.rays, R), R);
  const std::uint64_t per_groove = groove_plan.per_replicate();  // per replicate
  const std::uint64_t n_samples = sample_plan.per_replicate();
  for (std::size_t iv = 0; iv < nv; ++iv) {
    G1Result& r = results[iv];
    r.v = views[iv].normalized();
    r.theta = theta_of(r.v);
    r.phi = phi_of(r.v);
    r.macro_area = s.macro().area;
    r.binning = binning;
    r.bins.assign(nbins, G1NormalBin{});
    double back = 0;
    std::vector<double>& cdf = cdfs[iv];
    for (std::size_t j = 0; j < 2 * K; ++j) {
      const double proj = area[j] * r.v.dot(normal[j]);
      G1NormalBin& nb = r.bins[bin[j]];
      const double front = std::max(0.0, proj);
      nb.area += area[j];
      nb.front_projected += front;
      nb.mean_normal += front * normal[j];
      if (front > 0) nb.vcavity_weighted += front * models::vcavity_G1(r.v, normal[j]);
      back += std::max(0.0, -proj);
      r.total_area += area[j];
      cdf[j] = (j ? cdf[j - 1] : 0.0) + front;
    }
    for (auto& nb : r.bins)
      if (nb.mean_normal.norm() > 0) nb.mean_normal.normalize();
    r.front_projected = cdf.back();
    r.lambda_numeric = back / (r.v.z() * r.macro_area);  // [Heitz14, App. A]
    r.window_area_perp = r.v.z() * r.macro_area;          // K unit tiles seen along v
    r.replicates = R;
    r.raycast_rays = per_groove * K * R;
    r.sample_rays = n_samples * sample_plan.replicates;
  }

  // Area sampling: the stratified samples of every replicate along the view's CDF, each groove
  // handling the contiguous run of each replicate's samples on its two sides.
  // Only the replicates of this process are traced (measure/shards.hpp).
  const UnitRange reps = share_of(o.split, static_cast<std::uint64_t>(R));
  std::vector<CdfSamples> sample_facet;
  for (std::size_t iv = 0; iv < nv; ++iv)
    sample_facet.emplace_back(cdfs[iv], o.seed, stream_of(0xC000, iv), n_samples, reps);
  std::vector<Counts> counts(nv * R * nbins);
  auto at = [&](std::size_t iv, int q, int b) -> Counts& {
    return counts[(iv * R + q) * nbins + b];
  };
  std::vector<TraceCounters> groove_counters(K * nv);
  tbb::parallel_for(std::size_t(0), K, [&](std::size_t k) {
    // Groove k in its own frame: x along d (the horizontal direction of m_k), y along the
    // ridge, one period [-1/2, 1/2] per tile; cell i = 1 (x in [0, 1/2]) has normal m_k.
    const Vec3 m = normal[2 * k + 1];
    const double mh = std::hypot(m.x(), m.y());
    const Vec3 d = mh > 0 ? Vec3(m.x() / mh, m.y() / mh, 0) : Vec3::UnitX();
    const Vec3 t = Vec3::UnitZ().cross(d);
    const float top = static_cast<float>(0.5 * mh / m.z());
    Microsurface groove = Microsurface::heightfield(2, 2, 1.0, 1.0, {0.0f, top, 0.0f, top});
    Tracer tracer(groove);
    const SourcePlane plane[2] = {SourcePlane::of(groove.facet(0)), SourcePlane::of(groove.facet(2))};
    for (std::size_t iv = 0; iv < nv; ++iv) {
      TraceCounters& tc = groove_counters[k * nv + iv];
      const Vec3 v = results[iv].v;
      const Vec3 vl(v.dot(d), v.dot(t), v.z());
      for (int q = static_cast<int>(reps.first); q < static_cast<int>(reps.end); ++q) {
        std::uint64_t hits[2] = {0, 0}, samples[2] = {0, 0}, visible[2] = {0, 0};
        // (a) stratified rays over the tile along -v.
        const std::uint64_t stream =
            ReplicatePlan::stream(stream_of(0xA000, iv) + (static_cast<std::uint64_t>(k) << 24), q);
        for (std::uint64_t i = 0; i < per_groove; ++i) {
          CounterRng rng(o.seed, stream, i);
          Vec2 ab = groove_plan.strata.point(i, rng);
          Vec3 org(ab.x() - 0.5, ab.y() - 0.5, tracer.z_top());
          TraceHit h = tracer.first_hit(org, -vl, nullptr, tc);
          if (h.hit && !h.backface) ++hits[(h.facet / 2) % 2];
        }
        // (b) this groove's share of the replicate's stratified area samples.
        sample_facet[iv].for_each(q, static_cast<std::uint32_t>(2 * k), static_cast<std::uint32_t>(2 * k + 2),
                                  [&](std::uint64_t i, std::uint32_t f) {
                                    const int side = static_cast<int>(f - 2 * k);
                                    CounterRng rng = sample_facet[iv].rng(q, i);
                                    const double x = (side == 1 ? 0.5 : -0.5) * rng.uniform();
                                    const double y = rng.uniform() - 0.5;
                                    const Vec3 p(x, y, top * (1 - 2 * std::abs(x)));
                                    ++samples[side];
                                    if (!tracer.occluded(p, vl, &plane[side], tc)) ++visible[side];
                                  });
        for (int side = 0; side < 2; ++side) {
          Counts& c = at(iv, q, bin[2 * k + side]);
          c.hits += hits[side];
          c.samples += samples[side];
          c.visible += visible[side];
        }
      }
    }
  });

  for (std::size_t iv = 0; iv < nv; ++iv)  // in groove order
    for (std::size_t k = 0; k < K; ++k) results[iv].counters += groove_counters[k * nv + iv];
  if (o.split)  // the other processes' replicates, view by view, in measure_g1's layout
    for (std::size_t iv = 0; iv < nv; ++iv) {
      const std::size_t nb = static_cast<std::size_t>(nbins);
      // Field k of bin b at k * nb + b, as measure_g1 packs its per-bin vectors.
      const auto each_count = [&](auto&& fn) {
        std::size_t k = 0;
        Counts::for_each_field([&](const char*, auto member) {
          for (int q = 0; q < R; ++q)
            for (int b = 0; b < nbins; ++b) fn(at(iv, q, b).*member, q, k * nb + b);
          ++k;
        });
      };
      std::size_t fields = 0;
      Counts::for_each_field([&](const char*, auto) { ++fields; });
      Tallies t("g1", R, reps, fields * nb, 0, kCounterValues, 0);
      each_count([&](const std::atomic<std::uint64_t>& c, int q, std::size_t pos) { t.count_row(q)[pos] = c; });
      put_counters(results[iv].counters, t.tail_counts.data());
      o.split->exchange(t);
      each_count([&](std::atomic<std::uint64_t>& c, int q, std::size_t pos) { c = t.count_row(q)[pos]; });
      results[iv].counters = get_counters(t.tail_counts.data());
    }

  // Per-replicate counts into the results.
  for (std::size_t iv = 0; iv < nv; ++iv) {
    G1Result& r = results[iv];
    r.raycast_hits_r.assign(R, 0);
    r.sample_visible_r.assign(R, 0);
    for (int b = 0; b < nbins; ++b) {
      G1NormalBin& nb = r.bins[b];
      nb.raycast_hits_r.assign(R, 0);
      nb.samples_r.assign(R, 0);
      nb.visible_r.assign(R, 0);
      for (int q = 0; q < R; ++q) {
        const Counts& c = at(iv, q, b);
        nb.raycast_hits_r[q] = c.hits;
        nb.samples_r[q] = c.samples;
        nb.visible_r[q] = c.visible;
        nb.raycast_hits += c.hits;
        nb.samples += c.samples;
        nb.visible += c.visible;
        r.raycast_hits_r[q] += c.hits;
        r.sample_visible_r[q] += c.visible;
      }
      r.raycast_hits += nb.raycast_hits;
      r.sample_visible += nb.visible;
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (auto& r : results) r.seconds = seconds / nv;
  if (o.progress) o.progress(1.0);
  return results;
}

namespace {

// The 2K facets of a vcavity ensemble: side 1 of groove k = m_k (stored facets 4k, 4k+1),
// side 0 = m'_k (4k+2, 4k+3); normals and areas from the stored strips.
struct GrooveSides {
  std::size_t K = 0;
  std::vector<Vec3> normal;
  std::vector<double> area;
};
GrooveSides groove_sides(const Microsurface& s, const char* what) {
  if (!is_vcavity(s) || s.num_facets() % 4 != 0)
    throw UsageError(std::string(what) + ": not a vcavity surface (generate vcavity)");
  GrooveSides g;
  g.K = s.num_facets() / 4;
  g.normal.resize(2 * g.K);
  g.area.resize(2 * g.K);
  for (std::size_t k = 0; k < g.K; ++k)
    for (int side = 0; side < 2; ++side) {
      const std::size_t f = 4 * k + (side == 1 ? 0 : 2);
      const Triangle a = s.facet(f), b = s.facet(f + 1);
      g.normal[2 * k + side] = a.normal();
      g.area[2 * k + side] = a.area() + b.area();
    }
  return g;
}

// Groove k traced on its own (as measure_vcavity_g1): x along d (the horizontal direction of
// m_k), y along the ridge, one period [-1/2, 1/2] per tile; cell i = 1 (x in [0, 1/2]) has
// normal m_k, and the surface there is z = top (1 - 2|x|).
struct GrooveTile {
  Vec3 d, t;
  float top;
  Microsurface surface;
  explicit GrooveTile(const Vec3& m)
      : d(std::hypot(m.x(), m.y()) > 0 ? Vec3(m.x(), m.y(), 0).normalized() : Vec3::UnitX()),
        t(Vec3::UnitZ().cross(d)),
        top(static_cast<float>(0.5 * std::hypot(m.x(), m.y()) / m.z())),
        surface(Microsurface::heightfield(2, 2, 1.0, 1.0, {0.0f, top, 0.0f, top})) {}
  Vec3 to_local(const Vec3& w) const { return Vec3(w.dot(d), w.dot(t), w.z()); }
  // The point of side `side` at (u, w) in [0, 1)^2, uniform over the side's area.
  Vec3 point(int side, double u, double w) const {
    const double x = (side == 1 ? 0.5 : -0.5) * u;
    return Vec3(x, w - 0.5, top * (1 - 2 * std::abs(x)));
  }
};

}  // namespace

G2Result measure_vcavity_g2(const Microsurface& s, const Vec3& o_in, const Vec3& i_in, const G2Options& opt) {
  G2Result r = start_g2(o_in, i_in, opt, s.macro().area);
  const GrooveSides g = groove_sides(s, "measure_vcavity_g2");
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t K = g.K;
  const Vec3 o = r.o, i = r.i;
  const int nbins = r.binning.size();

  // Exact sums over the 2K facets (the weights and models of measure_g2) and the CDF of w_f.
  std::vector<int> bin(2 * K);
  std::vector<double> cdf(2 * K);
  double back_o = 0, back_i = 0, vcav_total = 0;
  for (std::size_t j = 0; j < 2 * K; ++j) {
    const Vec3& m = g.normal[j];
    const double a = g.area[j], om = o.dot(m), im = i.dot(m);
    bin[j] = r.binning.bin_of(m);
    G2NormalBin& nb = r.bins[bin[j]];
    const bool front = om > 0 && im > 0;
    const double w = front ? 0.5 * a * (om + im) : 0.0;
    nb.area += a;
    r.total_area += a;
    if (front) {
      nb.front_area += a;
      nb.weight += w;
      nb.mean_normal += w * m;
      const double v2 = w * models::vcavity_G2(o, i, m);  // [Heitz14, eq. 24 and Sec. 6]
      nb.vcavity_sum += v2;
      vcav_total += v2;
      r.front_area += a;
    }
    back_o += a * std::max(0.0, -om);
    back_i += a * std::max(0.0, -im);
    cdf[j] = (j ? cdf[j - 1] : 0.0) + w;
  }
  for (auto& nb : r.bins)
    if (nb.mean_normal.norm() > 0) nb.mean_normal.normalize();
  r.lambda_o = back_o / (o.z() * r.macro_area);  // [Heitz14, App. A]
  r.lambda_i = back_i / (i.z() * r.macro_area);
  r.weight = cdf.back();
  if (!(r.weight > 0)) throw RuntimeFailure("no facet faces both directions");
  r.vcavity = vcav_total / r.weight;

  // Stratified samples along the CDF per replicate (this process's replicates only), each
  // groove handling the contiguous run of each replicate's samples on its two sides.
  const ReplicatePlan plan = plan_g2(r, opt);
  const int R = plan.replicates;
  const UnitRange reps = share_of(opt.split, static_cast<std::uint64_t>(R));
  const CdfSamples samples(cdf, opt.seed, pair_stream(o, i, 0xC3000000ull), plan.per_replicate(), reps);

  struct G2Counts {
    std::atomic<std::uint64_t> samples{0}, vis_o{0}, vis_i{0}, vis_both{0};
  };
  std::vector<G2Counts> counts(static_cast<std::size_t>(R) * nbins);
  std::vector<TraceCounters> groove_counters(K);
  tbb::parallel_for(std::size_t(0), K, [&](std::size_t k) {
    const GrooveTile tile(g.normal[2 * k + 1]);
    Tracer tracer(tile.surface);
    const SourcePlane plane[2] = {SourcePlane::of(tile.surface.facet(0)), SourcePlane::of(tile.surface.facet(2))};
    const Vec3 ol = tile.to_local(o), il = tile.to_local(i);
    TraceCounters& tc = groove_counters[k];
    for (int q = static_cast<int>(reps.first); q < static_cast<int>(reps.end); ++q) {
      std::uint64_t n[2] = {0, 0}, vo[2] = {0, 0}, vi[2] = {0, 0}, vb[2] = {0, 0};
      samples.for_each(q, static_cast<std::uint32_t>(2 * k), static_cast<std::uint32_t>(2 * k + 2),
                       [&](std::uint64_t j, std::uint32_t f) {
                         const int side = static_cast<int>(f - 2 * k);
                         CounterRng rng = samples.rng(q, j);
                         const double u = rng.uniform();
                         const double w = rng.uniform();
                         const Vec3 p = tile.point(side, u, w);
                         const bool see_o = !tracer.occluded(p, ol, &plane[side], tc);
                         const bool see_i = o == i ? see_o : !tracer.occluded(p, il, &plane[side], tc);
                         ++n[side];
                         vo[side] += see_o;
                         vi[side] += see_i;
                         vb[side] += see_o && see_i;
                       });
      for (int side = 0; side < 2; ++side) {
        G2Counts& c = counts[static_cast<std::size_t>(q) * nbins + bin[2 * k + side]];
        c.samples += n[side];
        c.vis_o += vo[side];
        c.vis_i += vi[side];
        c.vis_both += vb[side];
      }
    }
  });
  for (int b = 0; b < nbins; ++b) {
    G2NormalBin& nb = r.bins[b];
    for (auto* x : {&nb.samples_r, &nb.visible_o_r, &nb.visible_i_r, &nb.visible_both_r}) x->assign(R, 0);
    for (int q = 0; q < R; ++q) {
      const G2Counts& c = counts[static_cast<std::size_t>(q) * nbins + b];
      nb.samples_r[q] = c.samples;
      nb.visible_o_r[q] = c.vis_o;
      nb.visible_i_r[q] = c.vis_i;
      nb.visible_both_r[q] = c.vis_both;
    }
  }
  for (std::size_t k = 0; k < K; ++k) r.counters += groove_counters[k];  // in groove order
  finish_g2(r, opt, reps);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (opt.progress) opt.progress(1.0);
  return r;
}

VndfResult measure_vcavity_vndf(const Microsurface& s, const Vec3& v_in, const VndfOptions& o) {
  VndfResult r = start_vndf(v_in, o, s.macro().area);
  const GrooveSides g = groove_sides(s, "measure_vcavity_vndf");
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t K = g.K;
  const Vec3 v = r.v;
  const int nbins = r.binning.size();
  std::vector<int> bin(2 * K);
  r.front_projected.assign(nbins, 0.0);
  for (std::size_t j = 0; j < 2 * K; ++j) {
    bin[j] = r.binning.bin_of(g.normal[j]);
    const double proj = std::max(0.0, g.area[j] * v.dot(g.normal[j]));
    if (bin[j] >= 0) r.front_projected[bin[j]] += proj;
    r.front_projected_total += proj;
  }
  if (!(r.front_projected_total > 0)) throw RuntimeFailure("no facet faces the direction");
  r.window_area_perp = v.z() * r.macro_area;  // K unit tiles seen along v
  // Ray j: groove, then origin on its tile, all from its own counter (i.i.d. rays); this
  // process's rays are bucketed by groove (counting sort, in ray order) so that each groove's
  // scene is built once.
  const UnitRange share = share_of(o.split, r.rays);
  const std::uint64_t stream = 0xD100 + direction_stream_key(v);
  std::vector<std::uint32_t> groove_of(share.size());
  tbb::parallel_for(std::uint64_t(0), share.size(), [&](std::uint64_t n) {
    CounterRng rng(o.seed, stream, share.first + n);
    groove_of[n] = static_cast<std::uint32_t>(std::min<std::uint64_t>(K - 1, static_cast<std::uint64_t>(rng.uniform() * K)));
  });
  std::vector<std::uint64_t> start(K + 1, 0);
  for (std::uint32_t k : groove_of) ++start[k + 1];
  for (std::size_t k = 0; k < K; ++k) start[k + 1] += start[k];
  std::vector<std::uint64_t> order(share.size());
  {
    std::vector<std::uint64_t> next(start.begin(), start.end() - 1);
    for (std::uint64_t n = 0; n < share.size(); ++n) order[next[groove_of[n]]++] = share.first + n;
  }
  std::vector<std::atomic<std::uint64_t>> counts(static_cast<std::size_t>(nbins) + 1);
  std::vector<TraceCounters> groove_counters(K);
  tbb::parallel_for(std::size_t(0), K, [&](std::size_t k) {
    if (start[k] == start[k + 1]) return;
    const GrooveTile tile(g.normal[2 * k + 1]);
    Tracer tracer(tile.surface);
    const Vec3 vl = tile.to_local(v);
    std::uint64_t hits[2] = {0, 0};
    for (std::uint64_t n = start[k]; n < start[k + 1]; ++n) {
      CounterRng rng(o.seed, stream, order[n]);
      rng.uniform();  // the draw that chose the groove
      const double a = rng.uniform();
      const double b = rng.uniform();
      const TraceHit h = tracer.first_hit(Vec3(a - 0.5, b - 0.5, tracer.z_top()), -vl, nullptr, groove_counters[k]);
      if (h.hit && !h.backface) ++hits[(h.facet / 2) % 2];
    }
    for (int side = 0; side < 2; ++side) {
      const int b = bin[2 * k + side];
      counts[b >= 0 ? static_cast<std::size_t>(b) : static_cast<std::size_t>(nbins)] += hits[side];
    }
  });
  for (std::size_t k = 0; k < K; ++k) r.counters += groove_counters[k];  // in groove order
  finish_vndf(r, o, share, std::vector<std::uint64_t>(counts.begin(), counts.end()));
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (o.progress) o.progress(1.0);
  return r;
}

std::vector<double> vcavity_vndf_probabilities(const Microsurface& s, const Vec3& v_in,
                                               const DirectionBinning& binning) {
  const GrooveSides g = groove_sides(s, "vcavity_vndf_probabilities");
  const Vec3 v = v_in.normalized();
  std::vector<double> p(binning.size(), 0.0);
  double total = 0;
  for (std::size_t j = 0; j < 2 * g.K; ++j) {
    const Vec3& m = g.normal[j];
    // Visible projected area of the side: A (v.m)+ G1 ([GeomBSDF24, eq. 2], [Heitz14, eq. 24]).
    const double vis = g.area[j] * std::max(0.0, v.dot(m)) * models::vcavity_G1(v, m);
    const int b = binning.bin_of(m);
    if (b >= 0) p[b] += vis;
    total += vis;
  }
  for (double& x : p) x /= total;
  return p;
}

BsdfTally trace_vcavity_bsdf(const Microsurface& s, const BsdfOptions& o, const Vec3& wi,
                             const HemisphereMap& map, const InPlaneBins& plane, std::uint64_t stream) {
  if (!is_vcavity(s) || s.num_facets() % 4 != 0)
    throw UsageError("trace_vcavity_bsdf: not a vcavity surface (generate vcavity)");
  const std::size_t K = s.num_facets() / 4;
  const Strata strata((o.rays + K - 1) / K);
  const int orders = o.orders, npix = map.size(), nplane = plane.size();
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, K, 16), BsdfTally(),
      [&](const tbb::blocked_range<std::size_t>& range, BsdfTally acc) {
        if (acc.albedo.empty()) acc = BsdfTally(orders, npix, nplane);
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          // Groove k in its own frame (as measure_vcavity_g1): x along the horizontal part of
          // m_k, y along the ridge, one unit period per tile.
          const models::GrooveFrame frame(vcavity_groove_normal(s, k));
          const float top = static_cast<float>(0.5 * std::tan(frame.facet_angle));
          Microsurface groove = Microsurface::heightfield(2, 2, 1.0, 1.0, {0.0f, top, 0.0f, top});
          Tracer tracer(groove);
          const Vec3 wl = frame.to_local(wi);
          for (std::uint64_t i = 0; i < strata.total(); ++i) {
            CounterRng rng(o.seed, stream + (static_cast<std::uint64_t>(k) << 32), i);
            ++acc.paths;
            const Vec2 ab = strata.point(i, rng);
            WalkEnd e = walk_bsdf_path(tracer, Vec3(ab.x() - 0.5, ab.y() - 0.5, tracer.z_top()), -wl,
                                       o.material, rng, o.max_events, false, acc.counters, acc.events);
            e.direction = frame.to_world(e.direction);
            record_walk_end(acc, e, 1.0, map, plane);
          }
        }
        return acc;
      },
      [](BsdfTally a, const BsdfTally& b) {
        a += b;
        return a;
      });
}

}  // namespace microsim
