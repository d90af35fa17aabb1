// Tests of the BSDF random-walk estimator (measure/bsdf_measure.hpp) and of the tracer's
// back-side rays it relies on: exact cases (flat plane: Fresnel; V-groove: orders by geometry),
// conservation (no path lost, R + T = 1), the equal-area map and in-plane bins, thread-count
// independence, and reciprocity of measured tables ([GeomBSDF24, eq. 4c], with eta^2 for transmission).
#include <gtest/gtest.h>

#include "microsim/validate/validate.hpp"
#include "microsim/measure/stats.hpp"

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/bsdf_record.hpp"
#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/measure/groove_models.hpp"
#include "microsim/models/vgroove_multiple.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/surface_io.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;
namespace mm = microsim::models;

namespace {

using microsim::sidak_z;  // microsim/measure/stats.hpp

BsdfOptions options(const mm::Material& m, double theta_deg, double phi_deg, std::uint64_t rays, int res = 16) {
  BsdfOptions o;
  o.material = m;
  o.theta_i = rad(theta_deg);
  o.phi_i = rad(phi_deg);
  o.rays = rays;
  o.resolution = res;
  return o;
}

// The surface seen from below: heights negated (z -> -z).
Microsurface flipped(const Microsurface& s) {
  std::vector<float> h = s.heights();
  for (float& x : h) x = -x;
  return Microsurface::heightfield(s.nx(), s.ny(), s.macro().size_x, s.macro().size_y, std::move(h));
}

}  // namespace

TEST(HemisphereMap, EqualAreaAndExactCosIntegrals) {
  for (int R : {1, 2, 7, 16}) {
    HemisphereMap map(R);
    double total = 0.0;
    for (int px = 0; px < map.size(); ++px) total += map.pixel_cos_integral(px);
    EXPECT_NEAR(total, kPi, 1e-12) << R;  // int_hemisphere cos = pi
    // Each pixel against brute-force midpoint quadrature of |cos| (pi/2 da db).
    for (int px = 0; px < map.size(); ++px) {
      const int i = px % R, j = px / R, n = 400;
      const double h = 2.0 / R;
      double s = 0.0;
      for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
          const double u = -1 + (i + (a + 0.5) / n) * h, v = -1 + (j + (b + 0.5) / n) * h;
          s += map.from_square(u, v).z();
        }
      const double brute = s * (h / n) * (h / n) * 0.5 * kPi;  // midpoint error ~1e-5 relative
      EXPECT_NEAR(map.pixel_cos_integral(px), brute, 3e-5 * brute) << R << " " << px;
    }
  }
  // Round trips and pixel lookup; the map preserves area (solid angle of a pixel = 2 pi / R^2,
  // checked by sampling directions uniformly on the hemisphere).
  HemisphereMap map(8);
  CounterRng rng(1, 2, 3);
  std::vector<int> count(map.size(), 0);
  const int n = 400000;
  for (int k = 0; k < n; ++k) {
    const double z = rng.uniform(), phi = 2 * kPi * rng.uniform(), r = std::sqrt(1 - z * z);
    const Vec3 d(r * std::cos(phi), r * std::sin(phi), z);
    const Vec2 sq = map.to_square(d);
    ASSERT_LT((map.from_square(sq.x(), sq.y()) - d).norm(), 1e-12);
    ++count[map.pixel_of(d)];
    EXPECT_EQ(map.pixel_of(d), map.pixel_of(Vec3(d.x(), d.y(), -d.z())));
  }
  const double p = 1.0 / map.size(), zmax = sidak_z(0.01, map.size());
  for (int c : count) EXPECT_LT(std::abs(c - n * p) / std::sqrt(n * p * (1 - p)), zmax);
}

TEST(InPlaneBins, GeometryAndExactCosIntegral) {
  const double phi_i = rad(30);
  InPlaneBins bins(phi_i, 12);
  const Vec3 l = direction_from_angles(rad(40), phi_i);
  const Vec3 spec(-l.x(), -l.y(), l.z());
  const int b = bins.bin_of(spec);
  ASSERT_GE(b, 0);
  EXPECT_GT(bins.psi_center(b), 0.0);  // specular side is positive
  EXPECT_LE(bins.psi_lo(b), rad(40) + 1e-12);
  EXPECT_GE(bins.psi_hi(b), rad(40) - 1e-12);
  EXPECT_LT(bins.psi_center(bins.bin_of(l)), 0.0);  // back toward the light: negative
  EXPECT_EQ(bins.bin_of(direction_from_angles(rad(40), phi_i + kPi / 2)), -1);  // out of the band
  for (int k = 0; k < bins.size(); ++k) {
    for (double beta : {-0.9, 0.0, 0.9})
      for (bool above : {true, false}) {
        const Vec3 d = bins.direction(bins.psi_center(k), beta * bins.half_width(), above);
        EXPECT_EQ(bins.bin_of(d), k);
        EXPECT_EQ(d.z() > 0, above);
      }
    // cos-weighted average of 1 is 1, and the exact integral matches a midpoint sum.
    EXPECT_NEAR(bins.cos_weighted_average(k, true, [](const Vec3&) { return 1.0; }), 1.0, 1e-14);
    const int n = 300;
    double s = 0.0;
    for (int a = 0; a < n; ++a)
      for (int c = 0; c < n; ++c) {
        const double psi = bins.psi_lo(k) + (a + 0.5) / n * (bins.psi_hi(k) - bins.psi_lo(k));
        const double beta = -bins.half_width() + (c + 0.5) / n * 2 * bins.half_width();
        s += std::abs(bins.direction(psi, beta, true).z()) * std::cos(beta);
      }
    s *= (bins.psi_hi(k) - bins.psi_lo(k)) / n * 2 * bins.half_width() / n;
    EXPECT_NEAR(bins.cos_integral(k), s, 1e-6);
  }
}

