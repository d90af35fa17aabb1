// Measured (non-periodic) patches measured as a window with a guard band: the tracer's
// side-wall rule on exact geometry, agreement with the periodic tile restricted to the same
// interior (same sample points) within errors plus the measured bias, the bias of no guard
// at grazing angles (its sign), and refusals.
#include <gtest/gtest.h>

#include "cli_helpers.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/guard_band.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/trace/tracer.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using microsim::testing::Result;
using microsim::testing::run_microsim;

namespace {
std::string tmp(const std::string& name) { return microsim::testing::temp_path("guard", name); }

// A 256^2 Beckmann tile, l = 8 cells (32 l per side).
Microsurface tile256(double alpha) {
  GaussianParams p;
  p.resolution = 256;
  p.alpha_x = p.alpha_y = alpha;
  p.correlation_length = 8.0 / 256;
  p.seed = 11;
  return generate_gaussian(p);
}

struct Pair {
  Estimate window, periodic;
  TraceCounters counters;
};

// G1 at theta (area sampling, or ray casting) on the window and on the periodic tile restricted
// to the same interior cells, same seed (the same sample points).
Pair g1_pair(const Microsurface& tile, int guard_cells, double theta_deg, bool raycast, std::uint64_t rays) {
  Microsurface w = tile, p = tile;
  apply_guard_band(w, guard_cells, guard_cells, false);
  const int cx = tile.nx() - 1;
  p.set_sample_region(guard_cells, cx - guard_cells, guard_cells, cx - guard_cells, true);
  G1Options o;
  o.rays = rays;
  o.seed = 5;
  const Vec3 v = direction_from_angles(rad(theta_deg), 0.3);
  Tracer tw(w), tp(p);
  const G1Result rw = measure_g1(tw, v, o), rp = measure_g1(tp, v, o);
  return {raycast ? rw.g1_raycast() : rw.g1_area_sampling(), raycast ? rp.g1_raycast() : rp.g1_area_sampling(),
          rw.counters};
}

double z_of(const Pair& q) {
  return (q.window.mean - q.periodic.mean) / std::hypot(q.window.stderr_, q.periodic.stderr_);
}
}  // namespace

TEST(GuardBand, RegionFacetsComeFirstAndCoverTheInterior) {
  Microsurface s = microsim::testing::bumpy_heightfield(32, 0.02);
  const std::size_t all = s.num_facets();
  apply_guard_band(s, 5, 3, false);
  EXPECT_EQ(s.num_facets(), 2u * (31 - 10) * (31 - 6));
  EXPECT_DOUBLE_EQ(s.macro().area, (31 - 10) * s.dx() * (31 - 6) * s.dy());
  EXPECT_FALSE(s.macro().periodic);
  EXPECT_FALSE(s.macro().finite_object());
  // facet_index and facet agree for region and guard cells.
  for (long j : {0L, 3L, 17L, 30L})
    for (long i : {0L, 5L, 20L, 30L})
      for (int h = 0; h < 2; ++h) {
        const Triangle t = s.facet(s.facet_index(i, j, h));
        EXPECT_NEAR(t.p0.x(), s.grid_point(i + h, j).x(), 1e-12);
        EXPECT_NEAR(t.p0.y(), s.grid_point(i + h, j).y(), 1e-12);
      }
  EXPECT_LT(s.num_facets(), all);
  const Json& g = s.description["guard_band"];
  EXPECT_EQ(g["cells_x"], 5);
  EXPECT_EQ(g["interior"]["cells_y"], 25);
}

TEST(GuardBand, FlatWindowRaysFromAboveAllHitAndSideWallsEndRays) {
  // A flat window: every ray from above hits its interior (visible area ratio exactly 1);
  // an occlusion ray at grazing height leaves through the side wall (escaped, counted).
  Microsurface s = Microsurface::heightfield(32, 32, 1.0, 1.0, std::vector<float>(32 * 32, 0.0f));
  std::vector<float> h(32 * 32, 0.0f);
  h[5 * 32 + 5] = 0.01f;  // a bump so the slab has a height (no hit is lost to a zero slab)
  s = Microsurface::heightfield(32, 32, 1.0, 1.0, h);
  apply_guard_band(s, 8, 8, false);
  Tracer t(s);
  G1Options o;
  o.rays = 4096;
  o.replicates = 16;
  const G1Result r = measure_g1(t, direction_from_angles(rad(80.0), 1.0), o);
  // Every sample point sees the sky; ray casting counts the interior's hits among the rays
  // of the stretched window, whose expected share is exactly the interior's.
  EXPECT_EQ(r.g1_area_sampling().mean, 1.0);
  const Estimate a = r.g1_raycast();
  EXPECT_LT(std::abs(a.mean - 1.0), 4 * a.stderr_ + 1e-12) << a.mean << " +- " << a.stderr_;
  EXPECT_EQ(r.counters.lost_below, 0u);
  TraceCounters c;
  const Vec3 p(0.0, 0.0, 1e-4), d = direction_from_angles(rad(89.9), 0.0);
  EXPECT_FALSE(t.occluded(p, d, nullptr, c));
  EXPECT_EQ(c.side_exits, 1u);
  // The same ray in the periodic tile wraps around and meets the bump's neighbourhood or
  // leaves through the top; in the window it ends at the wall before.
}

