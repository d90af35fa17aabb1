// Tracing layer: Embree's grid triangulation equals the surface's facets, periodic wrap-around
// loses and double-counts no ray, self-intersection handling does not depend on offsets.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/trace/facet_plane.hpp"
#include "microsim/trace/tile_border.hpp"
#include "microsim/trace/tracer.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;

namespace {
// Height of the piecewise-linear periodic heightfield at (x, y), from its own triangulation.
double surface_height(const Microsurface& s, double x, double y) {
  double gx = (x + 0.5 * s.macro().size_x) / s.dx(), gy = (y + 0.5 * s.macro().size_y) / s.dy();
  long i = static_cast<long>(std::floor(gx)), j = static_cast<long>(std::floor(gy));
  double fx = gx - i, fy = gy - j;
  double h00 = s.height(i, j), h10 = s.height(i + 1, j), h01 = s.height(i, j + 1),
         h11 = s.height(i + 1, j + 1);
  if (fx + fy <= 1) return h00 + fx * (h10 - h00) + fy * (h01 - h00);
  return h11 + (1 - fx) * (h01 - h11) + (1 - fy) * (h10 - h11);
}

// Independent reference: march along the ray in double precision in steps of 1/1024 cell and
// bisect the first sign change of z(t) - h(x(t), y(t)). (Steps of 1/16 cell stepped over a
// grazing ray that clips a crest by less than a step, and reported the hit behind it.)
double reference_hit_distance(const Microsurface& s, const Vec3& o, const Vec3& d) {
  double step = std::min(s.dx(), s.dy()) / 1024 / std::max(1e-3, std::hypot(d.x(), d.y()));
  auto f = [&](double t) { Vec3 p = o + t * d; return p.z() - surface_height(s, p.x(), p.y()); };
  double t0 = 0, f0 = f(0);
  for (int k = 1; k < 50000000; ++k) {
    double t1 = k * step, f1 = f(t1);
    if ((f0 > 0) != (f1 > 0)) {
      for (int b = 0; b < 60; ++b) {
        double tm = 0.5 * (t0 + t1);
        if ((f(tm) > 0) == (f0 > 0)) t0 = tm; else t1 = tm;
      }
      return 0.5 * (t0 + t1);
    }
    t0 = t1;
    f0 = f1;
  }
  return -1;
}
}  // namespace

TEST(Tracer, EmbreeGridTriangulationMatchesSurfaceFacets) {
  Microsurface s = bumpy_heightfield(32, 0.03);
  Tracer tracer(s);
  TraceCounters c;
  for (int k = 0; k < 2000; ++k) {
    CounterRng rng(1, 1, k);
    // Draws in named variables, in a fixed order: argument evaluation order is unspecified.
    const double ox = rng.uniform() - 0.5, oy = rng.uniform() - 0.5;
    const double ut = rng.uniform(), up = rng.uniform();
    Vec3 o(ox, oy, tracer.z_top());
    Vec3 d = -direction_from_angles(rad(60 * ut), 2 * kPi * up);
    TraceHit h = tracer.first_hit(o, d, nullptr, c);
    ASSERT_TRUE(h.hit);
    Triangle f = s.facet(h.facet);
    // The hit point (or its periodic copy) lies in the plane of the reported facet, within
    // the facet's cell, and on the heightfield.
    double best = 1e9;
    for (int sx = -1; sx <= 1; ++sx)
      for (int sy = -1; sy <= 1; ++sy) {
        Vec3 p = h.point + Vec3(sx, sy, 0);
        Vec3 centroid = (f.p0 + f.p1 + f.p2) / 3;
        if ((p - centroid).head<2>().norm() < 2 * s.dx())
          best = std::min(best, std::abs(f.normal().dot(p - f.p0)));
      }
    EXPECT_LT(best, 1e-5);
    EXPECT_NEAR(h.point.z(), surface_height(s, h.point.x(), h.point.y()), 1e-5);
  }
  EXPECT_EQ(c.lost_below, 0u);
}

TEST(Tracer, FirstHitMatchesIndependentMarchAcrossManyTileBorders) {
  // Rays at 70..89 degrees travel up to ~50 tiles horizontally before they hit.
  Microsurface s = bumpy_heightfield(24, 0.02);
  Tracer tracer(s);
  TraceCounters c;
  for (int k = 0; k < 60; ++k) {
    CounterRng rng(2, 2, k);
    double theta = rad(70 + 19 * rng.uniform());
    Vec3 d = -direction_from_angles(theta, 2 * kPi * rng.uniform());
    // Named draws: the order of evaluation of constructor arguments is unspecified (GCC and
    // clang draw them in opposite orders), so one seed must not depend on the compiler.
    const double ox = rng.uniform() - 0.5, oy = rng.uniform() - 0.5;
    const Vec3 o(ox, oy, tracer.z_top() + 0.5 * rng.uniform());
    TraceHit h = tracer.first_hit(o, d, nullptr, c);
    ASSERT_TRUE(h.hit) << k;
    double t_ref = reference_hit_distance(s, o, d);
    // Distance along the ray from the height alone (the hit point is wrapped into the tile);
    // the wrapped horizontal position must be the reference's modulo whole tiles.
    double t_hit = (h.point.z() - o.z()) / d.z();
    Vec3 p_ref = o + t_ref * d;
    for (int c = 0; c < 2; ++c) {
      double diff = h.point[c] - p_ref[c];
      EXPECT_NEAR(diff - std::round(diff), 0.0, 1e-4) << "ray " << k;
    }
    EXPECT_NEAR(t_hit, t_ref, 1e-4 * std::max(1.0, t_ref)) << "ray " << k;
  }
  EXPECT_GT(c.border_crossings, 100u);
  EXPECT_EQ(c.lost_below + c.unresolved, 0u);
}