TEST(BsdfMeasure, FlatDielectricIsFresnel) {
  // [GeomBSDF24, eq. 7d / 10b]: a flat interface reflects F and transmits 1 - F, all in order 1.
  Microsurface s = flat_heightfield(16);
  Tracer tracer(s);
  std::vector<double> zs;
  double sum_rf = 0, sum_ff = 0;  // weighted least squares of R = s F, weights 1 / stderr^2
  for (double eta : {1.5, 1.0 / 1.5})
    for (double theta : {0.0, 30.0, 60.0, 80.0}) {
      const BsdfResult r = measure_bsdf(tracer, options(mm::Material::dielectric(eta), theta, 10.0, 400000));
      const double F = mm::fresnel_dielectric_unpolarized(std::cos(rad(theta)), eta);
      EXPECT_EQ(r.measured.lost, 0u);
      const Estimate R = r.albedo(0, 4), T = r.albedo(1, 4);
      EXPECT_NEAR(R.mean + T.mean, 1.0, 1e-12);
      EXPECT_EQ(r.albedo(0, 0).mean, R.mean);  // order 1 only
      EXPECT_EQ(r.albedo(1, 0).mean, T.mean);
      if (F == 1.0) {
        EXPECT_EQ(R.mean, 1.0);  // total internal reflection (beyond 41.8 deg for 1/1.5)
        continue;
      }
      zs.push_back((R.mean - F) / R.stderr_);
      sum_rf += R.mean * F / (R.stderr_ * R.stderr_);
      sum_ff += F * F / (R.stderr_ * R.stderr_);
      // The transmitted rays leave in the refracted direction [GeomBSDF24, eq. 15a], reflected specularly.
      Vec3 t;
      ASSERT_TRUE(mm::refract(r.wi, Vec3::UnitZ(), 1.0 / eta, &t));
      const int bt = r.plane.bin_of(t), br = r.plane.bin_of(Vec3(-r.wi.x(), -r.wi.y(), r.wi.z()));
      EXPECT_NEAR(r.f_plane(1, 4, bt).mean * r.plane.cos_integral(bt), T.mean, 1e-12);
      EXPECT_NEAR(r.f_plane(0, 4, br).mean * r.plane.cos_integral(br), R.mean, 1e-12);
    }
  const double zmax = sidak_z(0.01, static_cast<int>(zs.size()) + 1);
  for (double z : zs) EXPECT_LT(std::abs(z), zmax);
  EXPECT_GT(zs.size(), 5u);
  // The scale s of R = s F over all cases (its error 1/sqrt(sum F^2/se^2)) is 1; power: a
  // Fresnel factor 1% wrong (s = 1.01) is rejected at the same threshold.
  const double s_hat = sum_rf / sum_ff, s_se = 1 / std::sqrt(sum_ff);
  EXPECT_LT(std::abs(s_hat - 1) / s_se, zmax) << s_hat << " +- " << s_se;
  EXPECT_GT(std::abs(s_hat - 1.01) / s_se, zmax) << "no power against a 1% wrong Fresnel: +- " << s_se;
  EXPECT_GT(std::abs(s_hat - 0.99) / s_se, zmax) << s_se;
}

TEST(BsdfMeasure, FlatConductorAndMirrorAreExact) {
  Microsurface s = flat_heightfield(8);
  Tracer tracer(s);
  const BsdfResult c = measure_bsdf(tracer, options(mm::Material::conductor(0.2, 3.4), 50.0, 0.0, 20000));
  const double F = mm::fresnel_conductor(std::cos(rad(50)), 0.2, 3.4).unpolarized();
  EXPECT_NEAR(c.albedo(0, 4).mean, F, 1e-12);
  EXPECT_NEAR(c.albedo(0, 4).stderr_, 0.0, 1e-9);
  const BsdfResult m = measure_bsdf(tracer, options(mm::Material::mirror(), 0.0, 0.0, 20000));
  EXPECT_EQ(m.albedo(0, 0).mean, 1.0);
  const int px = m.map.pixel_of(Vec3::UnitZ());
  EXPECT_NEAR(m.f_pixel(0, 4, px).mean * m.map.pixel_cos_integral(px), 1.0, 1e-12);
}

TEST(BsdfMeasure, VGrooveOrdersByGeometry) {
  // Mirror V-grooves with facet angle t in (30, 45) deg at normal incidence: a ray hitting a
  // facet at distance x from the valley reflects toward the other facet and hits it iff
  // x < W (4 sin^2 t - 1) (2D geometry), then leaves: order 2 with probability 4 sin^2 t - 1.
  for (double tdeg : {35.0, 40.0}) {
    Microsurface s = vgroove_heightfield(16, 16, rad(tdeg));
    Tracer tracer(s);
    const BsdfResult r = measure_bsdf(tracer, options(mm::Material::mirror(), 0.0, 0.0, 200000));
    const double t = rad(tdeg), p2 = 4 * std::sin(t) * std::sin(t) - 1;
    EXPECT_EQ(r.measured.lost, 0u);
    EXPECT_EQ(r.albedo(0, 4).mean, 1.0);
    const Estimate e2 = r.albedo(0, 1);
    EXPECT_LT(std::abs(e2.mean - p2) / e2.stderr_, 3.5) << tdeg << ": " << e2.mean << " vs " << p2;
    EXPECT_EQ(r.albedo(0, 2).mean, 0.0);
    // Order-1 rays leave at 2t from the normal, order-2 rays at 180 - 4t (symmetric on both sides).
    const int b1 = r.plane.bin_of(direction_from_angles(2 * t, 0.0));
    const int b1m = r.plane.bin_of(direction_from_angles(2 * t, kPi));
    EXPECT_NEAR(r.f_plane(0, 0, b1).mean * r.plane.cos_integral(b1) +
                    r.f_plane(0, 0, b1m).mean * r.plane.cos_integral(b1m),
                r.albedo(0, 0).mean, 1e-12);
    const int b2 = r.plane.bin_of(direction_from_angles(kPi - 4 * t, 0.0));
    const int b2m = r.plane.bin_of(direction_from_angles(kPi - 4 * t, kPi));
    EXPECT_NEAR(r.f_plane(0, 1, b2).mean * r.plane.cos_integral(b2) +
                    r.f_plane(0, 1, b2m).mean * r.plane.cos_integral(b2m),
                r.albedo(0, 1).mean, 1e-12);
  }
}

