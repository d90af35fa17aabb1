// Benchmark (not a test): rays/s of the G1 measurement against a bare rtcIntersect1 loop over
// the same scene and the very same rays, scene build time and memory, for several tile
// resolutions (Beckmann alpha = 0.5, 4 cells per correlation length).
//   microsim_bench [--rays N] [--repeat K] [--large] [--walks P]
//                  [--only g1|bare|lean|ahead|walk|plain|packets|layout|sample|bins] [resolution...]
// (default 1024 2048 4096 8192; --large adds 16384, about 9 GB and several processor minutes).
// Tiles run in increasing size, so the process's peak resident memory after a tile is that
// tile's peak (B/facet: peak bytes per facet, generation and tracing in this process).
//   --walks P: after each tile's G1 rows, P-path mirror and
//   dielectric walk rows against the replay of their own queries (bench_walks.hpp), and after
//   the first tile's, the Smith random-walk model's walks per processor second.
//   lean_Mray/s: the primary-ray path of (a) (Tracer::front_facet, rays set up and prefetched
//   ahead from kAheadMinCells cells on, as in measure_g1) alone on the bare loop's rays.
//   --only walk / --only plain: measure_bsdf's walks alone / the plain walk tracer alone
//   (plain_walk.hpp), P paths (--walks, default 1000000), for a profiler.
//   --only ahead: bare loop and lean path with and without the look-ahead, interleaved (rates
//   per processor second, ratio to bare).
//   --only packets | layout | sample (bench_large.hpp): the bare loop's rays as single rays,
//   packets of 4/8/16 and coherent streams; the Tracer's scene against other layouts of the
//   grid (flags, build quality, grid blocks, per-block instances); estimator (b)'s rays with
//   and without their look-ahead.
//   --only bins (bench_bins.hpp): the lean path with the hit's bin and count variants of (a)
//   (none, a bin from the index, the table's bin with 64- or 16-bit counts, rays in blocks as
//   (a) traces them), (a) inside measure_g1, and the bare loop after the caches were evicted;
//   median ratios to the bare loop.
// Each direction runs K times (default 3), the estimator and the bare loop interleaved in the
// same process; the best of each is reported (on a shared machine the slower runs are the ones
// that lost the CPU), and the ratio is that of the best rates.
// Peak memory of each command (generate, info, measure g1/ndf/bsdf) per tile: bench/peak_memory.sh.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "microsim/measure/facet_table.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/trace/tracer.hpp"
#include "bench_common.hpp"
#include "bench_bins.hpp"
#include "bench_large.hpp"
#include "bench_walks.hpp"

using namespace microsim;
using namespace microsim::bench;

