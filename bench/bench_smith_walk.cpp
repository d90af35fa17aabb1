// The Smith random-walk model column's cost per walk, single thread: the walk with forced continuation and
// its weight window (smith_walk_expected_path, as measure bsdf's error-target mode runs it) and the tally of
// its escapes, on the Beckmann alpha 0.5 NDF, mirror, at several incidences. For a profiler:
//   microsim_bench_smith_walk [walks per incidence = 200000] [resolution = 32]
#include <cstdio>
#include <cstdlib>

#include "bench_common.hpp"
#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/smith_walk_budget.hpp"

using namespace microsim;

int main(int argc, char** argv) {
  const std::uint64_t n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 200000;
  const int resolution = argc > 2 ? std::atoi(argv[2]) : 32;
  const int K = 4;
  const models::Ndf ndf = models::Ndf::beckmann(0.5, 0.5);
  const models::SmithRandomWalk walk =
      models::SmithRandomWalk(ndf, models::Material::mirror(), models::HeightDistribution::Uniform, 1000)
          .with_fast_slope_sampler();
  BsdfResult r;
  r.options.orders = K;
  r.map = HemisphereMap(resolution);
  r.plane = InPlaneBins(0.0, resolution);
  double total = 0.0;
  std::printf("theta_deg  ns/walk  events/walk\n");
  for (double theta : {0.0, 30.0, 60.0, 80.0}) {
    r.wi = direction_from_angles(theta * kPi / 180.0, 0.0);
    const WalkWindow window = walk_window(walk, r.wi, K, 1, 7);
    const WalkNet net = walk_net(1, 7, 0, n);
    BsdfTally t(K, r.map.size(), r.plane.size());
    const double c0 = bench::cpu_seconds();
    for (std::uint64_t j = 0; j < n; ++j) smith_walk_expected_path(walk, r.wi, 1, 7, j, net, r, t, window);
    const double s = bench::cpu_seconds() - c0;
    total += s;
    std::printf("%9.0f  %7.1f  %11.3f\n", theta, 1e9 * s / static_cast<double>(n),
                static_cast<double>(t.events) / static_cast<double>(n));
  }
  std::printf("total %.3f s CPU\n", total);
  return 0;
}