TEST(BsdfMeasure, DielectricConservesEnergyOnRoughSurfaces) {
  // Both sides of the interface, total internal reflection, exits below: no path is lost.
  Microsurface s = bumpy_heightfield(64, 0.08);
  Tracer tracer(s);
  for (double eta : {1.5, 1.0 / 1.5})
    for (double theta : {0.0, 70.0}) {
      const BsdfResult r = measure_bsdf(tracer, options(mm::Material::dielectric(eta), theta, 20.0, 100000));
      EXPECT_EQ(r.measured.lost, 0u);
      EXPECT_EQ(r.measured.unterminated, 0u);
      EXPECT_EQ(r.measured.counters.backface_hits, 0u);
      EXPECT_NEAR(r.albedo(0, 4).mean + r.albedo(1, 4).mean, 1.0, 1e-12);
      EXPECT_GT(r.albedo(1, 1).mean + r.albedo(0, 1).mean, 0.0);  // multiple scattering happens
    }
}

TEST(BsdfMeasure, PeriodicMeshTracesLikeTheHeightfield) {
  // The same facets as Embree triangles (with their periodic copies) instead of a grid: the
  // back-side rays of a dielectric see the same faces, the albedos agree path by path up to
  // rounding (same random numbers).
  Microsurface h = bumpy_heightfield(32, 0.06);
  Microsurface m = heightfield_to_mesh(h);
  Tracer th(h), tm(m);
  for (double eta : {1.5, 1.0 / 1.5}) {
    const BsdfOptions o = options(mm::Material::dielectric(eta), 50.0, 30.0, 50000);
    const BsdfResult a = measure_bsdf(th, o), b = measure_bsdf(tm, o);
    EXPECT_EQ(b.measured.lost, 0u);
    EXPECT_EQ(b.measured.counters.backface_hits, 0u);
    EXPECT_NEAR(b.albedo(0, 4).mean + b.albedo(1, 4).mean, 1.0, 1e-12);
    for (int side = 0; side < 2; ++side)
      for (int k = 0; k <= 4; ++k) EXPECT_NEAR(a.albedo(side, k).mean, b.albedo(side, k).mean, 1e-3) << side << k;
  }
}

TEST(BsdfMeasure, IndependentOfThreadCount) {
  Microsurface s = bumpy_heightfield(64, 0.08);
  Tracer tracer(s);
  BsdfOptions o = options(mm::Material::conductor(0.2, 3.4), 45.0, 0.0, 50000);
  BsdfResult a, b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a = measure_bsdf(tracer, o);
  }
  b = measure_bsdf(tracer, o);
  EXPECT_EQ(a.measured.albedo, b.measured.albedo);  // bitwise
  EXPECT_EQ(a.measured.pix, b.measured.pix);
  EXPECT_EQ(a.measured.plane2, b.measured.plane2);
}

// The replicates' walks run several at a time (measure_bsdf keeps both threads busy when a
// replicate has few chunks), yet every replicate's sums are formed as in one replicate after the
// other: per chunk of 8192 paths in path order from zero, a batch's two chunks (above 64 chunks
// a replicate has batches of two) added left to right, the batches added in order to a zero
// tally, then add_replicate in replicate order. Rebuilt here from the walks themselves, the
// sums must agree bitwise; the same chunks added in another order must not (power check).
namespace {
BsdfTally sequential_reference(const Tracer& tracer, const BsdfOptions& o, bool reversed_chunks) {
  const Vec3 wi = direction_from_angles(o.theta_i, o.phi_i);
  const RayWindow window = make_ray_window(tracer, wi);
  const ReplicatePlan plan(o.rays, o.replicates);
  const HemisphereMap map(o.resolution);
  const InPlaneBins bins(o.phi_i, o.resolution);
  const int K = o.orders, npix = map.size(), nplane = bins.size();
  const std::uint64_t stream = 0xB5DF0000ull +
                               static_cast<std::uint64_t>(static_cast<std::int64_t>(o.theta_i * 1e6)) * 7919 +
                               static_cast<std::uint64_t>(static_cast<std::int64_t>(o.phi_i * 1e6));
  const std::uint64_t n = plan.per_replicate(), chunk = 8192, nchunks = (n + chunk - 1) / chunk;
  const std::uint64_t batches = std::min<std::uint64_t>(nchunks, 64);
  BsdfTally total(K, npix, nplane);
  for (int q = 0; q < plan.replicates; ++q) {
    std::vector<BsdfTally> chunks;
    for (std::uint64_t c = 0; c < nchunks; ++c) {
      BsdfTally t(K, npix, nplane);
      for (std::uint64_t i = c * chunk; i < std::min(n, (c + 1) * chunk); ++i) {
        CounterRng rng(o.seed, ReplicatePlan::stream(stream, q), i);
        ++t.paths;
        const Vec2 ab = plan.strata.point(i, rng);
        const WalkEnd e = walk_bsdf_path(tracer, window.origin0 + ab.x() * window.e1 + ab.y() * window.e2, -wi,
                                         o.material, rng, o.max_events, false, t.counters, t.events);
        record_walk_end(t, e, 1.0, map, bins);
      }
      chunks.push_back(std::move(t));
    }
    if (reversed_chunks) std::reverse(chunks.begin(), chunks.end());
    BsdfTally rep(K, npix, nplane);
    for (std::uint64_t bt = 0; bt < batches; ++bt) {
      const std::uint64_t c0 = nchunks * bt / batches, c1 = nchunks * (bt + 1) / batches;
      EXPECT_LE(c1 - c0, 2u);  // the reference builds batches of one or two chunks
      BsdfTally part = chunks[c0];
      if (c1 - c0 == 2) part += chunks[c0 + 1];
      rep += part;
    }
    total.add_replicate(rep);
  }
  return total;
}
}  // namespace

