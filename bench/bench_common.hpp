// Shared by the benchmarks: timing, peak memory, and the bare Embree loop that the estimators'
// ray rates are compared with.
#pragma once
#include <embree3/rtcore.h>
#include <sys/resource.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <vector>

#include "microsim/measure/sampling.hpp"
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

// The estimators' primary rays (stratified, Morton-ordered origins on the top of the tile,
// direction -v), each traced by one plain rtcIntersect1: no wrap-around, no filter, no binning.
inline double bare_loop_rays_per_second(const Tracer& tracer, const Vec3& v, std::uint64_t n,
                                        std::uint64_t stream) {
  const Macrosurface& m = tracer.surface().macro();
  const Strata strata(n);
  const std::uint64_t total = strata.total(), chunk = 16384;
  std::vector<unsigned> hits(total / chunk + 1);
  const auto t0 = std::chrono::steady_clock::now();
  tbb::parallel_for(std::uint64_t(0), (total + chunk - 1) / chunk, [&](std::uint64_t c) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    unsigned count = 0;
    for (std::uint64_t i = c * chunk; i < std::min(total, (c + 1) * chunk); ++i) {
      CounterRng rng(1, stream, i);
      const Vec2 ab = strata.point(i, rng);
      RTCRayHit rh{};
      rh.ray.org_x = float(-0.5 * m.size_x + ab.x() * m.size_x);
      rh.ray.org_y = float(-0.5 * m.size_y + ab.y() * m.size_y);
      rh.ray.org_z = float(tracer.z_top());
      rh.ray.dir_x = float(-v.x());
      rh.ray.dir_y = float(-v.y());
      rh.ray.dir_z = float(-v.z());
      rh.ray.tfar = 1e30f;
      rh.ray.mask = ~0u;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(tracer.scene(), &ctx, &rh);
      count += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    hits[c] = count;  // kept so the loop cannot be optimised away
  });
  return total / seconds_since(t0);
}

}  // namespace microsim::bench
