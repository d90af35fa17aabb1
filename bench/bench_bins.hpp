// Experiment of microsim_bench (--only bins): what estimator (a) pays after the primary ray
// for the hit facet's normal bin and its count, on the bare loop's rays (bench_common.hpp),
// every variant interleaved in one process. Rates per processor second and ratio to the bare
// query; every variant counts the same hits (printed), and those that bin count the same bins.
#pragma once
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "bench_common.hpp"
#include "microsim/measure/facet_table.hpp"

namespace microsim::bench {

enum class BinVariant {
  None,         // the lean path alone: hits counted, no bin
  FakeBin64,    // a bin from the facet index (no memory read), 64-bit counts
  Table64,      // the table's bin, 64-bit counts (estimator (a) before)
  Table16,      // the table's bin, 16-bit counts per chunk
  Batched64,    // the table's bin, looked up for 32 hits at once after their rays, 64-bit counts
  Blocks64,     // Tracer::front_facets (ray j of every replicate: origins, queries, hits in
                // turn), the table's bin, 64-bit counts (estimator (a) now)
};

inline const char* bin_variant_name(BinVariant b) {
  switch (b) {
    case BinVariant::None: return "lean, no bin";
    case BinVariant::FakeBin64: return "index bin, u64";
    case BinVariant::Table64: return "table bin, u64";
    case BinVariant::Table16: return "table bin, u16";
    case BinVariant::Blocks64: return "front_facets blocks, table bin, u64";
    default: return "table bin batched, u64";
  }
}

// (a)'s loop on a heightfield below kAheadMinCells (g1_measure.cpp), with the variant's bin and
// count. Returns the rate; `checksum` gets a sum over the counts (equal between the variants
// that bin).
inline Rate binned_lean_rays_per_second(const Tracer& tracer, const FacetTable& table,
                                        const Vec3& v_in, const G1Options& o, BinVariant var,
                                        std::uint64_t& checksum) {
  const Vec3 v = v_in.normalized();
  const RayWindow w = make_ray_window(tracer, v);
  const G1RayChunks rays(v, o, 0xA000);  // measure_g1's chunks and streams
  const ReplicatePlan& plan = rays.plan;
  const int R = rays.R;
  const std::uint64_t nc = rays.chunks;
  std::vector<std::uint64_t> keys(R);
  for (int q = 0; q < R; ++q) keys[q] = CounterRng::key(o.seed, rays.streams[q]);
  const std::size_t nb = static_cast<std::size_t>(g1_normal_binning(o).size());
  const std::size_t nf = tracer.surface().num_facets();
  const std::uint16_t* bins16 = table.bins16();
  std::vector<std::uint64_t> sums(nc);
  const DownwardRays down(tracer, v);
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = cpu_seconds();
  tbb::parallel_for(std::uint64_t(0), nc, [&](std::uint64_t c) {
    TraceCounters counters;
    std::vector<std::uint64_t> h64(var == BinVariant::Table16 ? 0 : R * nb + 1);
    std::vector<std::uint16_t> h16(var == BinVariant::Table16 ? R * nb + 1 : 0);
    const std::size_t nobin = R * nb;
    std::size_t pend_k[32], pend_q[32];
    int pending = 0;
    auto flush = [&] {
      for (int i = 0; i < pending; ++i) {
        const std::uint16_t b = bins16[pend_k[i]];
        ++h64[b == FacetTable::kNoBin16 ? nobin : pend_q[i] * nb + b];
      }
      pending = 0;
    };
    for (std::uint64_t j = rays.first(c); j < rays.end(c); ++j) {
      const Strata::Cell cell = plan.strata.cell(j);
      if (var == BinVariant::Blocks64) {
        tracer.front_facets(
            down, static_cast<std::size_t>(R),
            [&](std::size_t q) {
              CounterRng rng(CounterRng::Keyed{}, keys[q], j);
              const Vec2 ab = plan.strata.point(cell, rng);
              return Vec3(w.origin0 + ab.x() * w.e1 + ab.y() * w.e2);
            },
            [&](std::size_t) -> TraceCounters& { return counters; },
            [&](std::size_t q, std::size_t k) {
              if (k >= nf) return;
              const std::uint16_t b = bins16[k];
              ++h64[b == FacetTable::kNoBin16 ? nobin : q * nb + b];
            });
        continue;
      }
      for (int q = 0; q < R; ++q) {
        CounterRng rng(CounterRng::Keyed{}, keys[q], j);
        const Vec2 ab = plan.strata.point(cell, rng);
        const Vec3 org = w.origin0 + ab.x() * w.e1 + ab.y() * w.e2;
        const std::size_t k = tracer.front_facet(down, org, counters);
        if (k >= nf) continue;
        switch (var) {
          case BinVariant::Batched64:
            pend_k[pending] = k;
            pend_q[pending] = q;
            if (++pending == 32) flush();
            break;
          case BinVariant::None: ++h64[0]; break;
          case BinVariant::FakeBin64: ++h64[q * nb + (k >> 7) % nb]; break;
          case BinVariant::Table64: {
            const std::uint16_t b = bins16[k];
            ++h64[b == FacetTable::kNoBin16 ? nobin : q * nb + b];
            break;
          }
          case BinVariant::Table16: {
            const std::uint16_t b = bins16[k];
            ++h16[b == FacetTable::kNoBin16 ? nobin : q * nb + b];
            break;
          }
          case BinVariant::Blocks64: break;  // counted block by block above
        }
      }
    }
    flush();
    std::uint64_t s = 0;
    for (std::size_t b = 0; b < h64.size(); ++b) s += h64[b] * (b + 1);
    for (std::size_t b = 0; b < h16.size(); ++b) s += h16[b] * (b + 1);
    sums[c] = s;
  });
  const Rate rate = rate_since(static_cast<double>(plan.total()), t0, c0);
  checksum = 0;
  for (std::uint64_t s : sums) checksum += s;
  return rate;
}

// Each repetition runs the bare loop and then every variant; the ratio reported is the median
// over repetitions of variant / bare of the same repetition (neighbours in time share the
// machine's load), beside the best rates.
// Reads and writes 64 MiB (twice the L3 of the development machine): the loop after it finds
// no tile data in the caches.
inline void evict_caches() {
  static std::vector<std::uint64_t> junk(std::size_t(8) << 20);
  std::uint64_t s = 0;
  for (std::uint64_t& x : junk) s += ++x;
  if (s == 42) std::printf(" ");  // keeps the loop
}

// Each repetition runs the bare loop, then every variant, then estimator (a) in measure_g1 (its
// own rate of the ray-casting phase, which follows the facet sums there), then the bare loop
// after the caches were evicted. Bins compared as sums per variant.
inline void print_bin_rows(const Tracer& tracer, const FacetTable& table, const Vec3& v,
                           const G1Options& o, int repeat, int res, double theta_deg) {
  const BinVariant vars[] = {BinVariant::None,      BinVariant::FakeBin64, BinVariant::Table64,
                             BinVariant::Table16,   BinVariant::Batched64, BinVariant::Blocks64};
  constexpr int kVars = sizeof(vars) / sizeof(vars[0]);
  Rate bare, rate[kVars], g1, cold;
  std::vector<double> ratios[kVars], g1_ratios, cold_ratios;
  std::uint64_t sum[kVars] = {};
  for (int k = 0; k < repeat; ++k) {
    const Rate b = bare_g1_rays_per_second(tracer, v, o);
    bare.best_of(b);
    for (int i = 0; i < kVars; ++i) {
      const Rate r = binned_lean_rays_per_second(tracer, table, v, o, vars[i], sum[i]);
      rate[i].best_of(r);
      ratios[i].push_back(r.cpu / b.cpu);
    }
    const G1Result g = measure_g1(tracer, v, o, &table);
    const Rate a{g.raycast_rays / g.raycast_seconds, g.raycast_rays / g.raycast_cpu_seconds};
    g1.best_of(a);
    g1_ratios.push_back(a.cpu / b.cpu);
    evict_caches();
    const Rate bc = bare_g1_rays_per_second(tracer, v, o);
    cold.best_of(bc);
    cold_ratios.push_back(bc.cpu / b.cpu);
  }
  auto median = [](std::vector<double>& x) {
    std::sort(x.begin(), x.end());
    return x[x.size() / 2];
  };
  std::printf("%5d^2 %3.0fdeg bare %.2f", res, theta_deg, bare.cpu / 1e6);
  for (int i = 0; i < kVars; ++i)
    std::printf(" | %s %.2f (median ratio %.3f) sum %llu", bin_variant_name(vars[i]), rate[i].cpu / 1e6,
                median(ratios[i]), static_cast<unsigned long long>(sum[i]));
  std::printf(" | (a) in measure_g1 %.2f (median ratio %.3f) | bare after eviction %.2f (median ratio %.3f)\n",
              g1.cpu / 1e6, median(g1_ratios), cold.cpu / 1e6, median(cold_ratios));
  std::fflush(stdout);
}

}  // namespace microsim::bench
