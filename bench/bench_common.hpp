// Shared by the benchmarks: timing, peak memory, and the bare Embree loops that the estimators'
// ray rates are compared with (the very same rays, nothing else done per ray).
#pragma once
#include <embree3/rtcore.h>
#include <sys/resource.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/trace/ray_pipeline.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim::bench {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

inline double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}

// Processor time of the process so far (user + system, all threads), seconds.
inline double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// A rate both per wall second and per processor second (the robust one on a shared machine).
struct Rate {
  double wall = 0, cpu = 0;
  void best_of(const Rate& o) {
    wall = std::max(wall, o.wall);
    cpu = std::max(cpu, o.cpu);
  }
};

// Resident memory now (VmRSS), MiB: peaks of single stages are read as differences of it.
inline double rss_mib() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atof(line.c_str() + 6) / 1024.0;
  return 0;
}

// Estimator (a)'s primary rays exactly as measure_g1 casts them (same seed, replicate streams,
// stratified Morton-ordered origins on the ray window, chunks of the same ray indices, ray j of
// every replicate in turn), each traced by one plain rtcIntersect1 from the window to infinity: no
// wrap-around, no facet lookup, no binning. Rays per second.
// With `lean`, each ray is traced by Tracer::front_facet instead (the primary-ray path of (a)
// without its tallies): the cost of the path itself beside the bare query; with `ahead` 1 (or
// -1 on tiles of kAheadMinCells or more, as measure_g1), each ray is set up and prefetched 8
// rays before it is traced.
inline Rate bare_g1_rays_per_second(const Tracer& tracer, const Vec3& v_in, const G1Options& o,
                                    bool lean = false, int ahead = -1) {
  const Vec3 v = v_in.normalized();
  const RayWindow w = make_ray_window(tracer, v);
  const ReplicatePlan plan(o.rays, o.replicates);
  const int R = plan.replicates;
  const std::uint64_t n = plan.per_replicate(), span = std::max<std::uint64_t>(1, (1u << 14) / R);
  const std::uint64_t key = direction_stream_key(v), nc = (n + span - 1) / span;
  std::vector<std::uint64_t> keys(R);  // as measure_g1: the generators' keys once per replicate
  for (int q = 0; q < R; ++q) keys[q] = CounterRng::key(o.seed, ReplicatePlan::stream(0xA000 + key, q));
  std::vector<unsigned> hits(nc);
  const DownwardRays down(tracer, v);
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = cpu_seconds();
  tbb::parallel_for(std::uint64_t(0), nc, [&](std::uint64_t c) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    unsigned count = 0;
    TraceCounters counters;
    if (lean && (ahead > 0 || (ahead < 0 && static_cast<double>(tracer.surface().nx()) *
                                                   tracer.surface().ny() >= kAheadMinCells))) {  // as measure_g1 traces a heightfield: set up and prefetched ahead
      std::uint64_t j = c * span;
      int rep = 0;
      run_ahead<Vec3>(
          (std::min(n, (c + 1) * span) - c * span) * R,
          [&] {
            CounterRng rng(CounterRng::Keyed{}, keys[rep], j);
            const Vec2 ab = plan.strata.point(plan.strata.cell(j), rng);
            const Vec3 org = w.origin0 + ab.x() * w.e1 + ab.y() * w.e2;
            tracer.prefetch_front(down, org);
            if (++rep == R) {
              rep = 0;
              ++j;
            }
            return org;
          },
          [&](const Vec3& org) { count += tracer.front_facet(down, org, counters) != DownwardRays::kNone; });
      hits[c] = count;
      return;
    }
    for (std::uint64_t j = c * span; j < std::min(n, (c + 1) * span); ++j) {
      const Strata::Cell cell = plan.strata.cell(j);  // as measure_g1: once per ray index
      for (int rep = 0; rep < R; ++rep) {
        CounterRng rng(CounterRng::Keyed{}, keys[rep], j);
        const Vec2 ab = plan.strata.point(cell, rng);
        const Vec3 org = w.origin0 + ab.x() * w.e1 + ab.y() * w.e2;
        if (lean) {
          count += tracer.front_facet(down, org, counters) != DownwardRays::kNone;
          continue;
        }
        RTCRayHit rh{};
        rh.ray.org_x = float(org.x());
        rh.ray.org_y = float(org.y());
        rh.ray.org_z = float(org.z());
        rh.ray.dir_x = float(-v.x());
        rh.ray.dir_y = float(-v.y());
        rh.ray.dir_z = float(-v.z());
        rh.ray.tfar = 1e30f;
        rh.ray.mask = ~0u;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(tracer.scene(), &ctx, &rh);
        count += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
      }
    }
    hits[c] = count;  // kept so the loop cannot be optimised away
  });
  const double wall = seconds_since(t0), cpu = cpu_seconds() - c0;
  return {static_cast<double>(plan.total()) / wall, static_cast<double>(plan.total()) / cpu};
}

// The logged Embree queries of a run (Tracer::log_rays_on_this_thread) traced again by plain
// rtcIntersect1 calls, in their order, in parallel chunks. Rays per second.
inline Rate replay_rays_per_second(RTCScene scene, const std::vector<RTCRay>& rays) {
  const std::size_t chunk = 8192, nc = (rays.size() + chunk - 1) / chunk;
  std::vector<unsigned> hits(nc);
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = cpu_seconds();
  tbb::parallel_for(std::size_t(0), nc, [&](std::size_t c) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    unsigned count = 0;
    for (std::size_t i = c * chunk; i < std::min(rays.size(), (c + 1) * chunk); ++i) {
      RTCRayHit rh;
      rh.ray = rays[i];
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene, &ctx, &rh);
      count += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    hits[c] = count;
  });
  const double wall = seconds_since(t0), cpu = cpu_seconds() - c0;
  return {static_cast<double>(rays.size()) / wall, static_cast<double>(rays.size()) / cpu};
}

inline Rate replay_rays_per_second(const Tracer& tracer, const std::vector<RTCRay>& rays) {
  return replay_rays_per_second(tracer.scene(), rays);
}

}  // namespace microsim::bench
