// Benchmark (not a test): random-walk rays/s of the BSDF measurement (every traced segment of
// every path counts as a ray) against a bare rtcIntersect1 loop over the same scene and the
// same primary rays, for mirror and dielectric walks at several incidence angles.
//   microsim_bench_bsdf [resolution] [rays]    (default 1024, 1000000)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <tbb/parallel_for.h>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/trace/tracer.hpp"

using namespace microsim;

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Stratified, Morton-ordered origins on the top of the tile, direction -l; one plain
// rtcIntersect1 each: no wrap-around, no filter, no scattering.
double bare_loop_rays_per_second(const Tracer& tracer, const Vec3& l, std::uint64_t n) {
  const Macrosurface& m = tracer.surface().macro();
  std::uint32_t grid = 1;
  while (std::uint64_t(grid) * 2 * grid * 2 <= n) grid *= 2;
  const std::uint64_t per = (n + std::uint64_t(grid) * grid - 1) / (std::uint64_t(grid) * grid);
  const std::uint64_t total = per * grid * grid;
  std::vector<unsigned> hits(total / 16384 + 1);
  const auto t0 = std::chrono::steady_clock::now();
  tbb::parallel_for(std::uint64_t(0), (total + 16383) / 16384, [&](std::uint64_t c) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    unsigned count = 0;
    for (std::uint64_t i = c * 16384; i < std::min(total, (c + 1) * 16384); ++i) {
      CounterRng rng(1, 0xB5DF, i);
      std::uint32_t sx, sy;
      morton_decode(i / per, sx, sy);
      const double a = (sx + rng.uniform()) / grid, b = (sy + rng.uniform()) / grid;
      RTCRayHit rh{};
      rh.ray.org_x = float(-0.5 * m.size_x + a * m.size_x);
      rh.ray.org_y = float(-0.5 * m.size_y + b * m.size_y);
      rh.ray.org_z = float(tracer.z_top());
      rh.ray.dir_x = float(-l.x());
      rh.ray.dir_y = float(-l.y());
      rh.ray.dir_z = float(-l.z());
      rh.ray.tfar = 1e30f;
      rh.ray.mask = ~0u;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(tracer.scene(), &ctx, &rh);
      count += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    hits[c] = count;
  });
  return total / seconds_since(t0);
}
}  // namespace

int main(int argc, char** argv) {
  const int res = argc > 1 ? std::atoi(argv[1]) : 1024;
  const std::uint64_t rays = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1000000;
  GaussianParams p;
  p.resolution = res;
  p.alpha_x = p.alpha_y = 0.5;
  Microsurface s = generate_gaussian(p);
  Tracer tracer(s);
  std::printf("Gaussian tile %d^2, alpha 0.5; %llu paths per row\n", res, (unsigned long long)rays);
  std::printf("%-11s %6s %9s %9s %11s %12s %12s %7s\n", "material", "theta", "paths/s", "rays/path",
              "walk_Mray/s", "bare_Mray/s", "model_walk/s", "ratio");
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
      o.rays = rays;
      o.model_walks = rays;
      const BsdfResult r = measure_bsdf(tracer, o);
      const double walk_seconds = r.seconds - r.model_seconds;
      const double walk_rate = r.measured.counters.rays / walk_seconds;
      const double bare = bare_loop_rays_per_second(tracer, direction_from_angles(o.theta_i, 0.0), rays);
      std::printf("%-11s %6.0f %9.3g %9.3f %11.2f %12.2f %12.3g %7.2f\n", c.name, theta,
                  r.measured.paths / walk_seconds,
                  double(r.measured.counters.rays) / r.measured.paths, walk_rate / 1e6, bare / 1e6,
                  r.smith_walk ? r.smith_walk->paths / r.model_seconds : 0.0, walk_rate / bare);
    }
  return 0;
}
