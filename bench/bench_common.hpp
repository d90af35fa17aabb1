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

// Estimator (a)'s or (b)'s ray indices as measure_g1 orders them: R replicates of n rays in
// chunks of `span` ray indices (ray j of every replicate in turn), and the replicates' streams
// for a base stream (0xA000: primary rays, 0xB000: area samples) of the direction v.
struct G1RayChunks {
  ReplicatePlan plan;
  int R;
  std::uint64_t n, span, chunks;
  std::vector<std::uint64_t> streams;
  G1RayChunks(const Vec3& v, const G1Options& o, std::uint64_t base)
      : plan(o.rays, o.replicates), R(plan.replicates), n(plan.per_replicate()),
        span(std::max<std::uint64_t>(1, (1u << 14) / R)), chunks((n + span - 1) / span), streams(R) {
    for (int q = 0; q < R; ++q) streams[q] = ReplicatePlan::stream(base + direction_stream_key(v), q);
  }
  std::uint64_t first(std::uint64_t c) const { return c * span; }
  std::uint64_t end(std::uint64_t c) const { return std::min(n, (c + 1) * span); }
};

// A plain Embree query from `org` along `dir` to infinity (no instance, no hit yet).
inline RTCRayHit bare_ray_hit(const Vec3& org, const float dir[3]) {
  RTCRayHit rh{};
  rh.ray.org_x = float(org.x());
  rh.ray.org_y = float(org.y());
  rh.ray.org_z = float(org.z());
  rh.ray.dir_x = dir[0];
  rh.ray.dir_y = dir[1];
  rh.ray.dir_z = dir[2];
  rh.ray.tfar = 1e30f;
  rh.ray.mask = ~0u;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
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
  const G1RayChunks rays(v, o, 0xA000);
  const ReplicatePlan& plan = rays.plan;
  const int R = rays.R;
  const std::uint64_t nc = rays.chunks;
  std::vector<std::uint64_t> keys(R);  // as measure_g1: the generators' keys once per replicate
  for (int q = 0; q < R; ++q) keys[q] = CounterRng::key(o.seed, rays.streams[q]);
  std::vector<unsigned> hits(nc);
  const float dir[3] = {float(-v.x()), float(-v.y()), float(-v.z())};
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
      std::uint64_t j = rays.first(c);
      int rep = 0;
      run_ahead<Vec3>(
          (rays.end(c) - rays.first(c)) * R,
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
    for (std::uint64_t j = rays.first(c); j < rays.end(c); ++j) {
      const Strata::Cell cell = plan.strata.cell(j);  // as measure_g1: once per ray index
      for (int rep = 0; rep < R; ++rep) {
        CounterRng rng(CounterRng::Keyed{}, keys[rep], j);
        const Vec2 ab = plan.strata.point(cell, rng);
        const Vec3 org = w.origin0 + ab.x() * w.e1 + ab.y() * w.e2;
        if (lean) {
          count += tracer.front_facet(down, org, counters) != DownwardRays::kNone;
          continue;
        }
        RTCRayHit rh = bare_ray_hit(org, dir);
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

// --- Pieces of the bare loops, shared by the large-tile experiments (bench_large.hpp) ---------

// A rate of `rays` rays over the wall time since t0 and the processor time since c0.
inline Rate rate_since(double rays, std::chrono::steady_clock::time_point t0, double c0) {
  const double wall = seconds_since(t0), cpu = cpu_seconds() - c0;
  return {rays / wall, rays / cpu};
}

// The w x h grid points (i0 + i - 1, j0 + j - 1) of a periodic heightfield (the Tracer's grid
// padded by one cell around the tile) as float triples, row by row, into `out`.
inline void grid_vertices(const Microsurface& s, int i0, int j0, int w, int h, float* out) {
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const Vec3 p = s.grid_point(i0 + i - 1, j0 + j - 1);
      float* q = out + 3 * (static_cast<std::size_t>(j) * w + i);
      q[0] = float(p.x());
      q[1] = float(p.y());
      q[2] = float(p.z());
    }
}

// One grid geometry over `gw` x `gh` shared vertices (row stride gw, e.g. from grid_vertices),
// split into grid primitives of at most block x block cells (block 0: one primitive), committed
// and attached to `scene`.
inline void attach_grid_blocks(RTCDevice device, RTCScene scene, const float* vertices, int gw, int gh, int block) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_GRID);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices, 0, 12,
                             static_cast<std::size_t>(gw) * gh);
  const int cells_x = gw - 1, cells_y = gh - 1, b = block > 0 ? block : std::max(cells_x, cells_y);
  const int bx = (cells_x + b - 1) / b, by = (cells_y + b - 1) / b;
  auto* grids = static_cast<RTCGrid*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_GRID, 0, RTC_FORMAT_GRID,
                                                              sizeof(RTCGrid), static_cast<std::size_t>(bx) * by));
  for (int jb = 0; jb < by; ++jb)
    for (int ib = 0; ib < bx; ++ib) {
      RTCGrid& r = grids[jb * bx + ib];
      r.startVertexID = static_cast<unsigned>(static_cast<std::size_t>(jb) * b * gw + static_cast<std::size_t>(ib) * b);
      r.stride = static_cast<unsigned>(gw);
      r.width = static_cast<unsigned short>(std::min(b, cells_x - ib * b) + 1);
      r.height = static_cast<unsigned short>(std::min(b, cells_y - jb * b) + 1);
    }
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
}

}  // namespace microsim::bench
