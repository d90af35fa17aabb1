#include "microsim/measure/vcavity_measure.hpp"
#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/sampling.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <chrono>

#include "microsim/models/vgroove_multiple.hpp"
#include "microsim/surface/generators.hpp"

namespace microsim {

namespace {

// Per groove and view: counts for its facet m (side 1) and m' (side 0).
struct GrooveTally {
  std::uint64_t hits[2] = {0, 0}, samples[2] = {0, 0}, visible[2] = {0, 0};
  TraceCounters counters;
};

std::uint64_t stream_of(std::uint64_t base, std::size_t view) { return base + 7919 * view; }

}  // namespace

std::vector<G1Result> measure_vcavity_g1(const Microsurface& s, const std::vector<Vec3>& views,
                                         const G1Options& o) {
  if (!is_vcavity(s) || s.num_facets() % 4 != 0)
    throw UsageError("measure_vcavity_g1: not a vcavity surface (generate vcavity)");
  if (o.rays == 0) throw UsageError("--rays must be positive");
  for (const Vec3& v : views)
    if (!(v.z() > 1e-12 * v.norm()))
      throw UsageError("--theta must be in [0, 90) degrees for a vcavity ensemble (its grooves are "
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
  const std::uint64_t per_groove = Strata((o.rays + K - 1) / K).total();
  const Strata sample_strata(o.rays);
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
    r.lambda_numeric = back / (r.v.z() * r.macro_area);  // DESIGN.md, 001 App. A
    r.window_area_perp = r.v.z() * r.macro_area;          // K unit tiles seen along v
    r.raycast_rays = per_groove * K;
    r.sample_rays = sample_strata.total();
  }

  // Area sampling: facet index of every stratified sample (nondecreasing in the sample index),
  // so that each groove handles a contiguous range of samples.
  std::vector<std::vector<std::uint32_t>> sample_facet(nv);
  for (std::size_t iv = 0; iv < nv; ++iv) {
    const std::vector<double>& cdf = cdfs[iv];
    const double total = cdf.back();
    std::vector<std::uint32_t>& sf = sample_facet[iv];
    sf.resize(sample_strata.total());
    tbb::parallel_for(std::uint64_t(0), sample_strata.total(), [&](std::uint64_t i) {
      CounterRng rng(o.seed, stream_of(0xC000, iv), i);
      double u = (static_cast<double>(i) + rng.uniform()) / sample_strata.total() * total;
      std::size_t j = std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin();
      j = std::min(j, 2 * K - 1);
      while (j > 0 && cdf[j] == cdf[j - 1]) --j;  // never a zero-weight facet
      sf[i] = static_cast<std::uint32_t>(j);
    });
  }

  std::vector<GrooveTally> tally(K * nv);
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
      GrooveTally& g = tally[k * nv + iv];
      const Vec3 v = results[iv].v;
      const Vec3 vl(v.dot(d), v.dot(t), v.z());
      // (a) stratified rays over the tile along -v.
      const Strata rays(per_groove);
      for (std::uint64_t i = 0; i < per_groove; ++i) {
        CounterRng rng(o.seed, stream_of(0xA000, iv) + (static_cast<std::uint64_t>(k) << 24), i);
        Vec2 ab = rays.point(i, rng);
        Vec3 org(ab.x() - 0.5, ab.y() - 0.5, tracer.z_top());
        TraceHit h = tracer.first_hit(org, -vl, nullptr, g.counters);
        if (h.hit && !h.backface) ++g.hits[(h.facet / 2) % 2];
      }
      // (b) this groove's share of the ensemble's stratified area samples.
      const std::vector<std::uint32_t>& sf = sample_facet[iv];
      const auto lo = std::lower_bound(sf.begin(), sf.end(), static_cast<std::uint32_t>(2 * k));
      const auto hi = std::lower_bound(sf.begin(), sf.end(), static_cast<std::uint32_t>(2 * k + 2));
      for (auto it = lo; it != hi; ++it) {
        const std::uint64_t i = static_cast<std::uint64_t>(it - sf.begin());
        const int side = static_cast<int>(*it - 2 * k);
        CounterRng rng(o.seed, stream_of(0xC000, iv), i);
        rng.uniform();  // the draw that placed the sample on its facet
        const double x = (side == 1 ? 0.5 : -0.5) * rng.uniform(), y = rng.uniform() - 0.5;
        const Vec3 p(x, y, top * (1 - 2 * std::abs(x)));
        ++g.samples[side];
        if (!tracer.occluded(p, vl, &plane[side], g.counters)) ++g.visible[side];
      }
    }
  });

  // Merge in groove order (integer counts: identical for any thread count).
  for (std::size_t iv = 0; iv < nv; ++iv) {
    G1Result& r = results[iv];
    for (std::size_t k = 0; k < K; ++k) {
      const GrooveTally& g = tally[k * nv + iv];
      for (int side = 0; side < 2; ++side) {
        G1NormalBin& nb = r.bins[bin[2 * k + side]];
        nb.raycast_hits += g.hits[side];
        nb.samples += g.samples[side];
        nb.visible += g.visible[side];
        r.raycast_hits += g.hits[side];
        r.sample_visible += g.visible[side];
      }
      r.counters += g.counters;
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (auto& r : results) r.seconds = seconds / nv;
  if (o.progress) o.progress(1.0);
  return results;
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