// Mirror and dielectric walks on a periodic tile count their exits in integers
// (measure/exit_counts.hpp): the tallies must be those of double tallies of every path walked,
// bit for bit, counters included. Power: the reference of another seed differs.
TEST(BsdfMeasure, IntegerCountsChangeNoBit) {
  GaussianParams gp;
  gp.resolution = 64;
  gp.correlation_length = 4.0 / 64;
  gp.seed = 9;
  const Microsurface g = generate_gaussian(gp);
  const Microsurface b = bumpy_heightfield(32, 0.08);
  for (const Microsurface* s : {&g, &b}) {
    Tracer tracer(*s);
    for (const mm::Material& mat : {mm::Material::mirror(), mm::Material::dielectric(1.5)})
      for (double theta : {0.0, 60.0, 85.0}) {
        BsdfOptions o = options(mat, theta, 20.0, 4 * 9000, 16);
        o.replicates = 4;
        o.models = false;
        const BsdfResult r = measure_bsdf(tracer, o);
        const BsdfTally ref = sequential_reference(tracer, o, false);
        for (const BsdfTally* t : {&r.measured}) {
          EXPECT_EQ(t->albedo, ref.albedo);  // bitwise
          EXPECT_EQ(t->albedo2, ref.albedo2);
          EXPECT_EQ(t->pix, ref.pix);
          EXPECT_EQ(t->pix2, ref.pix2);
          EXPECT_EQ(t->plane, ref.plane);
          EXPECT_EQ(t->plane2, ref.plane2);
          EXPECT_EQ(t->both2, ref.both2);
          EXPECT_EQ(t->events, ref.events);
          EXPECT_EQ(t->lost, ref.lost);
          EXPECT_EQ(t->counters.rays, ref.counters.rays);
          EXPECT_EQ(t->counters.border_crossings, ref.counters.border_crossings);
          EXPECT_EQ(t->counters.lost_below, ref.counters.lost_below);
          EXPECT_EQ(t->counters.backface_hits, ref.counters.backface_hits);
        }
        if (s == &g && theta == 60.0) {  // power: other paths, other tallies
          BsdfOptions other = o;
          other.seed = o.seed + 1;
          EXPECT_NE(sequential_reference(tracer, other, false).pix, ref.pix);
        }
      }
  }
}

TEST(BsdfMeasure, ReplicatesRunTogetherSumAsOneAfterTheOther) {
  Microsurface s = bumpy_heightfield(32, 0.08);
  Tracer tracer(s);
  // Conductor weights: sums that are not integers, so that the order of additions shows.
  // 4 replicates of 3 chunks each (batches of one chunk), and 2 replicates of 80 chunks (64
  // batches, 16 of them two chunks: 605000 paths rounded up to 655360 whole strata).
  // The third: a 300 x 300 map, whose tallies (14 MB) are run at most 4 at a time.
  struct Case {
    std::uint64_t rays;
    int reps, res;
  };
  for (const Case& c : {Case{4 * 20000, 4, 16}, Case{2 * 605000, 2, 16}, Case{4 * 20000, 4, 300}}) {
    const std::uint64_t rays = c.rays;
    const int reps = c.reps;
    BsdfOptions o = options(mm::Material::conductor(0.2, 3.4), 45.0, 0.0, rays, c.res);
    o.replicates = reps;
    o.models = false;
    const BsdfResult r = measure_bsdf(tracer, o);
    const BsdfTally ref = sequential_reference(tracer, o, false);
    EXPECT_EQ(r.measured.paths, ref.paths);
    EXPECT_EQ(r.measured.events, ref.events);
    EXPECT_EQ(r.measured.albedo, ref.albedo);  // bitwise
    EXPECT_EQ(r.measured.albedo2, ref.albedo2);
    EXPECT_EQ(r.measured.pix, ref.pix);
    EXPECT_EQ(r.measured.pix2, ref.pix2);
    EXPECT_EQ(r.measured.plane, ref.plane);
    EXPECT_EQ(r.measured.both2, ref.both2);
    if (reps == 4 && c.res == 16) {  // power: the same chunk sums added in the reverse order differ in the last bits
      const BsdfTally wrong = sequential_reference(tracer, o, true);
      EXPECT_NE(r.measured.pix, wrong.pix);
    }
  }
}

