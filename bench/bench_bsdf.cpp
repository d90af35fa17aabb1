// Benchmark (not a test): random-walk rays/s of the BSDF measurement (every traced segment of
// every path counts as a ray) against a bare rtcIntersect1 loop over the same scene and the
// same primary rays, for mirror and dielectric walks at several incidence angles.
//   microsim_bench_bsdf [resolution] [rays]    (default 1024, 1000000)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>


#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/trace/tracer.hpp"
#include "bench_common.hpp"

using namespace microsim;

using namespace microsim::bench;

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
      const double bare = bare_loop_rays_per_second(tracer, direction_from_angles(o.theta_i, 0.0), rays, 0xB5DF);
      std::printf("%-11s %6.0f %9.3g %9.3f %11.2f %12.2f %12.3g %7.2f\n", c.name, theta,
                  r.measured.paths / walk_seconds,
                  double(r.measured.counters.rays) / r.measured.paths, walk_rate / 1e6, bare / 1e6,
                  r.smith_walk ? r.smith_walk->paths / r.model_seconds : 0.0, walk_rate / bare);
    }
  return 0;
}
