// Uses the installed library the way an outside project would: generate a small Beckmann tile,
// check [GeomBSDF24, eq. 1c] on its facets, and measure G1 by ray casting. On a periodic heightfield every
// ray cast from above hits exactly once, so the ray-casting G1 equals 1/(1+Lambda) from the
// facets up to rounding of the float geometry (docs/theory/masking.md): a check that
// the installed tracer and estimator work, not of Smith's theory.
#include <cmath>
#include <cstdio>

#include "microsim/measure/g1_measure.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/heightmap_import.hpp"
#include "microsim/trace/tracer.hpp"

// With an image's path: also reads it through the library's image-reader module, which the
// installed package must find from this program (outside microsim's trees).
int main(int argc, char** argv) {
  using namespace microsim;
  GaussianParams p;
  p.resolution = 64;
  p.alpha_x = p.alpha_y = 0.5;
  p.seed = 3;
  validate(p);
  const Microsurface s = generate_gaussian(p);
  const FacetSums f = facet_sums(s);
  const double eq_1c = std::abs(f.sum_area_cos / s.macro().area - 1.0);  // [GeomBSDF24, eq. 1c]

  const Tracer tracer(s);
  G1Options o;
  o.rays = 20000;
  o.seed = 4;
  o.replicates = 8;
  const Vec3 v = direction_from_angles(rad(60.0), 0.0);
  const G1Result r = measure_g1(tracer, v, o);
  const double raycast = r.g1_raycast().mean, smith = 1.0 / (1.0 + r.lambda_numeric);
  const Estimate sampled = r.g1_area_sampling();
  std::printf("facets %zu, eq. 1c |error| %.3g\n", s.num_facets(), eq_1c);
  std::printf("G1(60 deg): ray casting %.9f, 1/(1+Lambda) %.9f (|difference| %.2g), area sampling %.5f +- %.5f, lost %llu\n",
              raycast, smith, std::abs(raycast - smith), sampled.mean, sampled.stderr_,
              static_cast<unsigned long long>(r.counters.lost_below + r.counters.unresolved));
  const bool ok = s.num_facets() == 2u * 64 * 64 && eq_1c < 1e-9 &&
                  std::abs(raycast - smith) < 1e-6 && r.counters.lost_below + r.counters.unresolved == 0 &&
                  sampled.mean > 0 && sampled.mean < 1;
  bool image_ok = true;
  if (argc > 1) {
    const RawHeightGrid g = read_height_grid(argv[1]);
    image_ok = g.nx > 0 && g.ny > 0 && g.z.size() == static_cast<std::size_t>(g.nx) * g.ny;
    std::printf("%s: %s %dx%d, channel %s\n", argv[1], g.format.c_str(), g.nx, g.ny, g.channel.c_str());
  }
  std::printf("%s\n", ok && image_ok ? "ok" : "FAILED");
  return ok && image_ok ? 0 : 1;
}
