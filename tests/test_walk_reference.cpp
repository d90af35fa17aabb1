// Mirror random walks of the BSDF estimator (measure/bsdf_walk.cpp, Embree) against an
// independent double-precision tracer over the same triangles (reference_heightfield_tracer.hpp):
// the scattering order of every path, including the orders >= 4 that on rough Gaussian tiles far
// exceed the Smith walk's (docs/theory/discretization.md), belongs to the surface, not to the
// tracer's offsets, filters, ridge retrace or periodic seams.
#include <gtest/gtest.h>

#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/surface/gaussian.hpp"
#include "reference_heightfield_tracer.hpp"

using namespace microsim;

namespace {

struct Comparison {
  int paths = 0, different = 0, order4_library = 0, order4_reference = 0;
};

// Paths from uniform points above the tile along -wi (theta_i in degrees, phi_i = 0), traced by
// walk_bsdf_path and by the reference; counts the paths whose order or fate differ.
Comparison compare_walks(const Microsurface& s, const ReferenceHeightfieldTracer& ref,
                         const std::vector<double>& thetas, int paths) {
  Tracer tracer(s);
  const models::Material mirror = models::Material::mirror();
  Comparison c;
  for (double th_deg : thetas) {
    const double th = th_deg * kPi / 180.0;
    const Vec3 wi(std::sin(th), 0.0, std::cos(th));
    for (int p = 0; p < paths; ++p) {
      CounterRng rng(11, static_cast<std::uint64_t>(th_deg), static_cast<std::uint64_t>(p));
      const double ox = rng.uniform() - 0.5, oy = rng.uniform() - 0.5;  // fixed draw order
      const Vec3 origin(ox, oy, tracer.z_top());
      TraceCounters counters;
      std::uint64_t events = 0;
      const WalkEnd e = walk_bsdf_path(tracer, origin, -wi, mirror, rng, 1000, false, counters, events);
      const ReferenceHeightfieldTracer::Walk w = ref.mirror_walk(origin, -wi, 1000);
      ++c.paths;
      if (e.order != w.order || (e.kind != WalkEnd::Reflected) != w.lost) ++c.different;
      if (e.kind == WalkEnd::Reflected && e.order >= 4) ++c.order4_library;
      if (!w.lost && w.order >= 4) ++c.order4_reference;
    }
  }
  return c;
}

Microsurface rough_tile() {
  GaussianParams p;
  p.resolution = 128;
  p.correlation_length = 16.0 / 128;  // 16 cells per l, 8 l per tile
  p.alpha_x = p.alpha_y = 1.0;
  p.seed = 3;
  return generate_gaussian(p);
}

}  // namespace

// Measured with analysis/walk_audit: 9 of 5.4e6 paths (alpha = 1; 8, 16, 32 cells per l;
// theta_i = 0, 60, 80 deg) differ, each first at a hit within 1e-3 cells of a facet edge, where
// float hit points and double ones fall on different sides (both ways: 3 higher, 6 lower orders).
// 60000 paths expect 0.1 such.
TEST(MirrorWalkReference, OrdersEqualAnIndependentTracer) {
  const Microsurface s = rough_tile();
  const ReferenceHeightfieldTracer ref(s);
  const Comparison c = compare_walks(s, ref, {0.0, 60.0, 80.0}, 20000);
  EXPECT_LE(c.different, 2) << "of " << c.paths;
  // The sample holds the high orders in question (about 0.4% of the paths).
  EXPECT_GE(c.order4_library, 100);
  EXPECT_NEAR(c.order4_library, c.order4_reference, 2);
}

// Power: the same comparison against a surface split along the other diagonal of every cell (the
// same heights, different triangles) must see the difference.
TEST(MirrorWalkReference, ADifferentTriangulationIsNoticed) {
  const Microsurface s = rough_tile();
  const ReferenceHeightfieldTracer other(s, /*other_diagonal=*/true);
  const Comparison c = compare_walks(s, other, {60.0}, 5000);
  EXPECT_GT(c.different, 100) << "of " << c.paths;
}