int main(int argc, char** argv) {
  std::vector<int> resolutions;
  std::uint64_t rays = 2000000;
  int repeat = 3;
  bool large = false;
  std::uint64_t walks = 0;  // --walks N: also N-path walk rows on every tile (bench_walks.hpp)
  std::string only;  // "g1", "bare" or "lean": run measure_g1, the bare loop or the lean path alone (for a profiler)
  for (int k = 1; k < argc; ++k) {
    if (!std::strcmp(argv[k], "--rays") && k + 1 < argc) rays = std::strtoull(argv[++k], nullptr, 10);
    else if (!std::strcmp(argv[k], "--only") && k + 1 < argc) only = argv[++k];
    else if (!std::strcmp(argv[k], "--walks") && k + 1 < argc) walks = std::strtoull(argv[++k], nullptr, 10);
    else if (!std::strcmp(argv[k], "--repeat") && k + 1 < argc) repeat = std::atoi(argv[++k]);
    else if (!std::strcmp(argv[k], "--large")) large = true;
    else resolutions.push_back(std::atoi(argv[k]));
  }
  if (resolutions.empty()) resolutions = {1024, 2048, 4096, 8192};
  if (large) resolutions.push_back(16384);
  std::sort(resolutions.begin(), resolutions.end());
  std::vector<std::pair<int, double>> peaks;  // tile, peak MiB
  std::printf("Gaussian tiles, alpha 0.5; %llu rays per estimator and direction, best of %d\n",
              static_cast<unsigned long long>(rays), repeat);
  std::printf("Rates per processor second (user + system of all threads; wall rates in the last "
              "columns)\n");
  std::printf("%-13s %6s %8s %8s %10s %10s %11s %8s %11s %9s %10s %10s %8s %8s %8s\n", "tile",
              "gen_s", "build_s", "facet_s", "(a)Mray/s", "(b)Mray/s", "bare_Mray/s", "(a)/bare",
              "lean_Mray/s", "lean/bare", "rss_MiB", "peak_MiB", "B/facet", "wall(a)", "wall_bare");
  for (int res : resolutions) {
    GaussianParams p;
    p.resolution = res;
    p.alpha_x = p.alpha_y = 0.5;
    p.correlation_length = 4.0 * p.size / res;
    auto t0 = std::chrono::steady_clock::now();
    Microsurface s = generate_gaussian(p);
    const double gen = seconds_since(t0);
    Tracer tracer(s);
    G1Options o;
    o.rays = rays;
    const FacetTable table = build_facet_table(s, g1_normal_binning(o));
    const double nf = static_cast<double>(s.num_facets());
    if (only == "walk" || only == "plain") {  // the walks alone, for a profiler (bench_walks.hpp)
      run_walks_only(tracer, walks > 0 ? walks : 1000000, repeat, only == "plain");
      continue;
    }
    for (double theta_deg : {0.0, 60.0, 85.0}) {
      const Vec3 v = direction_from_angles(rad(theta_deg), 0.0);
      Rate a, b, bare, lean;
      double facet_s = 1e30;
      if (only == "ahead") {  // the look-ahead alone: lean path with and without it, interleaved
        Rate bare1, with, without;
        for (int k = 0; k < repeat; ++k) {
          bare1.best_of(bare_g1_rays_per_second(tracer, v, o));
          without.best_of(bare_g1_rays_per_second(tracer, v, o, true, 0));
          with.best_of(bare_g1_rays_per_second(tracer, v, o, true, 1));
        }
        std::printf("%5d^2 %3.0fdeg bare %.2f  lean without look-ahead %.2f (%.2f)  with %.2f (%.2f)\n",
                    res, theta_deg, bare1.cpu / 1e6, without.cpu / 1e6, without.cpu / bare1.cpu,
                    with.cpu / 1e6, with.cpu / bare1.cpu);
        std::fflush(stdout);
        continue;
      }
      if (only == "bins") {  // what (a) pays for the hit's bin and count (bench_bins.hpp)
        print_bin_rows(tracer, table, v, o, repeat, res, theta_deg);
        continue;
      }
      if (only == "packets" || only == "layout" || only == "sample") {  // large-tile experiments (bench_large.hpp)
        if (only == "packets") print_packet_rows(tracer, v, o, repeat, res, theta_deg);
        else if (only == "sample") print_sample_rows(tracer, table, v, o, repeat, res, theta_deg);
        else print_layout_rows(tracer, v, o, repeat, res, theta_deg);
        continue;
      }
      if (!only.empty()) {
        for (int k = 0; k < repeat; ++k) {
          if (only == "g1") measure_g1(tracer, v, o, &table);
          else bare_g1_rays_per_second(tracer, v, o, only == "lean");
        }
        continue;
      }
      for (int k = 0; k < repeat; ++k) {
        const G1Result r = measure_g1(tracer, v, o, &table);
        // (a): the same rays as the bare loop, plus wrap-around, exact facet lookup, binning;
        // (b): occlusion rays leaving facets (filtered for self-intersection).
        a.best_of({r.raycast_rays / r.raycast_seconds, r.raycast_rays / r.raycast_cpu_seconds});
        b.best_of({r.sample_rays / r.sample_seconds, r.sample_rays / r.sample_cpu_seconds});
        facet_s = std::min(facet_s, r.facet_seconds);
        bare.best_of(bare_g1_rays_per_second(tracer, v, o));
        lean.best_of(bare_g1_rays_per_second(tracer, v, o, true));
      }
      const double rss = rss_mib(), peak = peak_rss_mib();
      std::printf("%5d^2 %3.0fdeg %6.2f %8.2f %8.3f %10.2f %10.2f %11.2f %8.2f %11.2f %9.2f %10.0f %10.0f %8.1f %8.2f %8.2f\n",
                  res, theta_deg, gen, tracer.build_seconds(), facet_s, a.cpu / 1e6, b.cpu / 1e6,
                  bare.cpu / 1e6, a.cpu / bare.cpu, lean.cpu / 1e6, lean.cpu / bare.cpu, rss, peak,
                  peak * 1048576.0 / nf, a.wall / 1e6, bare.wall / 1e6);
      std::fflush(stdout);
    }
    peaks.emplace_back(res, peak_rss_mib());
    if (walks > 0 && only.empty()) {
      std::printf("walks on the %d^2 tile, %llu paths per row:\n", res, static_cast<unsigned long long>(walks));
      // The Smith random-walk model does not depend on the tile: its rows once, after the first.
      print_walk_rows(tracer, walks, repeat, res == resolutions.front());
    }
  }
  std::printf("\nPeak resident memory per tile (generation, scene build, facet table, G1)\n%-8s %10s %8s\n",
              "tile", "peak_MiB", "B/facet");
  for (const auto& [res, peak] : peaks)
    std::printf("%6d^2 %10.0f %8.1f\n", res, peak, peak * 1048576.0 / (2.0 * res * res));
  std::fflush(stdout);  // the libraries' exit handlers may end the process without flushing
  return 0;
}