TEST(BsdfMeasure, MeasuredTablesAreReciprocal) {
  // [GeomBSDF24, eq. 4c] on the explicit surface. Reflection: f(b <- a) = f(a <- b) with both angles at
  // in-plane bin centers. Transmission: light from below is light from above on the surface
  // seen from below (heights negated) with the inverse index; f_t(o <- i) / eta_o^2 =
  // f_t(i <- o) / eta_i^2.
  GaussianParams gp;
  gp.resolution = 128;
  gp.correlation_length = 4.0 / 128;  // 4 cells per l
  gp.alpha_x = gp.alpha_y = 0.5;
  gp.seed = 3;
  Microsurface s = generate_gaussian(gp);
  Microsurface sf = flipped(s);
  Tracer tracer(s), tracer_f(sf);
  const int res = 32;
  const double w = 180.0 / res;
  auto center = [&](int b) { return -90.0 + (b + 0.5) * w; };
  const double ta = center(16 + 3), tb = center(16 + 9);  // 14.06 and 47.81 deg
  std::vector<double> zs;
  // reflection: light at ta (azimuth 0), read the specular-side bin at tb (azimuth 180); and
  // the reverse path. (The same with the light at azimuth 0 both times is a rotated, i.e.
  // different, surface: one tile's realization differs by ~10% there.)
  {
    const BsdfResult r1 = measure_bsdf(tracer, options(mm::Material::mirror(), ta, 0.0, 1500000, res));
    // reverse path: light from (tb, azimuth 180), leaving toward (ta, azimuth 0) = its specular side
    const BsdfResult r2 = measure_bsdf(tracer, options(mm::Material::mirror(), tb, 180.0, 1500000, res));
    const Estimate f1 = r1.f_plane(0, 4, 16 + 9), f2 = r2.f_plane(0, 4, 16 + 3);
    zs.push_back((f1.mean - f2.mean) / std::hypot(f1.stderr_, f2.stderr_));
    EXPECT_GT(f1.mean, 10 * f1.stderr_);
  }
  // transmission through glass: above (eta 1) at 50.6 deg -> below (eta 1.5) at 30.9 deg (near
  // the refracted direction), and back from below
  {
    const double eta = 1.5;
    const int ba = 25, bb = 21;
    const BsdfResult r1 = measure_bsdf(tracer, options(mm::Material::dielectric(eta), center(ba), 0.0, 1500000, res));
    // from below at tb, toward azimuth 0 above: on the flipped surface, light from above at tb
    // with azimuth 180, leaving toward azimuth 0 (its specular side)
    const BsdfResult r2 =
        measure_bsdf(tracer_f, options(mm::Material::dielectric(1 / eta), center(bb), 180.0, 1500000, res));
    const Estimate f1 = r1.f_plane(1, 4, bb), f2 = r2.f_plane(1, 4, ba);
    const double c = 1.0 / (eta * eta);  // eta_i^2 / eta_o^2 for f1 (i above, o below)
    zs.push_back((c * f1.mean - f2.mean) / std::hypot(c * f1.stderr_, f2.stderr_));
    EXPECT_GT(f1.mean, 10 * f1.stderr_);
    // without the eta^2 the two differ by far more than their errors (the test has power)
    EXPECT_GT(std::abs(f1.mean - f2.mean) / std::hypot(f1.stderr_, f2.stderr_), 10.0);
  }
  for (double z : zs) EXPECT_LT(std::abs(z), sidak_z(0.01, 2)) << z;
}

// --- Finite objects, V-grooves and V-cavity ensembles beside their closed forms ---------------

TEST(BsdfMeasure, MirrorBoxAlbedoIsItsVisibleAreaRatio) {
  // A convex mirror object reflects every ray that hits it once; per unit of the flux on its
  // macrosurface ([GeomBSDF24, eq. 4a] with the base area A) the total albedo is its visible area ratio,
  // 1 + (H/W) tan(theta) seen across a face [GeomBSDF24, "Inherent Assumptions", Fig. 5].
  BoxParams p;
  p.height = 0.5;
  Microsurface s = generate_box(p);
  Tracer tracer(s);
  const double zc = sidak_z(0.001, 3);
  for (double th : {0.0, 30.0, 60.0}) {
    const BsdfResult r = measure_bsdf(tracer, options(mm::Material::mirror(), th, 0.0, 100000));
    const double ratio = 1.0 + 0.5 * std::tan(rad(th));
    const Estimate e = r.albedo(0, 4);
    SCOPED_TRACE("theta " + std::to_string(th));
    EXPECT_EQ(r.measured.lost, 0u);
    EXPECT_EQ(r.albedo(0, 0).mean, e.mean);  // convex: one bounce
    EXPECT_LT(std::abs(e.mean - ratio) / e.stderr_, zc) << e.mean << " vs " << ratio;
    // Power: the plain macro-area normalization (ratio 1) is rejected where walls are lit.
    if (th > 0) { EXPECT_GT(std::abs(e.mean - 1.0) / e.stderr_, zc); }
    // The top's mirror lobe: the share 1 of the albedo leaves upward in the specular pixel.
    const int px = r.map.pixel_of(direction_from_angles(rad(th), kPi));
    EXPECT_NEAR(r.f_pixel(0, 4, px).mean * r.map.pixel_cos_integral(px), 1.0, 6 * r.f_pixel(0, 4, px).stderr_ * r.map.pixel_cos_integral(px));
  }
}

TEST(BsdfMeasure, TiledMirrorBoxesTendToTheMacrosurface) {
  BoxParams p;
  p.height = 0.5;
  p.tiles = 4;
  Microsurface s = generate_tiled_boxes(p);
  Tracer tracer(s);
  const BsdfResult r = measure_bsdf(tracer, options(mm::Material::mirror(), 30.0, 0.0, 100000));
  // Only the outer walls stick out of the macrosurface's swept volume: 1 + (H/(N W)) tan(theta).
  const double ratio = 1.0 + 0.5 / 4 * std::tan(rad(30));
  const Estimate e = r.albedo(0, 4);
  EXPECT_LT(std::abs(e.mean - ratio) / e.stderr_, 3.5) << e.mean << " vs " << ratio;
}

