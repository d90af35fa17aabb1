// Walk rows shared by the benchmarks (microsim_bench --walks, microsim_bench_bsdf): random walks
// of the BSDF measurement (mirror and dielectric) against a bare rtcIntersect1 loop over the very
// same Embree queries, and the Smith random-walk model's walks per second.
// The bare loop replays the queries that the walks of the first 200000 paths made (logged by
// the tracer, in order); the ratio compares rays per second of the walk (Embree queries made per
// path x paths per second) with the replay's. Rates per processor second (user + system of all
// threads: robust on a shared machine), best of `repeat`, interleaved; wall_path/s: the walks'
// paths per wall second (measure_bsdf's own clock), which shows whether both threads worked.
// Beside them, the plain walk tracer (plain_walk.hpp) on the same heights, paths and incidence,
// with and without RTC_SCENE_FLAG_ROBUST, and the replay on its (non-robust) scene.
#pragma once
#include <algorithm>
#include <cstdio>
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/replicates.hpp"
#include "bench_common.hpp"
#include "plain_walk.hpp"

namespace microsim::bench {


// The Embree queries of the walks of the first m paths (replicates in order), as measure_bsdf
// starts them; *paths_walked: how many.
inline std::vector<RTCRay> log_walk_queries(const Tracer& tracer, const BsdfOptions& o, std::uint64_t m,
                                     std::uint64_t* paths_walked) {
  const Vec3 wi = direction_from_angles(o.theta_i, o.phi_i);
  const RayWindow window = make_ray_window(tracer, wi);
  const ReplicatePlan plan(o.rays, o.replicates);
  // measure_bsdf's stream of a direction (bsdf_measure.cpp)
  const std::uint64_t stream = 0xB5DF0000ull +
                               static_cast<std::uint64_t>(static_cast<std::int64_t>(o.theta_i * 1e6)) * 7919 +
                               static_cast<std::uint64_t>(static_cast<std::int64_t>(o.phi_i * 1e6));
  std::vector<RTCRay> log;
  Tracer::log_rays_on_this_thread(&log);
  TraceCounters counters;
  std::uint64_t events = 0;
  std::uint64_t walked = 0;
  for (int q = 0; q < plan.replicates && walked < m; ++q)
    for (std::uint64_t i = 0; i < plan.per_replicate() && walked < m; ++i, ++walked) {
      CounterRng rng(o.seed, ReplicatePlan::stream(stream, q), i);
      const Vec2 ab = plan.strata.point(i, rng);
      walk_bsdf_path(tracer, window.origin0 + ab.x() * window.e1 + ab.y() * window.e2, -wi,
                     o.material, rng, o.max_events, false, counters, events);
    }
  *paths_walked = walked;
  Tracer::log_rays_on_this_thread(nullptr);
  return log;
}


// For a profiler: only the walks of measure_bsdf (`plain` false) or only the plain walk tracer's,
// mirror and dielectric at 0, 60 and 85 degrees, `repeat` times each.
inline void run_walks_only(const Tracer& tracer, std::uint64_t paths, int repeat, bool plain) {
  const PlainWalker walker(tracer.surface());
  for (const models::Material& m : {models::Material::mirror(), models::Material::dielectric(1.5)})
    for (double theta : {0.0, 60.0, 85.0})
      for (int k = 0; k < repeat; ++k) {
        BsdfOptions o;
        o.material = m;
        o.theta_i = rad(theta);
        o.rays = paths;
        o.models = false;
        if (plain)
          walker.run(tracer, direction_from_angles(o.theta_i, 0.0), paths,
                     m.kind == models::MaterialKind::Dielectric ? m.eta : 0.0);
        else
          measure_bsdf(tracer, o);
      }
}

// Prints the walk rows for `tracer`'s tile; `smith`: also the Smith random-walk model's rows.
inline void print_walk_rows(const Tracer& tracer, std::uint64_t paths, int repeat, bool smith) {
  // The plain walk tracer (plain_walk.hpp) on the same heights, same paths and incidence.
  // plainR: the same with RTC_SCENE_FLAG_ROBUST, as the Tracer's scene; lost/M: paths per
  // million that ended neither reflected nor transmitted; bare_nonrob: the replay on the plain
  // tracer's (non-robust) scene.
  const PlainWalker plain(tracer.surface()), plain_robust(tracer.surface(), true);
  std::printf("%-11s %6s %10s %10s %12s %12s %12s %7s %12s %11s %11s %9s %12s %9s %9s %11s %11s\n", "material", "theta",
              "paths/s", "segs/path", "Msegs/s", "queries/path", "bare_Mray/s", "ratio", "plain_path/s", "plain_segs",
              "plain_Mseg/s", "vs_plain", "plainR_path/s", "lost/M", "lostR/M", "bare_nonrob", "wall_path/s");
  struct Case {
    const char* name;
    models::Material m;
  };
  for (const Case& c : {Case{"mirror", models::Material::mirror()},
                        Case{"dielectric", models::Material::dielectric(1.5)}})
    for (double theta : {0.0, 60.0, 85.0}) {
      BsdfOptions o;
      o.material = c.m;
      o.theta_i = rad(theta);
      o.rays = paths;
      o.models = false;
      std::uint64_t walked = 0;
      const std::vector<RTCRay> log = log_walk_queries(tracer, o, std::min<std::uint64_t>(paths, 200000), &walked);
      const double queries_per_path = double(log.size()) / walked;
      double best = 0, segs_per_path = 0, plain_best = 0, plain_segs = 0, robust_best = 0;
      double lost = 0, lost_robust = 0, wall_best = 0;
      Rate bare, bare_nonrobust;
      for (int k = 0; k < repeat; ++k) {
        const double c0 = cpu_seconds();
        const BsdfResult r = measure_bsdf(tracer, o);
        best = std::max(best, r.measured.paths / (cpu_seconds() - c0));
        wall_best = std::max(wall_best, r.measured.paths / r.timing.wall_seconds);
        segs_per_path = double(r.measured.counters.rays) / r.measured.paths;
        bare.best_of(replay_rays_per_second(tracer, log));
        const Vec3 wi = direction_from_angles(o.theta_i, o.phi_i);
        const double eta = c.m.kind == models::MaterialKind::Dielectric ? c.m.eta : 0.0;
        const double c1 = cpu_seconds();
        const PlainWalkStats ps = plain.run(tracer, wi, paths, eta);
        plain_best = std::max(plain_best, ps.paths / (cpu_seconds() - c1));
        plain_segs = double(ps.segments) / ps.paths;
        lost = 1e6 * double(ps.lost) / ps.paths;
        const double c2 = cpu_seconds();
        const PlainWalkStats pr = plain_robust.run(tracer, wi, paths, eta);
        robust_best = std::max(robust_best, pr.paths / (cpu_seconds() - c2));
        lost_robust = 1e6 * double(pr.lost) / pr.paths;
        bare_nonrobust.best_of(replay_rays_per_second(plain.scene(), log));
      }
      std::printf("%-11s %6.0f %10.3g %10.3f %12.2f %12.3f %12.2f %7.2f %12.3g %11.3f %11.2f %9.2f %12.3g %9.1f %9.1f %11.2f %11.3g\n",
                  c.name, theta, best, segs_per_path, best * segs_per_path / 1e6, queries_per_path, bare.cpu / 1e6,
                  best * queries_per_path / bare.cpu, plain_best, plain_segs, plain_best * plain_segs / 1e6,
                  best / plain_best, robust_best, lost, lost_robust, bare_nonrobust.cpu / 1e6, wall_best);
      std::fflush(stdout);
    }
  // The Smith random-walk model alone (the measured part reduced to a token 1000 paths).
  if (smith)
  for (double theta : {0.0, 60.0, 85.0}) {
    double best = 0;
    for (int k = 0; k < repeat; ++k) {
      BsdfOptions o;
      o.material = models::Material::mirror();
      o.theta_i = rad(theta);
      o.rays = 1000;
      o.model_walks = paths;
      // Processor time of the model part: the whole call less the (token) walks' share.
      const double c0 = cpu_seconds();
      const BsdfResult r = measure_bsdf(tracer, o);
      const double cpu = (cpu_seconds() - c0) * r.model_timing.wall_seconds / r.timing.wall_seconds;
      if (r.smith_walk) best = std::max(best, r.smith_walk->paths / cpu);
    }
    std::printf("smith-walk  %6.0f %10.3g walks/s (mirror)\n", theta, best);
    std::fflush(stdout);
  }
}

}  // namespace microsim::bench
