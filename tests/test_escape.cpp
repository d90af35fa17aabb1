// The walks' escape test (trace/escape_test.hpp): wherever it says a ray leaving a facet meets
// nothing, the tracer's own query finds nothing either, and its no_hit answer is first_hit's
// bit for bit (counters included). Rays start where primary rays hit (the tracer's own rounded
// hit points) and leave on both sides, down to grazing angles. Power: a pyramid lowered by a
// fraction of the heights' spread claims escapes where the tracer hits.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/trace/escape_test.hpp"
#include "microsim/trace/facet_plane.hpp"
#include "test_helpers.hpp"

using namespace microsim;

namespace {

struct Tally {
  long rays = 0, escaped = 0, claimed = 0, wrong = 0, counters_differ = 0;
};

bool same(const TraceCounters& a, const TraceCounters& b) {
  return a.rays == b.rays && a.border_crossings == b.border_crossings && a.lost_below == b.lost_below &&
         a.backface_hits == b.backface_hits && a.unresolved == b.unresolved && a.side_exits == b.side_exits &&
         a.side_entries == b.side_entries;
}

// n primary rays from random points and directions above; from each hit, rays leaving the facet
// on both sides in random directions (a quarter of them within 3 degrees of the facet's plane).
Tally check(const Microsurface& s, const EscapeTest& escape, int n, std::uint64_t seed) {
  Tracer tracer(s);
  const FacetPlanes planes(tracer);
  Tally t;
  const double top = tracer.z_top();
  for (int k = 0; k < n; ++k) {
    CounterRng rng(seed, 77, static_cast<std::uint64_t>(k));
    const double x = (rng.uniform() - 0.5) * s.macro().size_x, y = (rng.uniform() - 0.5) * s.macro().size_y;
    const double ct = 0.05 + 0.95 * rng.uniform(), ph = 2 * kPi * rng.uniform();
    const double st = std::sqrt(1 - ct * ct);
    const Vec3 dir0(st * std::cos(ph), st * std::sin(ph), -ct);
    TraceCounters c0;
    const TraceHit h = tracer.first_hit(Vec3(x, y, top), dir0, nullptr, c0);
    if (!h.hit || h.backface) continue;
    const Vec3 m = h.normal;
    const SourcePlane plane = planes.plane(h.facet);
    for (int side = 0; side < 2; ++side)
      for (int r = 0; r < 8; ++r) {
        // A direction on the chosen side of the facet (d.m > 0 front, < 0 back) and of the
        // macrosurface (up front, down back).
        Vec3 d;
        for (int tries = 0; tries < 100; ++tries) {
          const double z = 2 * rng.uniform() - 1, a = 2 * kPi * rng.uniform(), q = std::sqrt(1 - z * z);
          d = Vec3(q * std::cos(a), q * std::sin(a), z);
          if (r < 2) {  // grazing: within 3 degrees of the facet's plane
            d -= d.dot(m) * m;
            d.normalize();
            d += std::tan(rng.uniform() * 3 * kPi / 180) * (side == 0 ? m : Vec3(-m));
            d.normalize();
          }
          const double dm = d.dot(m);
          if (side == 0 ? (dm > 0 && d.z() > 0) : (dm < 0 && d.z() < 0)) break;
        }
        const RaySide rs = side == 0 ? RaySide::Front : RaySide::Back;
        if (side == 0 ? !(d.dot(m) > 0 && d.z() > 0) : !(d.dot(m) < 0 && d.z() < 0)) continue;
        ++t.rays;
        TraceCounters ct1, ct2;
        const TraceHit ref = tracer.first_hit(h.point, d, &plane, ct1, rs);
        if (!ref.hit) ++t.escaped;
        if (!escape.clear(h.point, d, h.facet, rs)) continue;
        ++t.claimed;
        if (ref.hit) ++t.wrong;
        const TraceHit mine = escape.no_hit(h.point, d, ct2, rs);
        if (!ref.hit && (mine.exit_below != ref.exit_below || mine.hit || !same(ct1, ct2))) ++t.counters_differ;
      }
  }
  return t;
}

struct Case {
  const char* name;
  Microsurface surface;
};

std::vector<Case> surfaces() {
  std::vector<Case> cases;
  auto gauss = [](int res, double ax, double ay, double cl, std::uint64_t seed) {
    GaussianParams p;
    p.resolution = res;
    p.alpha_x = ax;
    p.alpha_y = ay;
    p.correlation_length = cl;
    p.seed = seed;
    return generate_gaussian(p);
  };
  cases.push_back({"beckmann 0.5, 64^2", gauss(64, 0.5, 0.5, 4.0 / 64, 3)});
  cases.push_back({"beckmann 1.0, 48^2", gauss(48, 1.0, 1.0, 4.0 / 48, 4)});
  cases.push_back({"anisotropic 0.2 x 0.9, 64^2", gauss(64, 0.2, 0.9, 8.0 / 64, 5)});
  cases.push_back({"bumpy 32^2", microsim::testing::bumpy_heightfield(32, 0.08)});
  cases.push_back({"flat 16^2", Microsurface::heightfield(16, 16, 1.0, 1.0, std::vector<float>(256, 0.25f))});
  return cases;
}

}  // namespace

TEST(EscapeTest, NeverClaimsAnEscapeWhereTheTracerHits) {
  for (const Case& c : surfaces()) {
    Tracer tracer(c.surface);
    const EscapeTest escape(tracer);
    ASSERT_TRUE(escape.applies()) << c.name;
    const Tally t = check(c.surface, escape, 1500, 11);
    std::printf("%-28s rays %ld, escaped %ld, claimed %ld (%.0f%% of escapes), margin %.2g\n", c.name, t.rays,
                t.escaped, t.claimed, 100.0 * t.claimed / std::max(1L, t.escaped), escape.margin());
    EXPECT_EQ(t.wrong, 0) << c.name;
    EXPECT_EQ(t.counters_differ, 0) << c.name;
    // Not vacuous: most escapes are proven (the flat plane: every ray escapes).
    EXPECT_GT(t.claimed, t.escaped / 2) << c.name;
  }
}

TEST(EscapeTest, LoweredPyramidClaimsWrongEscapes) {
  // Power: block bounds lowered by 0.3 of the heights' spread are proven wrong by the tracer.
  const Case c = surfaces()[0];
  const std::vector<float>& h = c.surface.heights();
  double m = 0, m2 = 0;
  for (float v : h) m += v;
  m /= h.size();
  for (float v : h) m2 += (v - m) * (v - m);
  const double sd = std::sqrt(m2 / h.size());
  Tracer tracer(c.surface);
  const EscapeTest wrong(tracer, 0.3 * sd);
  const Tally t = check(c.surface, wrong, 1500, 11);
  EXPECT_GT(t.wrong, 0);
}

TEST(EscapeTest, OnlyPeriodicHeightfieldTiles) {
  // A finite object (a box, a mesh): the test never applies and never claims an escape.
  const Microsurface box = generate_box(BoxParams{});
  Tracer tracer(box);
  const EscapeTest escape(tracer);
  EXPECT_FALSE(escape.applies());
  EXPECT_FALSE(escape.clear(Vec3(0, 0, 0.5), Vec3(0, 0, 1), 0, RaySide::Front));
}