TEST(BsdfMeasure, VGrooveOrdersEqualTheClosedForm) {
  // Periodic V-grooves traced in 3D against the 2D-unfolding closed form per order
  // (models/vgroove_multiple.hpp), several facet angles, incidences and azimuths.
  const mm::Material mats[2] = {mm::Material::mirror(), mm::Material::conductor(0.2, 3.0)};
  const double cases[3][2] = {{20, 0}, {50, 30}, {70, 120}};
  const int K = 4;
  const double zc = sidak_z(0.001, 3 * 3 * 2 * K);
  int rejected_wrong = 0;
  for (double tf : {45.0, 60.0, 70.0})
    for (const auto& c : cases)
      for (const auto& mat : mats) {
        VGrooveParams vp;
        vp.facet_angle_deg = tf;
        Microsurface s = generate_vgroove(vp);
        Tracer tracer(s);
        BsdfOptions o = options(mat, c[0], c[1], 40000);
        const BsdfResult r = measure_bsdf(tracer, o);
        const auto model = mm::vgroove_albedo(rad(tf), direction_from_angles(o.theta_i, o.phi_i), mat, K);
        const auto wrong = mm::vgroove_albedo(rad(tf + 1.0), direction_from_angles(o.theta_i, o.phi_i), mat, K);
        // The tracer's leak budget (validate's albedo_total row): rays slipping through at
        // rounding level, at most max(1, kMaxLostFraction paths).
        EXPECT_LE(static_cast<double>(r.measured.lost),
                  std::max(1.0, std::ceil(validation::kMaxLostFraction * r.measured.paths)));
        for (int k = 0; k < K; ++k) {
          const Estimate e = r.albedo(0, k);
          SCOPED_TRACE("tf " + std::to_string(tf) + " theta " + std::to_string(c[0]) + " order " + std::to_string(k + 1));
          if (e.stderr_ > 0) EXPECT_LT(std::abs(e.mean - model[k]) / e.stderr_, zc) << e.mean << " vs " << model[k];
          else EXPECT_NEAR(e.mean, model[k], 1e-9);
          if (std::abs(e.mean - wrong[k]) > zc * std::max(e.stderr_, 1e-9)) ++rejected_wrong;
        }
        // The known case: facet angle 70, theta_i 20: orders 3 and 4 = 0.4679 and 0.5321.
        if (tf == 70.0 && c[0] == 20.0 && mat.kind == mm::MaterialKind::Mirror) {
          EXPECT_NEAR(model[2], 0.4679, 1e-4);
          EXPECT_NEAR(model[3], 0.5321, 1e-4);
        }
      }
  EXPECT_GT(rejected_wrong, 10);  // power: a groove 1 deg steeper is rejected
}

TEST(BsdfMeasure, VCavityEnsembleEqualsItsGroovesClosedForm) {
  VCavityParams vp;
  vp.grooves = 256;
  Microsurface s = generate_vcavity(vp);
  Tracer tracer(s);
  const mm::Material mat = mm::Material::conductor(0.2, 3.0);
  const BsdfOptions o = options(mat, 50.0, 20.0, 256 * 256);
  const BsdfResult r = measure_bsdf(tracer, o);
  const auto model = groove_model_albedo(s, o, "vcavity_multiple_grooves");
  ASSERT_TRUE(model.has_value());
  EXPECT_EQ(r.measured.lost, 0u);
  const double zc = sidak_z(0.001, 5);
  for (int k = 0; k <= 4; ++k) {
    const Estimate e = r.albedo(0, k);
    if (e.stderr_ == 0) {  // no ray in this order (shallow grooves): the closed form agrees
      EXPECT_EQ(e.mean, 0.0);
      EXPECT_LT((*model)[k], 1e-3);
      continue;
    }
    EXPECT_LT(std::abs(e.mean - (*model)[k]) / e.stderr_, zc) << k << ": " << e.mean << " vs " << (*model)[k];
    // Power: a 5% change of a slot holding more than 5% is rejected.
    if ((*model)[k] > 0.05) { EXPECT_GT(std::abs(e.mean - 1.05 * (*model)[k]) / e.stderr_, zc); }
  }
  // The record carries the models beside the rows.
  const Json j = bsdf_summary_json(r, s);
  EXPECT_TRUE(j["albedo_models"]["vcavity_multiple"].is_object());
  EXPECT_TRUE(j["albedo_models"]["vgroove_multiple"].is_null());
  EXPECT_TRUE(j["rows"][0].contains("z_vcavity_multiple_grooves"));
  EXPECT_TRUE(j["in_plane"][0].contains("vcavity_multiple_order_2_stderr"));
}

TEST(BsdfMeasure, VGrooveInPlaneLobesEqualTheClosedFormBeams) {
  // Every beam of a V-groove leaves in one direction: binned, the closed form's in-plane lobes
  // equal the traced ones bin by bin (facet angle 70, theta_i 20, phi_i 0: all in the plane).
  VGrooveParams vp;
  vp.facet_angle_deg = 70.0;
  Microsurface s = generate_vgroove(vp);
  Tracer tracer(s);
  const BsdfResult r = measure_bsdf(tracer, options(mm::Material::mirror(), 20.0, 0.0, 40000, 31));  // odd: no bin edge at the normal
  const Json j = bsdf_summary_json(r, s);
  // The beams of a groove 3 degrees steeper, beside the same measurement (power check).
  vp.facet_angle_deg = 73.0;
  const Json j_wrong = bsdf_summary_json(r, generate_vgroove(vp));
  double model_sum = 0.0;
  int b = 0, rejected_wrong = 0;
  for (const Json& row : j["in_plane"]) {
    const double ci = r.plane.cos_integral(b);
    for (int k = 0; k < 4; ++k) {
      const double model = row["vgroove_multiple_" + order_key(k, 4)].get<double>() * ci;
      const double wrong = j_wrong["in_plane"][b]["vgroove_multiple_" + order_key(k, 4)].get<double>() * ci;
      const Estimate e = r.f_plane(0, k, b);
      if (e.stderr_ > 0) EXPECT_LT(std::abs(e.mean * ci - model) / (e.stderr_ * ci), 3.5) << b << " " << k;
      else EXPECT_NEAR(e.mean * ci, model, 1e-9) << b << " " << k;
      if (std::abs(e.mean * ci - wrong) > 3.5 * std::max(e.stderr_ * ci, 1e-9)) ++rejected_wrong;
    }
    model_sum += row["vgroove_multiple"].get<double>() * ci;
    ++b;
  }
  EXPECT_NEAR(model_sum, 1.0, 1e-12);
  EXPECT_GE(rejected_wrong, 2);  // the steeper groove's beams leave in other bins
}

