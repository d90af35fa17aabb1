// Benchmark (not a test): rays/s of the G1 measurement against a bare rtcIntersect1 loop over
// the same scene and rays, scene build time and peak memory, for several tile resolutions.
//   microsim_bench [resolution...]    (default 1024 2048 4096)

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>


#include "microsim/measure/g1_measure.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/trace/tracer.hpp"
#include "bench_common.hpp"

using namespace microsim;

using namespace microsim::bench;

int main(int argc, char** argv) {
  std::vector<int> resolutions;
  for (int k = 1; k < argc; ++k) resolutions.push_back(std::atoi(argv[k]));
  if (resolutions.empty()) resolutions = {1024, 2048, 4096};
  const std::uint64_t rays = 2000000;
  std::printf("%-13s %6s %8s %8s %10s %10s %10s %10s %8s %9s %7s\n", "tile", "gen_s", "build_s",
              "facet_s", "g1_Mray/s", "(a)Mray/s", "(b)Mray/s", "bare_Mray/s", "(a)/bare",
              "peak_MiB", "B/facet");
  for (int res : resolutions) {
    GaussianParams p;
    p.resolution = res;
    auto t0 = std::chrono::steady_clock::now();
    Microsurface s = generate_gaussian(p);
    double gen = seconds_since(t0);
    Tracer tracer(s);
    G1Options o;
    o.rays = rays;
    FacetTable table = build_facet_table(s, g1_normal_binning(o));
    for (double theta_deg : {0.0, 60.0, 85.0}) {
      Vec3 v = direction_from_angles(rad(theta_deg), 0.0);
      G1Result r = measure_g1(tracer, v, o, &table);
      // Rate of the tracing part; the exact facet sums (facet_s) are reported separately.
      // raycast: estimator (a) alone, the same rays as the bare loop (the honest ratio);
      // occlusion: estimator (b), rays leaving facets (filtered for self-intersection).
      double g1_rate = r.counters.rays / (r.seconds - r.facet_seconds);
      double raycast_rate = r.raycast_rays / r.raycast_seconds;
      double sample_rate = r.sample_rays / r.sample_seconds;
      double bare = bare_loop_rays_per_second(tracer, v, rays, 0xA000);
      std::printf("%4d^2 %3.0fdeg %6.2f %8.2f %8.3f %10.2f %10.2f %10.2f %10.2f %8.2f %9.0f %7.1f\n",
                  res, theta_deg, gen, tracer.build_seconds(), r.facet_seconds, g1_rate / 1e6,
                  raycast_rate / 1e6, sample_rate / 1e6, bare / 1e6, raycast_rate / bare,
                  peak_rss_mib(), peak_rss_mib() * 1048576.0 / s.num_facets());
    }
  }
  return 0;
}
