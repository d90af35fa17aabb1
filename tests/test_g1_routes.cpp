// measure_g1's fast routes on a heightfield (its rays decoded by the grid walk, in blocks or set
// up ahead; area samples drawn ahead) against the exact route, every ray traced on the
// surface's Scene (G1Options::grid_fast_paths = false): the same counts in every normal bin and
// replicate, on a small periodic tile, a measured window and a tile beyond the caches.
#include <gtest/gtest.h>

#include "microsim/measure/g1_measure.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/guard_band.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/trace/ray_pipeline.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;

namespace {

G1Options route_options(std::uint64_t rays, std::uint64_t seed, bool fast) {
  G1Options o;
  o.rays = rays;
  o.seed = seed;
  o.replicates = 8;
  o.grid_fast_paths = fast;
  return o;
}

// The bins whose per-replicate counts (hits, samples, visible) differ between a and b.
int bins_differing(const G1Result& a, const G1Result& b) {
  int differ = 0;
  for (int k = 0; k < a.binning.size(); ++k)
    differ += a.bins[k].raycast_hits_r != b.bins[k].raycast_hits_r || a.bins[k].samples_r != b.bins[k].samples_r ||
              a.bins[k].visible_r != b.bins[k].visible_r;
  return differ;
}

// The fast routes taken are `route` and `ahead` (g1_raycast_route, g1_draws_ahead), the exact
// ones without grid_fast_paths; every bin's counts of the fast routes equal the exact routes',
// from the zenith to grazing views. Power: the exact route with another seed differs in many
// bins.
void expect_fast_route_equals_scene_route(const Microsurface& s, std::uint64_t rays, G1RaycastRoute route, bool ahead,
                                          const char* what) {
  EXPECT_EQ(g1_raycast_route(s, route_options(rays, 3, true)), route) << what;
  EXPECT_EQ(g1_draws_ahead(s, route_options(rays, 3, true)), ahead) << what;
  EXPECT_EQ(g1_raycast_route(s, route_options(rays, 3, false)), G1RaycastRoute::SceneFirstHit) << what;
  EXPECT_FALSE(g1_draws_ahead(s, route_options(rays, 3, false))) << what;
  const Tracer tracer(s);
  for (double theta : {0.0, 60.0, 85.0}) {
    const Vec3 v = direction_from_angles(rad(theta), 0.4);
    const G1Result fast = measure_g1(tracer, v, route_options(rays, 3, true));
    const G1Result exact = measure_g1(tracer, v, route_options(rays, 3, false));
    const G1Result other = measure_g1(tracer, v, route_options(rays, 4, false));
    EXPECT_EQ(bins_differing(fast, exact), 0) << what << " theta " << theta;
    EXPECT_EQ(fast.raycast_hits, exact.raycast_hits) << what << " theta " << theta;
    EXPECT_EQ(fast.sample_visible, exact.sample_visible) << what << " theta " << theta;
    EXPECT_GT(fast.raycast_hits, 0u);
    EXPECT_GT(bins_differing(exact, other), 3) << what << " theta " << theta;
  }
}

}  // namespace

TEST(G1Routes, SmallTileGridBlocksCountAsTheScene) {
  expect_fast_route_equals_scene_route(beckmann_tile(48, 61, 1.0), 24000, G1RaycastRoute::GridBatched, false, "tile");
}

TEST(G1Routes, WindowGridBlocksCountAsTheScene) {
  Microsurface w = beckmann_tile(48, 17, 1.0);
  apply_guard_band(w, 6, 6, false);  // a measured window: rays end at its side walls
  ASSERT_TRUE(w.macro().region);
  expect_fast_route_equals_scene_route(w, 24000, G1RaycastRoute::GridBatched, false, "window");
}

// A mesh has one route, the Scene's.
TEST(G1Routes, MeshesAreTracedOnTheirScene) {
  const Microsurface m = heightfield_to_mesh(beckmann_tile(16, 5));
  EXPECT_EQ(g1_raycast_route(m, route_options(1000, 1, true)), G1RaycastRoute::SceneFirstHit);
  EXPECT_FALSE(g1_draws_ahead(m, route_options(1000, 1, true)));
}

TEST(G1Routes, LargeTileRaysAndDrawsAheadCountAsTheScene) {
  GaussianParams p;
  p.resolution = 1536;
  p.correlation_length = 4.0 / 1536;
  const Microsurface s = generate_gaussian(p);
  ASSERT_GE(double(s.nx()) * s.ny(), kAheadMinCells);  // the routes set up ahead
  expect_fast_route_equals_scene_route(s, 16000, G1RaycastRoute::GridAhead, true, "large tile");
}