TEST(GuardBand, DefaultGuardAgreesWithThePeriodicTileAtGrazingAngles) {
  // Default guard (kDefaultGuardCorrelationLengths l) on a 256^2 tile, Beckmann 1.0, G1 at 85
  // degrees by area sampling (the quantity most exposed to the missing surroundings): within
  // 3 sigma of both errors plus an allowance of 0.002 for the bias (docs/guide/heightmaps.md table: +0.0007 at
  // 8 l, +0.0019 at 4 l on a 512^2 tile).
  const Microsurface tile = tile256(1.0);
  const int gc = static_cast<int>(std::lround(kDefaultGuardCorrelationLengths * 8));
  const Pair q = g1_pair(tile, gc, 85.0, false, 200000);
  const double se = std::hypot(q.window.stderr_, q.periodic.stderr_);
  EXPECT_LT(std::abs(q.window.mean - q.periodic.mean), 3 * se + 0.002)
      << q.window.mean << " vs " << q.periodic.mean << " +- " << se;
  // Ray casting too (rays from above; side entries are what the guard removes).
  const Pair a = g1_pair(tile, gc, 85.0, true, 200000);
  EXPECT_LT(std::abs(a.window.mean - a.periodic.mean), 3 * std::hypot(a.window.stderr_, a.periodic.stderr_) + 0.002)
      << a.window.mean << " vs " << a.periodic.mean;
}

TEST(GuardBand, NoGuardOverestimatesG1AtGrazingAngles) {
  // Power check: without a guard, sample points near the border see past the missing
  // surroundings (their rays escape through the side wall), so G1 is too high at grazing
  // angles, by area sampling and by ray casting alike (the same rule): many sigma away
  // (docs/guide/heightmaps.md bias table: +0.022 at 512^2, alpha 1, 85 degrees).
  const Microsurface tile = tile256(1.0);
  const Pair q = g1_pair(tile, 0, 85.0, false, 200000);
  EXPECT_GT(z_of(q), 5.0) << q.window.mean << " vs " << q.periodic.mean;
  EXPECT_GT(q.counters.side_exits, 0u);
  const Pair a = g1_pair(tile, 0, 85.0, true, 200000);
  EXPECT_GT(z_of(a), 5.0) << a.window.mean << " vs " << a.periodic.mean;
}

TEST(GuardBand, GuardWiderThanHalfThePatchIsRefused) {
  Microsurface s = microsim::testing::bumpy_heightfield(32, 0.02);
  EXPECT_THROW(apply_guard_band(s, 16, 2, false), UsageError);  // 31 cells: 2 x 16 > 31
  EXPECT_THROW(apply_guard_band(s, -1, 2, false), UsageError);
  // The command: one line naming the option, exit 2, nothing written.
  const Microsurface tile = tile256(0.5);
  const std::string plain = tmp("plain.exr"), out = tmp("w.exr");
  ExrTable z;
  z.width = tile.nx();
  z.height = tile.ny();
  z.channel_names = {"Z"};
  z.channels = {tile.heights()};
  write_exr(plain, z);
  Result r = run_microsim("generate heightmap --input " + plain + " --pixel-size 1 --guard 17 -o " + out);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--guard"), std::string::npos) << r.err;
  EXPECT_FALSE(microsim::testing::exists(out));
  r = run_microsim("generate heightmap --input " + plain + " --pixel-size 1 --guard-width 200 -o " + out);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--guard-width"), std::string::npos) << r.err;
  r = run_microsim("generate heightmap --input " + plain + " --pixel-size 1 --periodic --guard 2 -o " + out);
  EXPECT_EQ(r.code, 2) << r.err;
  // A window measured from the command line carries its guard band in the record.
  r = run_microsim("generate heightmap --input " + plain + " --pixel-size 1 --guard 2 -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string json = tmp("g1.json");
  r = run_microsim("measure g1 " + out + " --theta 70 --rays 20000 -o " + json);
  ASSERT_EQ(r.code, 0) << r.err;
  const Json j = Json::parse(microsim::testing::slurp(json));
  EXPECT_TRUE(j["surface"].contains("guard_band")) << j["surface"].dump();
  EXPECT_GE(j["surface"]["guard_band"]["cells_x"].get<int>(), 1);
  EXPECT_TRUE(j["rows"][0].contains("side_exits"));
}

TEST(GuardBand, BothG1EstimatorsAgreeOnAWindowAtGrazingAngles) {
  // A ray entering the window through a side wall below the surface there meets the solid from
  // behind: a miss, like the reverse ray from the hit point, which area sampling finds
  // occluded. Handled as a graze of a convex edge instead (traced on through the solid), such
  // rays counted as hits and ray casting read +0.0024 above area sampling at 85 degrees here
  // (8 seeds: +0.0018 to +0.0028). Power: that offset is rejected.
  const Microsurface tile = tile256(1.0);
  const int gc = static_cast<int>(std::lround(kDefaultGuardCorrelationLengths * 8));
  Microsurface w = tile;
  apply_guard_band(w, gc, gc, false);
  G1Options o;
  o.rays = 1000000;
  o.seed = 3;
  const Tracer t(w);
  const G1Result r = measure_g1(t, direction_from_angles(rad(85.0), 0.3), o);
  const Estimate a = r.g1_raycast(), b = r.g1_area_sampling();
  const double se = std::hypot(a.stderr_, b.stderr_);
  EXPECT_GT(r.counters.side_entries, 0u);  // the case occurs
  EXPECT_LT(std::abs(a.mean - b.mean), 3.5 * se) << a.mean << " vs " << b.mean << " +- " << se;
  EXPECT_GT(std::abs(a.mean + 0.0024 - b.mean), 3.5 * se);
}
