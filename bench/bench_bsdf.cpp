// Benchmark (not a test): random walks of the BSDF measurement (mirror and dielectric) against a
// bare rtcIntersect1 loop over the very same Embree queries, and the Smith random-walk model's
// walks per second (rows: bench_walks.hpp; microsim_bench --walks prints the same rows per tile).
//   microsim_bench_bsdf [resolution] [paths] [repeat]    (default 1024, 1000000, 3)
#include <cstdio>
#include <cstdlib>

#include "microsim/surface/gaussian.hpp"
#include "microsim/trace/tracer.hpp"
#include "bench_walks.hpp"

using namespace microsim;
using namespace microsim::bench;

int main(int argc, char** argv) {
  const int res = argc > 1 ? std::atoi(argv[1]) : 1024;
  const std::uint64_t paths = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1000000;
  const int repeat = argc > 3 ? std::atoi(argv[3]) : 3;
  GaussianParams p;
  p.resolution = res;
  p.alpha_x = p.alpha_y = 0.5;
  p.correlation_length = 4.0 * p.size / res;
  Microsurface s = generate_gaussian(p);
  Tracer tracer(s);
  std::printf("Gaussian tile %d^2, alpha 0.5, 4 cells per l; %llu paths per row, best of %d\n", res,
              static_cast<unsigned long long>(paths), repeat);
  print_walk_rows(tracer, paths, repeat, true);
  return 0;
}