TEST(Tracer, FlatPlaneAt89DegreesEveryRayHitsOnce) {
  Microsurface s = flat_heightfield(8);
  Tracer tracer(s);
  TraceCounters c;
  const int n = 20000;
  int hits = 0;
  for (int k = 0; k < n; ++k) {
    CounterRng rng(3, 3, k);
    Vec3 d = -direction_from_angles(rad(89.0), 2 * kPi * rng.uniform());
    const double ox = rng.uniform() - 0.5, oy = rng.uniform() - 0.5;
    Vec3 o(ox, oy, 0.2);  // ~11 tiles of travel
    TraceHit h = tracer.first_hit(o, d, nullptr, c);
    hits += h.hit && !h.backface;
    EXPECT_NEAR(h.point.z(), 0.0, 1e-6);
  }
  EXPECT_EQ(hits, n);
  EXPECT_EQ(c.lost_below + c.unresolved + c.backface_hits, 0u);
  EXPECT_GT(c.border_crossings, static_cast<std::uint64_t>(5 * n));
}

TEST(Tracer, RaysAlongTileBordersAreNotLost) {
  Microsurface s = bumpy_heightfield(16, 0.02);
  Tracer tracer(s);
  TraceCounters c;
  for (double y : {-0.5, 0.5, 0.0}) {
    for (double theta : {80.0, 88.0, 89.5}) {
      Vec3 d = -direction_from_angles(rad(theta), 0.0);  // along x, exactly on y = border
      TraceHit h = tracer.first_hit(Vec3(0.1, y, tracer.z_top()), d, nullptr, c);
      EXPECT_TRUE(h.hit);
      Vec3 d2 = -direction_from_angles(rad(theta), kPi / 2);  // along y on x = border
      TraceHit h2 = tracer.first_hit(Vec3(y, 0.1, tracer.z_top()), d2, nullptr, c);
      EXPECT_TRUE(h2.hit);
    }
  }
  EXPECT_EQ(c.lost_below + c.unresolved, 0u);
}

TEST(Tracer, SelfIntersectionIndependentOfOriginOffset) {
  // Occlusion rays leaving a flat plane or a V-groove facet toward the open side must never be
  // blocked by the facet they leave, whatever the offset along the normal (0 .. 1e-3).
  for (int shape = 0; shape < 2; ++shape) {
    Microsurface s = shape == 0 ? flat_heightfield(16) : vgroove_heightfield(8, 4, rad(30));
    Tracer tracer(s);
    for (double offset : {0.0, 1e-7, 1e-5, 1e-3}) {
      TraceCounters c;
      int blocked = 0;
      for (int k = 0; k < 4000; ++k) {
        CounterRng rng(4, 4, k);
        std::size_t f = static_cast<std::size_t>(rng.uniform() * s.num_facets());
        Triangle t = s.facet(f);
        double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
        Vec3 p = t.point(r1 * (1 - r2), r1 * r2) + offset * t.normal();
        // Directions that leave the facet unobstructed: on the plane, any azimuth at 89.9 deg;
        // on the groove, along the grooves at 89.9 deg (the cross-section never changes) or
        // along the facet normal (steeper than the opposite wall).
        Vec3 m = t.normal();
        Vec3 d = shape == 0       ? direction_from_angles(rad(89.9), 2 * kPi * rng.uniform())
                 : k % 2 == 0 ? direction_from_angles(rad(89.9), k % 4 == 0 ? kPi / 2 : -kPi / 2)
                              : m;
        ASSERT_GT(d.dot(m), 0);
        SourcePlane plane = SourcePlane::of(t);
        blocked += tracer.occluded(p, d, &plane, c);
      }
      EXPECT_EQ(blocked, 0) << "shape " << shape << " offset " << offset;
    }
  }
}

TEST(Tracer, PeriodicMeshTracesLikeTheHeightfield) {
  Microsurface s = bumpy_heightfield(24, 0.03);
  Microsurface m = heightfield_to_mesh(s);
  Tracer ts(s), tm(m);
  TraceCounters c;
  for (int k = 0; k < 500; ++k) {
    CounterRng rng(5, 5, k);
    const double ut = rng.uniform(), up = rng.uniform();
    const double ox = rng.uniform() - 0.5, oy = rng.uniform() - 0.5;
    Vec3 d = -direction_from_angles(rad(85 * ut), 2 * kPi * up);
    Vec3 o(ox, oy, ts.z_top());
    TraceHit a = ts.first_hit(o, d, nullptr, c), b = tm.first_hit(o, d, nullptr, c);
    ASSERT_TRUE(a.hit && b.hit);
    EXPECT_EQ(a.facet, b.facet);
    EXPECT_NEAR((a.point - b.point).norm(), 0.0, 1e-5);
  }
}