TEST(BsdfMeasure, VCavityInPlaneLobesEqualTheClosedFormOverItsGrooves) {
  // The closed form binned over the ensemble's own grooves is the exact expectation of the traced
  // in-plane lobe (every groove gets the same rays): z per bin and order with the traced error.
  // The nominal V-cavity model's order-1 lobe (grooves drawn from D, Monte Carlo) is, by an
  // independent route, the V-cavity single-scattering BRDF ([Heitz14, eq. 18] with the V-cavity G2 of
  // sec. 6: the lit part of a facet whose reflection escapes is the part seen from both sides).
  VCavityParams vp;
  vp.grooves = 256;
  Microsurface s = generate_vcavity(vp);
  Tracer tracer(s);
  const int nb = 31;  // odd: no bin edge at the normal
  const mm::Material mat = mm::Material::mirror();
  const BsdfResult r = measure_bsdf(tracer, options(mat, 50.0, 0.0, 256 * 256, nb));
  const Json j = bsdf_summary_json(r, s);
  // The same record with the closed forms of a 2 degree different incidence (power check).
  BsdfResult r_wrong = r;
  r_wrong.options.theta_i = rad(52.0);
  r_wrong.wi = direction_from_angles(r_wrong.options.theta_i, r_wrong.options.phi_i);
  const Json j_wrong = bsdf_summary_json(r_wrong, s);
  // V-cavity single scattering of a rougher D (power check of the model comparison).
  const mm::MicrofacetBsdf rough{mm::Ndf::beckmann(0.55, 0.55), mat, mm::Masking::VCavity};

  const char* keys[3] = {"order_1", "order_2", "total"};
  const int slots[3] = {0, 1, 4};
  const double zc = sidak_z(0.001, 3 * nb), zm = sidak_z(0.001, nb);
  int tested = 0, rejected_wrong = 0, model_tested = 0, rejected_rough = 0;
  double untested_mass = 0.0;
  for (int b = 0; b < nb; ++b) {
    const Json& row = j["in_plane"][b];
    for (int q = 0; q < 3; ++q) {
      const std::string suffix = q == 2 ? "" : std::string("_") + keys[q];
      const double own = row["vcavity_multiple_grooves" + suffix].get<double>();
      const double wrong = j_wrong["in_plane"][b]["vcavity_multiple_grooves" + suffix].get<double>();
      const Estimate e = r.f_plane(0, slots[q], b);
      SCOPED_TRACE("bin " + std::to_string(b) + " " + keys[q]);
      if (e.stderr_ > 0) {
        EXPECT_LT(std::abs(e.mean - own) / e.stderr_, zc) << e.mean << " vs " << own;
        if (std::abs(e.mean - wrong) / e.stderr_ > zc) ++rejected_wrong;
        ++tested;
      } else {
        untested_mass += own * r.plane.cos_integral(b);
      }
    }
    const double m1 = row["vcavity_multiple_order_1"].get<double>();
    const double m1_se = row["vcavity_multiple_order_1_stderr"].get<double>();
    const double single = row["vcavity_single"].get<double>();
    if (m1_se > 0) {
      SCOPED_TRACE("bin " + std::to_string(b) + " model order 1");
      EXPECT_LT(std::abs(m1 - single) / m1_se, zm) << m1 << " vs V-cavity single scattering " << single;
      const double f_rough = r.plane.cos_weighted_average(b, true, [&](const Vec3& o) { return rough.eval(o, r.wi); });
      if (std::abs(m1 - f_rough) / m1_se > zm) ++rejected_rough;
      ++model_tested;
    }
  }
  EXPECT_GT(tested, 20);
  EXPECT_GT(model_tested, 20);
  // Bins no traced ray reached hold a negligible share of the closed form's light.
  EXPECT_LT(untested_mass, 1e-3);
  EXPECT_GT(rejected_wrong, 5);  // power: the lobe of a 2 degree different incidence
  EXPECT_GT(rejected_rough, 3);  // power: alpha 0.55 instead of 0.5
}