TEST(Tracer, GrazingRayOverARidgeIsNeverABackFaceHit) {
  // A ray from above that passes a V-groove's ridge closer than float spacing (~6e-8 at the
  // ridge height 0.5) may be reported by Embree on the far facet's back face; geometrically it
  // either meets the near facet (below the ridge) or passes over it, and both give a front-face
  // hit. Every ray here must hit a front face. (The sweep passes with or without the handling:
  // which rays Embree misreports depends on float details; the recorded rays below fail without
  // it.)
  VGrooveParams vp;
  vp.facet_angle_deg = 45.0;  // ridge at x = 0, z = 0.5; valleys at the tile borders
  Microsurface s = generate_vgroove(vp);
  Tracer tracer(s);
  TraceCounters c;
  int front = 0, n = 0;
  for (double theta : {70.0, 80.0, 88.0}) {
    const Vec3 d = -direction_from_angles(rad(theta), 0.0);  // toward -x, across the ridge
    for (int k = -2000; k <= 2000; ++k) {
      CounterRng rng(5, 5, static_cast<std::uint64_t>(k + 2000));
      const Vec3 ridge(0.0, rng.uniform() - 0.5, 0.5 + 1e-10 * k);  // +-2e-7 about the ridge
      const Vec3 o = ridge - ((tracer.z_top() - ridge.z()) / d.z()) * d;
      const TraceHit h = tracer.first_hit(o, d, nullptr, c);
      front += h.hit && !h.backface;
      ++n;
    }
  }
  // Rays of `measure bsdf` (seed 1, 400000 rays) that a tracer without this handling reported
  // on a back face at the ridge: {facet angle, origin, light direction l}.
  const double cases[][7] = {
      {45, 2.7306282389671921e-06, 0.10699511465661271, 0.50000100000000003, 0.93969262078590832, 0, 0.34202014332566882},
      {60, 2.6949246065055554e-05, 0.48881965725233778, 0.86602638824081424, 0.99939082701909576, 0, 0.03489949670250108},
      {60, 2.7314555690161058e-05, -0.024109637388424365, 0.86602638824081424, 0.99939082701909576, 0, 0.03489949670250108},
      {60, 2.6603486676823884e-05, 0.33716616585804116, 0.86602638824081424, 0.99939082701909576, 0, 0.03489949670250108},
      {70, -1.9525588331625876e-05, -0.11841549403437363, 1.3737401394553184, -0.49969541350954766, 0.86549784450767653, 0.03489949670250108},
      {70, -1.8678949746553375e-05, -0.3990192085391111, 1.3737401394553184, -0.49969541350954766, 0.86549784450767653, 0.03489949670250108},
      {70, -2.0368414300475646e-05, 0.46953791317863569, 1.3737401394553184, -0.49969541350954766, 0.86549784450767653, 0.03489949670250108},
      {70, -1.8663975677180034e-05, -0.36124000856961025, 1.3737401394553184, -0.49969541350954766, 0.86549784450767653, 0.03489949670250108},
      {70, 1.6070840747395287e-05, -0.22420472555814064, 1.3737401394553184, 0.99619469809174555, 0, 0.087155742747658138}};
  for (const auto& k : cases) {
    vp.facet_angle_deg = k[0];
    Microsurface g = generate_vgroove(vp);
    Tracer t(g);
    const TraceHit h = t.first_hit(Vec3(k[1], k[2], k[3]), -Vec3(k[4], k[5], k[6]), nullptr, c);
    front += h.hit && !h.backface;
    ++n;
  }
  EXPECT_EQ(front, n);
  EXPECT_EQ(c.backface_hits + c.lost_below + c.unresolved, 0u);
}

TEST(Tracer, FrontFacetEqualsFirstHitFacet) {
  // The primary-ray path (Tracer::front_facet) must give, ray for ray, the facet first_hit
  // reports when its front face is met first, and the same counters: on a rough tile (back
  // faces at silhouettes, many wrap-arounds at grazing views), on a region of a periodic tile
  // (facet numbering of the region), on a non-periodic window (the general path) and on rays
  // grazing a V-groove's ridge (back-face first hits traced again).
  struct Case {
    Microsurface s;
    std::vector<double> thetas;
    bool ridge = false;
  };
  std::vector<Case> cases;
  cases.push_back({beckmann_tile(64, 3, 1.0), {0.0, 45.0, 70.0, 85.0, 89.0}});
  Microsurface region = beckmann_tile(64, 4, 0.5);
  region.set_sample_region(8, 40, 16, 48, true);
  cases.push_back({std::move(region), {0.0, 60.0, 85.0}});
  Microsurface window = beckmann_tile(64, 5, 0.5);
  window.set_sample_region(4, 60, 4, 60, false);
  cases.push_back({std::move(window), {0.0, 60.0}});
  VGrooveParams vp;
  vp.facet_angle_deg = 60.0;
  cases.push_back({generate_vgroove(vp), {70.0, 80.0, 88.0}, true});
  std::uint64_t compared = 0, hits = 0, differ_perturbed = 0;
  for (const Case& cs : cases) {
    Tracer tracer(cs.s);
    const bool vgroove = cs.ridge;
    for (double theta : cs.thetas)
      for (int k = 0; k < 3000; ++k) {
        CounterRng rng(11, 7, static_cast<std::uint64_t>(k));
        const Vec3 v = direction_from_angles(rad(theta), vgroove ? 0.0 : 2 * kPi * rng.uniform());
        const double ox = rng.uniform() - 0.5, oy = rng.uniform() - 0.5;
        Vec3 o(ox, oy, tracer.z_top());
        if (vgroove) {  // within +-2e-7 of the ridge (x = 0, z at the top), as in the test above
          const Vec3 ridge(0.0, o.y(), tracer.z_top() - 1e-6 + 1e-10 * (k - 1500));
          o = ridge + ((tracer.z_top() - ridge.z()) / v.z()) * v;
        }
        TraceCounters c1, c2, c3;
        const TraceHit h = tracer.first_hit(o, -v, nullptr, c1);
        const std::size_t expected = h.hit && !h.backface ? h.facet : DownwardRays::kNone;
        const std::size_t got = tracer.front_facet(DownwardRays(tracer, v), o, c2);
        ASSERT_EQ(got, expected) << "theta " << theta << " ray " << k;
        for (auto [a, b] : {std::pair{c1.rays, c2.rays}, {c1.border_crossings, c2.border_crossings},
                            {c1.lost_below, c2.lost_below}, {c1.backface_hits, c2.backface_hits},
                            {c1.unresolved, c2.unresolved}, {c1.side_exits, c2.side_exits},
                            {c1.side_entries, c2.side_entries}})
          ASSERT_EQ(a, b) << "theta " << theta << " ray " << k;
        // Power: the same comparison against a direction 1e-3 rad away does see differences.
        const Vec3 vp2 = direction_from_angles(rad(theta) + 1e-3, vgroove ? 0.0 : phi_of(v));
        differ_perturbed += tracer.front_facet(DownwardRays(tracer, vp2), o, c3) != expected;
        ++compared;
        hits += expected != DownwardRays::kNone;
      }
  }
  EXPECT_GT(hits, compared / 2);
  EXPECT_GT(differ_perturbed, compared / 100);
  // Rays that a tracer without the back-face handling reported on a back face at a ridge
  // (GrazingRayOverARidgeIsNeverABackFaceHit): {facet angle, origin, v}.
  const double ridge_cases[][7] = {
      {45, 2.7306282389671921e-06, 0.10699511465661271, 0.50000100000000003, 0.93969262078590832, 0, 0.34202014332566882},
      {60, 2.6949246065055554e-05, 0.48881965725233778, 0.86602638824081424, 0.99939082701909576, 0, 0.03489949670250108},
      {70, -1.9525588331625876e-05, -0.11841549403437363, 1.3737401394553184, -0.49969541350954766, 0.86549784450767653, 0.03489949670250108}};
  for (const auto& k : ridge_cases) {
    vp.facet_angle_deg = k[0];
    const Microsurface g = generate_vgroove(vp);
    const Tracer t(g);
    TraceCounters c1, c2;
    const Vec3 o(k[1], k[2], k[3]), v(k[4], k[5], k[6]);
    const TraceHit h = t.first_hit(o, -v, nullptr, c1);
    ASSERT_TRUE(h.hit && !h.backface);
    EXPECT_EQ(t.front_facet(DownwardRays(t, v), o, c2), h.facet);
    EXPECT_EQ(c1.rays, c2.rays);
    EXPECT_EQ(c2.backface_hits, 0u);
  }
}