TEST(BsdfRecord, AlbedoTablesMergeOverSurfacesByTheTableRule) {
  // Two independent Gaussian tiles: the merged albedo is the mean with the between-surface
  // error, its ray-count error sqrt(se1^2 + se2^2) / 2, and the nominal models' z use the
  // between-surface error combined with the Smith walk's own (table.hpp, Comparison::model_error).
  std::vector<Table> tables;
  std::vector<BsdfResult> results;
  for (std::uint64_t seed : {5u, 6u}) {
    GaussianParams gp;
    gp.alpha_x = gp.alpha_y = 0.5;
    gp.resolution = 32;
    gp.seed = seed;
    const Microsurface s = generate_gaussian(gp);
    Tracer tracer(s);
    BsdfOptions o = options(mm::Material::dielectric(1.5), 40.0, 0.0, 4000, 8);
    o.model_walks = 4000;
    results.push_back(measure_bsdf(tracer, o));
    tables.push_back(bsdf_albedo_table(results.back()));
  }
  const Table merged = merge({&tables[0], &tables[1]});
  ASSERT_EQ(merged.rows.size(), 10u);  // reflected and transmitted x orders 1, 2, 3, 4+, total
  EXPECT_EQ(merged.error, ErrorKind::Surfaces);
  for (std::size_t i = 0; i < merged.rows.size(); ++i) {
    const Json& row = merged.rows[i];
    const int side = static_cast<int>(i / 5), slot = static_cast<int>(i % 5);
    const Estimate a = results[0].albedo(side, slot), b = results[1].albedo(side, slot);
    EXPECT_EQ(row["side"], tables[0].rows[i]["side"]);
    EXPECT_EQ(row["order"], order_key(slot, 4));
    EXPECT_DOUBLE_EQ(row["albedo"].get<double>(), 0.5 * (a.mean + b.mean));
    EXPECT_NEAR(row["albedo_stderr"].get<double>(), 0.5 * std::abs(a.mean - b.mean), 1e-15);
    EXPECT_NEAR(row["albedo_stderr_rays"].get<double>(), 0.5 * std::hypot(a.stderr_, b.stderr_), 1e-15);
    // The Smith walk runs beside each surface, its walks set by that surface's errors: the merged row takes
    // the run with the smaller error (both runs estimate the same model of the same nominal NDF).
    const Estimate m0 = results[0].model_albedo(side, slot), m1 = results[1].model_albedo(side, slot);
    const Estimate m = m1.stderr_ < m0.stderr_ ? m1 : m0;
    EXPECT_EQ(row["smith_multiple"].get<double>(), m.mean);
    EXPECT_EQ(row["smith_multiple_stderr"].get<double>(), m.stderr_);
    if (m0.stderr_ > 0.0 && m1.stderr_ > 0.0) { EXPECT_LT(std::abs(m0.mean - m1.mean), 5.0 * std::hypot(m0.stderr_, m1.stderr_)); }
    const double se = std::hypot(row["albedo_stderr"].get<double>(), m.stderr_);
    if (se > 0) { EXPECT_NEAR(row["z_smith_multiple"].get<double>(), (row["albedo"].get<double>() - m.mean) / se, 1e-12); }
    EXPECT_TRUE(row["p_smith_multiple"].is_null() == !row["z_smith_multiple"].is_number());
    // A wrong model (the walk's value 30% higher) moves z by 0.3 m / se: the rule sees it.
    if (se > 0 && m.mean > 0.05) {
      Json wrong = row;
      wrong["smith_multiple"] = 1.3 * m.mean;
      compare(wrong, merged.spec.comparisons[0], 2);
      EXPECT_NEAR(row["z_smith_multiple"].get<double>() - wrong["z_smith_multiple"].get<double>(), 0.3 * m.mean / se, 1e-9);
    }
  }
  // One surface's record: the nominal models' z are null, their ray-count z kept as *_rays.
  GaussianParams gp;
  gp.alpha_x = gp.alpha_y = 0.5;
  gp.resolution = 32;
  gp.seed = 5;
  const Json j = bsdf_summary_json(results[0], generate_gaussian(gp));
  const Json& r1 = j["rows"][0];
  EXPECT_TRUE(r1["z_smith_single"].is_null());
  EXPECT_NEAR(r1["z_smith_single_rays"].get<double>(),
              (r1["albedo"].get<double>() - r1["smith_single"].get<double>()) / r1["albedo_stderr"].get<double>(), 1e-12);
  EXPECT_TRUE(j["rows"][4]["z_smooth_interface"].is_number());  // exact model: a verdict
}

// The estimators' driver (measure/replicates.hpp: run_units): units handed over in unit order,
// only the share's, and a unit's chunks summed by halving (c0 + (c1 + c2) for three chunks),
// whatever the passes and the threads.
namespace {
struct OrderProbe {
  double sum = 0.0;
  std::uint64_t paths = 0;
  OrderProbe& operator+=(const OrderProbe& o) {
    sum += o.sum;
    paths += o.paths;
    return *this;
  }
};
}  // namespace

TEST(UnitDriver, UnitsInOrderChunksSummedByHalvingShareOnly) {
  // 3 replicates of 21 paths, chunks of 4 (6 chunks: the last holds one path), 2 units a
  // replicate (chunks 0-2 and 3-5). A chunk's first path carries 1e16 in chunks 0 and 3, 1 in
  // the others: halving gives 1e16 + (1 + 1) = 1e16 + 2, a left-to-right sum 1e16.
  const microsim::UnitPlan plan{3, 21, 4, 2};
  ASSERT_EQ(plan.chunks(), 6u);
  ASSERT_EQ(plan.groups(), 2u);
  auto body = [](int, std::uint64_t j, OrderProbe& p) {
    ++p.paths;
    if (j % 4 == 0) p.sum += (j / 4) % 3 == 0 ? 1e16 : 1.0;
  };
  for (int threads : {1, 2})
    for (std::uint64_t max_units : {std::uint64_t(1), ~std::uint64_t(0)}) {
      tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
      std::vector<std::pair<int, std::uint64_t>> order;
      std::vector<OrderProbe> units;
      microsim::run_units<OrderProbe>(
          plan, [] { return OrderProbe(); }, body,
          [&](int q, std::uint64_t g, OrderProbe&& p) {
            order.emplace_back(q, g);
            units.push_back(p);
          },
          {0, ~std::uint64_t(0)}, microsim::UnitPasses{~std::uint64_t(0), max_units});
      const std::vector<std::pair<int, std::uint64_t>> expected{{0, 0}, {0, 1}, {1, 0}, {1, 1}, {2, 0}, {2, 1}};
      EXPECT_EQ(order, expected);
      ASSERT_EQ(units.size(), 6u);
      for (std::size_t u = 0; u < units.size(); ++u) {
        EXPECT_EQ(units[u].sum, 1e16 + 2.0) << u;  // halving; left to right would give 1e16
        EXPECT_EQ(units[u].paths, u % 2 == 0 ? 12u : 9u) << u;
      }
    }
  // The share of a process that holds replicate 1 only: its two units, nothing else.
  std::vector<std::pair<int, std::uint64_t>> order;
  microsim::run_units<OrderProbe>(
      plan, [] { return OrderProbe(); }, body,
      [&](int q, std::uint64_t g, OrderProbe&&) { order.emplace_back(q, g); }, plan.units_of({1, 2}));
  EXPECT_EQ(order, (std::vector<std::pair<int, std::uint64_t>>{{1, 0}, {1, 1}}));
}

TEST(UnitDriver, ReplicateChunksOutsideTheShareAreLeftAsMade) {
  auto parts = microsim::run_replicate_chunks<OrderProbe>(
      3, 10, 4, [] { return OrderProbe(); }, [](int, std::uint64_t, OrderProbe& p) { ++p.paths; }, {1, 2});
  ASSERT_EQ(parts.size(), 9u);  // 3 chunks a replicate, every chunk its own part
  for (std::size_t c = 0; c < parts.size(); ++c)
    EXPECT_EQ(parts[c].paths, c / 3 == 1 ? (c % 3 == 2 ? 2u : 4u) : 0u) << c;
}