namespace {
// The origin of a ray along -v aimed where a hit's grid coordinates round across a border:
// kind 0 a uniform point (the origin on the slab's top), 1 Embree's float vertex (i, j), 2 a
// point of the x border from it, 3 of the y border, 4 of the cell's diagonal; a, b pick the
// cell and t the point along the edge.
Vec3 aimed_origin(const Microsurface& s, const Tracer& tracer, const Vec3& v, int kind, double a,
                  double b, double t) {
  auto fpoint = [&](long i, long j) {  // Embree's vertex (i, j): float x, y, z
    const Vec3 p = s.grid_point(i, j);
    return Vec3(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  };
  const long i = static_cast<long>(a * s.nx()), j = static_cast<long>(b * s.ny());
  Vec3 p;
  switch (kind) {
    case 0: return Vec3(a - 0.5, b - 0.5, tracer.z_top());
    case 1: p = fpoint(i, j); break;
    case 2: p = fpoint(i, j) + t * (fpoint(i + 1, j) - fpoint(i, j)); break;
    case 3: p = fpoint(i, j) + t * (fpoint(i, j + 1) - fpoint(i, j)); break;
    default: p = fpoint(i + 1, j) + t * (fpoint(i, j + 1) - fpoint(i + 1, j)); break;
  }
  return p + ((tracer.z_top() - p.z()) / v.z()) * v;
}

// The counters front_facet and first_hit both keep must agree.
void expect_same_counters(const TraceCounters& e, const TraceCounters& c, const std::string& where) {
  for (auto [x, y] : {std::pair{e.rays, c.rays}, {e.border_crossings, c.border_crossings},
                      {e.lost_below, c.lost_below}, {e.backface_hits, c.backface_hits},
                      {e.unresolved, c.unresolved}})
    ASSERT_EQ(x, y) << where;
}
}  // namespace

TEST(Tracer, FrontFacetFastDecodingEqualsCheckedDecoding) {
  // front_facet names most hits from Embree's grid coordinates and the sign of its float normal
  // alone (DownwardRays::band, graze), and leaves hits near a cell's borders or diagonal, and
  // grazing ones, to the checked decoding (the facet whose exact normal is aligned with Ng).
  // Both must give the same facet and counters on every ray: uniform origins, and rays aimed
  // exactly at Embree's float vertices and at points of shared edges (cell borders and
  // diagonals), where the grid coordinates round across a border. Tiles: rough, smooth
  // (neighbours nearly coplanar), flat (coplanar), 256^2 (a wider band), a sample region.
  // Power: the decoding without its band and grazing limit (every hit named from u, v and Ng
  // alone) must disagree on the rays aimed at edges.
  std::vector<Microsurface> surfaces;
  surfaces.push_back(beckmann_tile(64, 21, 0.5));
  surfaces.push_back(beckmann_tile(64, 22, 1.0));
  surfaces.push_back(bumpy_heightfield(32, 0.03));
  surfaces.push_back(flat_heightfield(16));
  surfaces.push_back(beckmann_tile(256, 23, 0.5));
  surfaces.push_back(beckmann_tile(64, 24, 0.5));
  surfaces.back().set_sample_region(8, 40, 16, 48, true);
  std::uint64_t compared = 0, hits = 0, naive_differ = 0, naive_differ_uniform = 0;
  for (std::size_t si = 0; si < surfaces.size(); ++si) {
    const Microsurface& s = surfaces[si];
    const Tracer tracer(s);
    for (double theta : {0.0, 30.0, 60.0, 85.0, 89.0})
      for (int k = 0; k < 4000; ++k) {
        CounterRng rng(31, 100 * si + static_cast<std::uint64_t>(theta), static_cast<std::uint64_t>(k));
        const double phi = 2 * kPi * rng.uniform();
        const Vec3 v = direction_from_angles(rad(theta), phi);
        const double a = rng.uniform(), b = rng.uniform(), t = rng.uniform();
        const int kind = k % 5;
        const Vec3 o = aimed_origin(s, tracer, v, kind, a, b, t);
        DownwardRays fast(tracer, v), checked(tracer, v), naive(tracer, v);
        checked.exact_decode = true;
        naive.band = 0;
        naive.graze = 0;
        TraceCounters c1, c2, c3;
        const std::size_t expected = tracer.front_facet(checked, o, c1);
        const std::size_t got = tracer.front_facet(fast, o, c2);
        const std::string where = "surface " + std::to_string(si) + " theta " + std::to_string(theta) +
                                  " ray " + std::to_string(k);
        ASSERT_EQ(got, expected) << where;
        expect_same_counters(c1, c2, where);
        if (HasFatalFailure()) return;
        const bool differ = tracer.front_facet(naive, o, c3) != expected;
        naive_differ += differ;
        naive_differ_uniform += differ && kind == 0;
        hits += expected != DownwardRays::kNone;
        ++compared;
      }
  }
  EXPECT_GT(hits, compared * 9 / 10);
  EXPECT_GT(naive_differ, compared / 100);  // power: a decoding without the band is wrong there
  EXPECT_LT(naive_differ_uniform, naive_differ / 10);  // (and rarely on uniform rays)
}

TEST(Tracer, FrontFacetsInBlocksEqualFirstHit) {
  // Tracer::front_facets traces a block of rays at a time (origins, then queries, then hits):
  // ray for ray it must give the facet first_hit reports when its front face is met first, and
  // the same counters. Rays: uniform origins and rays aimed at Embree's float vertices, cell
  // borders and diagonals (the checked decoding), at 0 to 89 degrees (wrap-arounds, misses in
  // the first segment, back faces at silhouettes), on a rough tile, a smooth one and a region
  // of a tile; blocks of 32 and of 7 (a partial last block). Power: the same comparison with a
  // decoding without its band and grazing limit (hits named from u, v and Ng alone) fails.
  std::vector<Microsurface> surfaces;
  surfaces.push_back(beckmann_tile(64, 41, 1.0));
  surfaces.push_back(beckmann_tile(32, 42, 0.3));
  surfaces.push_back(beckmann_tile(64, 43, 0.5));
  surfaces.back().set_sample_region(8, 40, 16, 48, true);
  std::uint64_t compared = 0, hits = 0, crossed = 0, naive_differ = 0;
  for (std::size_t si = 0; si < surfaces.size(); ++si) {
    const Microsurface& s = surfaces[si];
    const Tracer tracer(s);
    for (double theta : {0.0, 45.0, 70.0, 85.0, 89.0}) {
      const Vec3 v = direction_from_angles(rad(theta), 0.7 + si);
      const int n = 1500;
      std::vector<Vec3> orgs(n);
      for (int k = 0; k < n; ++k) {
        CounterRng rng(51, 100 * si + static_cast<std::uint64_t>(theta), static_cast<std::uint64_t>(k));
        const double a = rng.uniform(), b = rng.uniform(), t = rng.uniform();
        const int kind = k % 4 == 3 ? 4 : k % 4;  // uniform, vertex, x border, diagonal
        orgs[k] = aimed_origin(s, tracer, v, kind, a, b, t);
      }
      std::vector<std::size_t> expected(n);
      std::vector<TraceCounters> c_expected(n);
      for (int k = 0; k < n; ++k) {
        const TraceHit h = tracer.first_hit(orgs[k], -v, nullptr, c_expected[k]);
        expected[k] = h.hit && !h.backface ? h.facet : DownwardRays::kNone;
      }
      // front_facets with the given rays; facets and counters per ray.
      auto blocks = [&](const DownwardRays& down, int batch, std::vector<TraceCounters>& c) {
        std::vector<std::size_t> got(n, 12345);
        c.assign(n, TraceCounters{});
        std::vector<int> order;
        auto origin = [&](std::size_t k) { return orgs[k]; };
        auto counters = [&](std::size_t k) -> TraceCounters& { return c[k]; };
        auto use = [&](std::size_t k, std::size_t f) {
          got[k] = f;
          order.push_back(static_cast<int>(k));
        };
        if (batch == 7) tracer.front_facets<7>(down, n, origin, counters, use);
        else tracer.front_facets(down, n, origin, counters, use);
        for (int k = 0; k < n; ++k) EXPECT_EQ(order[k], k);  // in order, each once
        return got;
      };
      const DownwardRays down(tracer, v);
      for (int batch : {32, 7}) {
        std::vector<TraceCounters> c;
        const std::vector<std::size_t> got = blocks(down, batch, c);
        for (int k = 0; k < n; ++k) {
          const std::string where = "surface " + std::to_string(si) + " theta " +
                                    std::to_string(theta) + " ray " + std::to_string(k);
          ASSERT_EQ(got[k], expected[k]) << where;
          expect_same_counters(c_expected[k], c[k], where);
          if (HasFatalFailure()) return;
        }
      }
      DownwardRays naive(tracer, v);
      naive.band = 0;
      naive.graze = 0;
      std::vector<TraceCounters> c;
      const std::vector<std::size_t> perturbed = blocks(naive, 32, c);
      for (int k = 0; k < n; ++k) {
        naive_differ += perturbed[k] != expected[k];
        hits += expected[k] != DownwardRays::kNone;
        crossed += c_expected[k].border_crossings > 0;
        ++compared;
      }
    }
  }
  EXPECT_GT(hits, compared * 9 / 10);
  EXPECT_GT(crossed, compared / 20);  // wrap-arounds: first segments that missed
  EXPECT_GT(naive_differ, compared / 100);  // power
}

TEST(Tracer, FacetTriangleEqualsMicrosurfaceFacet) {
  // The walks' plane of the facet a ray leaves (facet_plane) must be bit for bit the one
  // Microsurface::facet gives, on a tile, on a region of it (facets renumbered) and on a window.
  std::vector<Microsurface> surfaces;
  surfaces.push_back(beckmann_tile(16, 2));
  surfaces.push_back(beckmann_tile(16, 3));
  surfaces.back().set_sample_region(3, 11, 5, 14, true);
  surfaces.push_back(beckmann_tile(16, 4));
  surfaces.back().set_sample_region(2, 13, 1, 12, false);
  int differ_next = 0, compared_next = 0, n = 0;
  for (const Microsurface& s : surfaces) {
    // With a region, every cell's facets follow the region's (named by tracer hits).
    const std::size_t end = s.num_facets() + (s.has_region() ? 2 * static_cast<std::size_t>(s.nx()) * s.ny() : 0);
    const Tracer tracer(s);
    const FacetPlanes planes = tracer.facet_planes();
    for (std::size_t k = 0; k < end; ++k) {
      const Triangle a = s.facet(k), b = facet_triangle(s, k);
      ASSERT_EQ(a.p0, b.p0) << k;
      ASSERT_EQ(a.p1, b.p1) << k;
      ASSERT_EQ(a.p2, b.p2) << k;
      const SourcePlane pa = SourcePlane::of(a), pb = facet_plane(s, k);
      ASSERT_EQ(pa.normal, pb.normal);
      ASSERT_EQ(pa.offset, pb.offset);
      // From the tracer's grid vertices, for every facet it can report (a window traces the
      // cells between its vertices only).
      const std::size_t cell = k < s.num_facets() || !s.has_region() ? 0 : (k - s.num_facets()) / 2;
      const bool traced = s.macro().periodic || k < s.num_facets() ||
                          (static_cast<long>(cell % s.nx()) < s.nx() - 1 &&
                           static_cast<long>(cell / s.nx()) < s.ny() - 1);
      if (traced) {
        const Triangle c = planes.triangle(k);
        ASSERT_EQ(a.p0, c.p0) << k;
        ASSERT_EQ(a.p1, c.p1) << k;
        ASSERT_EQ(a.p2, c.p2) << k;
      }
      // Power: the neighbouring facet's plane is another one.
      if (k + 1 < s.num_facets()) {
        differ_next += !(SourcePlane::of(s.facet(k + 1)).normal == pb.normal);
        ++compared_next;
      }
      ++n;
    }
  }
  EXPECT_GT(n, 1000);
  EXPECT_GT(differ_next, compared_next * 9 / 10);
}

TEST(Tracer, PrefetchFrontNamesTheCellWhereTheRayCrossesTheMeanHeight) {
  // prefetch_front (a hint for memory only) must name the cell where the ray crosses the mean
  // height: on a rough tile seen from the zenith the cell of the facet front_facet finds (same
  // x, y); on a flat tile at 0.2 seen at 60 and 85 degrees from 0.05 above it that same cell
  // (2.8 and 18 cells over, wrapped); also in the numbering of a sample region. Power: the
  // guess for the vertical ray through the same origin (or, seen from the zenith, for the
  // origin one cell over) names another cell.
  struct Case {
    Microsurface s;
    double theta, lift;
  };
  std::vector<Case> cases;
  cases.push_back({beckmann_tile(64, 3, 0.5), 0.0, 0.0});
  const Microsurface flat = Microsurface::heightfield(32, 32, 1.0, 1.0, std::vector<float>(32 * 32, 0.2f));
  cases.push_back({flat, 60.0, 0.05});
  cases.push_back({flat, 85.0, 0.05});
  Microsurface region = beckmann_tile(64, 4, 0.5);
  region.set_sample_region(8, 40, 16, 48, true);
  cases.push_back({std::move(region), 0.0, 0.0});
  for (const Case& cs : cases) {
    Tracer tracer(cs.s);
    int compared = 0, same = 0, same_wrong = 0;
    for (int k = 0; k < 2000; ++k) {
      CounterRng rng(5, 3, static_cast<std::uint64_t>(k));
      const double phi = 2 * kPi * rng.uniform();
      const Vec3 v = direction_from_angles(rad(cs.theta), phi);
      const Vec3 o(rng.uniform() - 0.5, rng.uniform() - 0.5, tracer.z_top() + cs.lift);
      const DownwardRays down(tracer, v), vertical(tracer, Vec3(0, 0, 1));
      TraceCounters c;
      const std::size_t f = tracer.front_facet(down, o, c);
      if (f == DownwardRays::kNone) continue;
      ++compared;
      same += tracer.prefetch_front(down, o) / 2 == f / 2;
      const std::size_t wrong = cs.theta > 0 ? tracer.prefetch_front(vertical, o)
                                             : tracer.prefetch_front(down, o + Vec3(cs.s.dx(), 0, 0));
      same_wrong += wrong / 2 == f / 2;
    }
    EXPECT_GT(compared, 1900) << "theta " << cs.theta;
    EXPECT_GE(same, compared - 2) << "theta " << cs.theta;  // rounding exactly at a cell border
    EXPECT_LT(same_wrong, compared / 10) << "theta " << cs.theta;
  }
}

// ---------------------------------------------------------------------------------------------
// The walks' decisions without divisions and square roots (Tracer::trace, the filter): each
// fast test implies the exact one on random and border inputs, and with its margin perturbed
// it does not (the inputs reach the border closely enough to show the margin is needed).
// ---------------------------------------------------------------------------------------------

namespace {
// Offsets from a border: on it, a few ulps, and up to 1e-9 relative either side.
std::vector<double> relative_offsets() {
  std::vector<double> o = {0.0};
  for (double e : {1e-16, 2.2e-16, 4.4e-16, 1e-15, 1e-14, 1e-13, 1e-12, 3e-12, 1e-11, 1e-9}) {
    o.push_back(e);
    o.push_back(-e);
  }
  return o;
}
}  // namespace

TEST(Tracer, ReachesBeforeBorderOnlyWhenTheBorderQuotientSaysSo) {
  std::mt19937_64 g(41);
  std::uniform_real_distribution<double> u(-1, 1);
  const std::vector<double> off = relative_offsets();
  long claimed = 0, wrong_perturbed = 0, far_claimed = 0, far = 0;
  for (double hx : {0.5, 3.7, 1e-3})
    for (int k = 0; k < 200000; ++k) {
      const double hy = hx * (k % 3 == 0 ? 1.0 : 0.37);
      Vec3 o(hx * u(g), hy * u(g), u(g));
      if (k % 7 == 0) o.x() = hx;  // on the border
      Vec3 d(u(g), u(g), u(g));
      if (k % 5 == 0) d.x() = 0;
      if (k % 11 == 0) d.y() = -0.0;
      d.normalize();
      const double exact = distance_to_tile_border(o, d, hx, hy);
      // t at the border distance (and a few ulps to 1e-9 off it), or anywhere below.
      const double t = k % 2 == 0 ? exact * (1 + off[k / 2 % off.size()]) : std::abs(u(g)) * exact;
      if (!std::isfinite(t)) continue;
      if (reaches_before_border(o, d, hx, hy, t)) {
        ++claimed;
        ASSERT_GE(exact, t) << o.transpose() << " | " << d.transpose();
      }
      if (reaches_before_border(o, d, hx, hy, t, -kBorderMargin) && !(exact >= t)) ++wrong_perturbed;
      if (t < 0.99 * exact) {
        ++far;
        if (reaches_before_border(o, d, hx, hy, t)) ++far_claimed;
      }
    }
  EXPECT_GT(claimed, 100000);
  EXPECT_EQ(far_claimed, far);     // it decides every case not within the margin
  EXPECT_GT(wrong_perturbed, 0);   // power: a reversed margin claims wrong ones
}

TEST(Tracer, NotParallelClearlyOnlyWhenTheQuotientSaysSo) {
  // a = |ng.n| and len2 = |ng|^2 around the threshold a / |ng| = 1 - 1e-6, and the same for a
  // normal within the slack: every clear answer must be the quotient's for every normal within
  // the slack, i.e. hold with a raised by slack * |ng|.
  std::mt19937_64 g(42);
  std::uniform_real_distribution<double> u(0, 1);
  const std::vector<double> off = relative_offsets();
  long clear = 0, wrong_perturbed = 0, wrong_slack = 0;
  for (int k = 0; k < 2000000; ++k) {
    const double len2 = std::ldexp(0.5 + u(g), static_cast<int>(u(g) * 200) - 100);
    const double len = std::sqrt(len2);
    const double e = off[k % off.size()] + (k % 3 == 0 ? (u(g) - 0.5) * 1e-6 : 0.0);
    const double a = (1 - 1e-6) * (1 + e) * len;
    if (not_parallel_clearly(a, len2, 0.0)) {
      ++clear;
      ASSERT_TRUE(not_parallel_exactly(a, len2)) << a << " " << len2;
    }
    if (not_parallel_clearly(a, len2, kReportedNormalSlack)) {
      ASSERT_TRUE(not_parallel_exactly(a + kReportedNormalSlack * len, len2));
    }
    if (not_parallel_clearly(a, len2, 0.0, -1e-9) && !not_parallel_exactly(a, len2)) ++wrong_perturbed;
    if (not_parallel_clearly(a, len2, 0.0) && !not_parallel_exactly(a + kReportedNormalSlack * len, len2))
      ++wrong_slack;
  }
  EXPECT_GT(clear, 100000);
  EXPECT_GT(wrong_perturbed, 0);  // power: a reversed margin claims wrong ones
  EXPECT_GT(wrong_slack, 0);      // and the reported normal's slack is needed
  // Underflowing squares are never decided on.
  EXPECT_FALSE(not_parallel_clearly(1e-170, 1e-300, 0.0));
}

TEST(Tracer, ReportedNormalIsWithinItsSlackOfThePlaneNormal) {
  // TraceHit::normal (the cell sizes) against SourcePlane::of (the corners' coordinates) for
  // the same facet, on square, anisotropic and very wide grids, a region and a window.
  std::vector<Microsurface> surfaces;
  surfaces.push_back(beckmann_tile(64, 51, 1.0));
  std::mt19937_64 g(43);
  std::normal_distribution<double> n;
  {
    const int nx = 16384, ny = 3;
    std::vector<float> h(static_cast<std::size_t>(nx) * ny);
    for (float& x : h) x = static_cast<float>(3e-4 * n(g));
    surfaces.push_back(Microsurface::heightfield(nx, ny, 7.3, 0.0123, std::move(h)));
  }
  {
    const int nx = 37, ny = 300;
    std::vector<float> h(static_cast<std::size_t>(nx) * ny);
    for (float& x : h) x = static_cast<float>(0.05 * n(g));
    surfaces.push_back(Microsurface::heightfield(nx, ny, 1.1, 0.3, std::move(h)));
  }
  surfaces.push_back(beckmann_tile(32, 52));
  surfaces.back().set_sample_region(3, 27, 5, 20, true);
  surfaces.push_back(beckmann_tile(32, 53));
  surfaces.back().set_sample_region(2, 29, 1, 30, false);
  double worst = 0;
  for (const Microsurface& s : surfaces) {
    const Tracer tracer(s);
    const FacetPlanes planes = tracer.facet_planes();
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    int hits = 0;
    for (int k = 0; k < 20000; ++k) {
      const Vec3 o(u(g) * s.macro().size_x, u(g) * s.macro().size_y, tracer.z_top());
      TraceCounters c;
      const TraceHit h = tracer.first_hit(o, Vec3(0.05, -0.03, -1).normalized(), nullptr, c);
      if (!h.hit) continue;
      ++hits;
      worst = std::max(worst, (h.normal - planes.plane(h.facet).normal).cwiseAbs().maxCoeff());
    }
    EXPECT_GT(hits, 5000);
  }
  EXPECT_LT(worst, kReportedNormalSlack / 100) << worst;
  EXPECT_GT(worst, 0.0);  // power: the two normals differ, the slack is needed
}

TEST(Tracer, LeavingAFacetEqualsLeavingItsPlane) {
  // first_hit with SourceFacet (the plane formed only near parallel) against first_hit with
  // SourcePlane::of the facet: the same TraceHit and counters, bit for bit, for rays leaving
  // hit facets by reflection, at random, grazing (n.dir from 1e-9 on) and into the solid
  // (Back side). Power: with a normal tilted by 1e-2 (beyond the slack) the hits differ.
  std::vector<Microsurface> surfaces;
  surfaces.push_back(beckmann_tile(64, 61, 1.0));
  surfaces.push_back(bumpy_heightfield(48, 0.02));
  surfaces.push_back(vgroove_heightfield(8, 4, 0.6));
  {  // an inclined plane (coplanar neighbours everywhere; a cliff at the tile border)
    const int nn = 32;
    std::vector<float> h(nn * nn);
    for (int j = 0; j < nn; ++j)
      for (int i = 0; i < nn; ++i) h[j * nn + i] = static_cast<float>(0.3 * i / nn + 0.1 * j / nn);
    surfaces.push_back(Microsurface::heightfield(nn, nn, 1.0, 1.0, std::move(h)));
  }
  surfaces.push_back(beckmann_tile(32, 62));
  surfaces.back().set_sample_region(2, 29, 1, 30, false);
  std::mt19937_64 g(44);
  std::uniform_real_distribution<double> u(0, 1);
  long compared = 0, differ_tilted = 0;
  for (const Microsurface& s : surfaces) {
    const Tracer tracer(s);
    for (int k = 0; k < 4000; ++k) {
      const Vec3 o((u(g) - 0.5) * s.macro().size_x, (u(g) - 0.5) * s.macro().size_y, tracer.z_top());
      TraceCounters c0;
      const TraceHit h = tracer.first_hit(o, Vec3(0.2 * (u(g) - 0.5), 0.2 * (u(g) - 0.5), -1).normalized(),
                                          nullptr, c0);
      if (!h.hit || h.backface) continue;
      const Vec3& m = h.normal;
      const Vec3 t1 = (std::abs(m.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(m).normalized();
      const Vec3 t2 = m.cross(t1);
      const double psi = 2 * kPi * u(g);
      const Vec3 along = std::cos(psi) * t1 + std::sin(psi) * t2;
      for (int variant = 0; variant < 6; ++variant) {
        double lift;  // n.dir
        switch (variant) {
          case 0: lift = 1e-9; break;
          case 1: lift = 1e-7; break;
          case 2: lift = 1e-5; break;
          case 3: lift = 1e-3; break;
          default: lift = u(g); break;
        }
        const bool back = variant == 5;
        Vec3 dir = (std::sqrt(1 - lift * lift) * along + (back ? -lift : lift) * m).normalized();
        const RaySide side = back ? RaySide::Back : RaySide::Front;
        const SourcePlane plane = tracer.facet_planes().plane(h.facet);
        TraceCounters c1, c2, c3;
        const TraceHit a = tracer.first_hit(h.point, dir, &plane, c1, side);
        const TraceHit b = tracer.first_hit(h.point, dir, SourceFacet{h.facet, h.normal}, c2, side);
        ASSERT_EQ(a.hit, b.hit);
        ASSERT_EQ(a.exit_below, b.exit_below);
        ASSERT_EQ(a.point, b.point);
        ASSERT_EQ(a.normal, b.normal);
        ASSERT_EQ(a.facet, b.facet);
        ASSERT_EQ(a.backface, b.backface);
        ASSERT_EQ(c1.rays, c2.rays);
        ASSERT_EQ(c1.border_crossings, c2.border_crossings);
        ASSERT_EQ(c1.lost_below, c2.lost_below);
        ASSERT_EQ(c1.backface_hits, c2.backface_hits);
        ASSERT_EQ(c1.side_exits, c2.side_exits);
        ++compared;
        const Vec3 tilted = (h.normal + 1e-2 * along).normalized();
        const TraceHit w = tracer.first_hit(h.point, dir, SourceFacet{h.facet, tilted}, c3, side);
        if (w.hit != a.hit || w.facet != a.facet || w.point != a.point) ++differ_tilted;
      }
    }
  }
  EXPECT_GT(compared, 50000);
  EXPECT_GT(differ_tilted, 0);
}
