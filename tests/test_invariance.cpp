// Invariances of masking [Heitz14, Sec. 3]: stretching by diag(sx, sy, 1) (sec. 3.1) ray for ray,
// vertical shearing with offset slopes and the mesonormal's projected area (sec. 3.4), and
// anisotropic Gaussian tiles against Smith with the projected roughness alpha_o (eq. 11).
#include <gtest/gtest.h>

#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/measure/stats.hpp"
#include "microsim/models/g2_forms.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/transform.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;

namespace {
Vec3 dir(double theta_deg, double phi_deg) { return direction_from_angles(rad(theta_deg), rad(phi_deg)); }

Microsurface gaussian(int resolution, std::uint64_t seed, double ax, double ay) {
  GaussianParams p;
  p.resolution = resolution;
  p.correlation_length = 4.0 / resolution;  // 4 cells per l
  p.alpha_x = ax;
  p.alpha_y = ay;
  p.seed = seed;
  return generate_gaussian(p);
}

// Facet k and barycentrics drawn with density proportional to A_f max(0, v.m_f) over the facets
// [0, nf) of s (the G1 area-sampling population).
struct FacetSampler {
  std::vector<double> cdf;
  FacetSampler(const Microsurface& s, const Vec3& v, std::size_t nf) : cdf(nf) {
    double acc = 0;
    for (std::size_t k = 0; k < nf; ++k) cdf[k] = acc += std::max(0.0, 0.5 * s.facet(k).cross().dot(v));
  }
  std::size_t draw(double u) const {
    std::size_t k = std::upper_bound(cdf.begin(), cdf.end(), u * cdf.back()) - cdf.begin();
    k = std::min(k, cdf.size() - 1);
    while (k > 0 && cdf[k] == cdf[k - 1]) --k;
    return k;
  }
};

struct RayForRay {
  std::uint64_t n = 0, mismatches = 0, visible_a = 0, visible_b = 0;
};
}  // namespace

TEST(Stretching, VisibilityIsTheSameRayForRay) {
  // [Heitz14, Sec. 3.1]: stretching the configuration (surface and view) keeps occluded rays occluded
  // and visible rays visible. Occlusion rays from the same surface points (mapped) and first
  // hits of the same parallel rays (mapped) on both surfaces: they agree up to float rounding.
  Microsurface s = gaussian(128, 3, 0.5, 0.5);
  Tracer ts(s);
  for (auto [sx, sy] : {std::pair{2.0, 0.5}, std::pair{1.7, 0.6}}) {
    Microsurface s2 = stretch_surface(s, sx, sy);
    Tracer t2(s2);
    for (const Vec3& v : {dir(75, 30), dir(85, 200)}) {
      const Vec3 v2 = stretch_vector(v, sx, sy).normalized();
      FacetSampler fs(s, v, s.num_facets());
      RayForRay occ;
      TraceCounters c;
      const std::uint64_t n = 200000;
      for (std::uint64_t j = 0; j < n; ++j) {
        CounterRng rng(5, 1, j);
        const std::size_t k = fs.draw(rng.uniform());
        const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
        const Triangle f = s.facet(k), f2 = s2.facet(k);
        const SourcePlane p1 = SourcePlane::of(f), p2 = SourcePlane::of(f2);
        const bool a = ts.occluded(f.point(r1 * (1 - r2), r1 * r2), v, &p1, c);
        const bool b = t2.occluded(f2.point(r1 * (1 - r2), r1 * r2), v2, &p2, c);
        ++occ.n;
        occ.mismatches += a != b;
        occ.visible_a += !a;
        occ.visible_b += !b;
      }
      // First hits of parallel rays along -v from the tile's top, mapped.
      RayForRay hit;
      const RayWindow w = make_ray_window(ts, v);
      for (std::uint64_t j = 0; j < n; ++j) {
        CounterRng rng(6, 1, j);
        const double s1 = rng.uniform(), s2 = rng.uniform();  // named: operand order is unspecified
        const Vec3 org = w.origin0 + s1 * w.e1 + s2 * w.e2;
        const TraceHit h1 = ts.first_hit(org, -v, nullptr, c);
        const TraceHit h2 = t2.first_hit(stretch_vector(org, sx, sy), -v2, nullptr, c);
        ++hit.n;
        hit.mismatches += !(h1.hit && h2.hit && h1.facet == h2.facet);
      }
      std::printf("stretch (%.2f, %.2f), view theta %.0f: occlusion mismatches %llu / %llu "
                  "(G1 %.5f vs %.5f), first-hit facet mismatches %llu / %llu\n",
                  sx, sy, deg(theta_of(v)), (unsigned long long)occ.mismatches,
                  (unsigned long long)occ.n, double(occ.visible_a) / n, double(occ.visible_b) / n,
                  (unsigned long long)hit.mismatches, (unsigned long long)hit.n);
      // Float rounding only: a ray must pass within ~1e-6 of the scene size of an edge to flip,
      // which a few rays in 1e5 at most do. A wrong view mapping (unstretched v) flips ~5-20%.
      EXPECT_LE(occ.mismatches, n / 10000) << sx << "," << sy;
      EXPECT_LE(hit.mismatches, n / 10000) << sx << "," << sy;
      EXPECT_EQ(c.lost_below + c.unresolved, 0u);
    }
  }
}

TEST(Stretching, WrongViewMappingIsDetected) {
  // Power of the ray-for-ray test: keep the view unstretched.
  Microsurface s = gaussian(128, 3, 0.5, 0.5);
  Microsurface s2 = stretch_surface(s, 2.0, 0.5);
  Tracer ts(s), t2(s2);
  const Vec3 v = dir(75, 30);
  FacetSampler fs(s, v, s.num_facets());
  std::uint64_t mismatches = 0;
  TraceCounters c;
  for (std::uint64_t j = 0; j < 20000; ++j) {
    CounterRng rng(5, 1, j);
    const std::size_t k = fs.draw(rng.uniform());
    const Triangle f = s.facet(k), f2 = s2.facet(k);
    const SourcePlane p1 = SourcePlane::of(f), p2 = SourcePlane::of(f2);
    mismatches += ts.occluded(f.point(0.3, 0.3), v, &p1, c) != t2.occluded(f2.point(0.3, 0.3), v, &p2, c);
  }
  EXPECT_GT(mismatches, 500u);
}

TEST(Stretching, MaskingStatisticsAndModelsAreInvariant) {
  // Lambda from the facets, the measured G1 and the nominal Smith G1 ([Heitz14, eq. 11]: alpha scales
  // by 1/s with the slopes) are the same for (S, v) and (stretched S, stretched v).
  Microsurface s = gaussian(128, 4, 0.4, 0.4);
  Microsurface s2 = stretch_surface(s, 1.6, 0.7);
  Tracer ts(s), t2(s2);
  G1Options go;
  go.rays = 200000;
  for (const Vec3& v : {dir(60, 0), dir(80, 45)}) {
    const Vec3 v2 = stretch_vector(v, 1.6, 0.7).normalized();
    G1Result a = measure_g1(ts, v, go), b = measure_g1(t2, v2, go);
    EXPECT_NEAR(a.lambda_numeric, b.lambda_numeric, 1e-5 * a.lambda_numeric);
    const Estimate ea = a.g1_area_sampling(), eb = b.g1_area_sampling();
    EXPECT_LT(std::abs(ea.mean - eb.mean), 4 * std::hypot(ea.stderr_, eb.stderr_));
    EXPECT_NEAR(s.nominal->G1(v), s2.nominal->G1(v2), 1e-13);
  }
  EXPECT_DOUBLE_EQ(s2.nominal->alpha_x, 0.4 / 1.6);
  EXPECT_DOUBLE_EQ(s2.description["alpha_y"].get<double>(), 0.4 / 0.7);
}

TEST(Shearing, OffsetSlopeSmithMatchesTheAngleFormOfHeitz14) {
  // [Heitz14, Sec. 3.4]: a = (cot theta_o - (cos phi_o xbar + sin phi_o ybar)) / alpha_o.
  for (auto ndf : {models::Ndf::beckmann(0.5, 0.5), models::Ndf::ggx(0.3, 0.6)})
    for (auto [t, p, xb, yb] : {std::tuple{60.0, 0.0, 0.2, 0.0}, std::tuple{75.0, 130.0, -0.3, 0.25},
                                std::tuple{40.0, 250.0, 0.1, 0.4}}) {
      const double th = rad(t), ph = rad(p);
      const double a = (1 / std::tan(th) - (std::cos(ph) * xb + std::sin(ph) * yb)) / ndf.alpha_o(ph);
      const double expected = ndf.kind == models::Distribution::Beckmann ? models::beckmann_lambda(a)
                                                                         : models::ggx_lambda(a);
      const double got = models::Lambda_offset_slopes(ndf, dir(t, p), xb, yb);
      if (std::isinf(expected)) EXPECT_TRUE(std::isinf(got));  // view below the mesosurface
      else EXPECT_NEAR(got, expected, 1e-12 * (1 + expected));
    }
}

TEST(Shearing, ShearedTileMasksLikeSmithWithOffsetSlopesAndMesonormalArea) {
  // A tile with non-centered slopes: the Gaussian tile sheared by z += kx x + ky y. Its masking
  // measured on the explicit sheared geometry (area sampling by projected area toward v', one
  // occlusion ray each) against Smith with offset slopes and the mesosurface's projected area:
  // Lambda' = sum_f A'_f max(0, -v'.m'_f) / (A_tile (v'.(-kx, -ky, 1))) [Heitz14, Sec. 3.4]; and ray
  // for ray against the unsheared tile seen along the unsheared view.
  const double kx = 0.3, ky = -0.15;
  Microsurface s = gaussian(128, 7, 0.5, 0.5);
  ShearedPatch patch = shear_surface(s, kx, ky, 1);
  Tracer ts(s), t2(patch.surface);
  for (const Vec3& v2 : {dir(70, 0), dir(60, 180), dir(75, 100)}) {
    const Vec3 v = unshear_vector(v2, kx, ky).normalized();
    ASSERT_GT(v.z(), 0);
    double back = 0;
    for (std::size_t k = 0; k < patch.central_facets; ++k)
      back += std::max(0.0, -0.5 * patch.surface.facet(k).cross().dot(v2));
    const double lambda_sheared = back / (patch.tile_area * v2.dot(Vec3(-kx, -ky, 1)));
    EXPECT_NEAR(lambda_sheared, lambda_from_facets(s, v), 2e-5 * (1 + lambda_sheared));
    EXPECT_NEAR(models::Lambda_offset_slopes(*s.nominal, v2, kx, ky), s.nominal->Lambda(v), 1e-12);

    FacetSampler fs(patch.surface, v2, patch.central_facets);
    const std::uint64_t n = 200000;
    std::uint64_t visible = 0, mismatches = 0;
    TraceCounters c;
    for (std::uint64_t j = 0; j < n; ++j) {
      CounterRng rng(8, 1, j);
      const std::size_t k = fs.draw((j + rng.uniform()) / n);  // stratified along the CDF
      const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
      const Triangle f2 = patch.surface.facet(k), f = s.facet(k);
      const SourcePlane p2 = SourcePlane::of(f2), p1 = SourcePlane::of(f);
      const bool occ2 = t2.occluded(f2.point(r1 * (1 - r2), r1 * r2), v2, &p2, c);
      const bool occ1 = ts.occluded(f.point(r1 * (1 - r2), r1 * r2), v, &p1, c);
      visible += !occ2;
      mismatches += occ1 != occ2;
    }
    const Estimate g = binomial_estimate(visible, n);
    const double smith = 1 / (1 + lambda_sheared);
    std::printf("shear (%.2f, %.2f) view theta' %.0f phi' %.0f: G1 %.5f +- %.5f, Smith offset "
                "slopes (facets) %.5f, nominal %.5f, ray-for-ray mismatches %llu / %llu\n",
                kx, ky, deg(theta_of(v2)), deg(phi_of(v2)), g.mean, g.stderr_, smith,
                1 / (1 + models::Lambda_offset_slopes(*s.nominal, v2, kx, ky)),
                (unsigned long long)mismatches, (unsigned long long)n);
    EXPECT_LT(std::abs(g.mean - smith), sidak_z(0.01, 3) * g.stderr_);
    EXPECT_LE(mismatches, n / 10000);
    // Power: normalizing by the macrosurface's projected area (v'.z) instead of the
    // mesosurface's is rejected where the two differ (view 70 degrees over the rising side).
    if (theta_of(v2) > rad(69) && phi_of(v2) < 0.1) {
      const double wrong = 1 / (1 + back / (patch.tile_area * v2.z()));
      EXPECT_GT(std::abs(g.mean - wrong), 10 * g.stderr_);
    }
  }
}

TEST(Anisotropy, GaussianTilesFollowSmithWithProjectedRoughness) {
  // [Heitz14, eq. 11]: an anisotropic tile masks like the isotropic one with alpha_o(phi). Ensemble of
  // independent tiles, between-surface standard errors (docs/theory/error-bars.md).
  // The Gaussian generator realizes alpha_x exactly but its y slopes (correlation length
  // l alpha_x / alpha_y, here 4 cells) only in expectation "expected_slope_var_y" of its
  // description; the model uses alpha_y = sqrt(2 expected_slope_var_y).
  const double ax = 0.3, ay = 0.6, theta = 75;
  const std::vector<double> phis = {0, 30, 60, 90};
  const int tiles = 6;
  std::vector<std::vector<double>> g(phis.size());
  G1Options go;
  go.rays = 100000;
  double ay_eff = 0;
  for (int k = 0; k < tiles; ++k) {
    GaussianParams p;
    p.resolution = 128;
    p.alpha_x = ax;
    p.alpha_y = ay;
    p.correlation_length = 8.0 / 128;
    p.seed = 100 + k;
    Microsurface s = generate_gaussian(p);
    ay_eff = std::sqrt(2 * s.description["expected_slope_var_y"].get<double>());
    Tracer t(s);
    for (std::size_t a = 0; a < phis.size(); ++a)
      g[a].push_back(measure_g1(t, dir(theta, phis[a]), go).g1_area_sampling().mean);
  }
  const models::Ndf nominal = models::Ndf::beckmann(ax, ay_eff);
  const models::Ndf iso = models::Ndf::beckmann(std::sqrt(ax * ay_eff), std::sqrt(ax * ay_eff));
  // Between-tile errors of `tiles` surfaces: Student t with tiles - 1 degrees of freedom.
  const double zmax = sidak_t(0.01, static_cast<int>(phis.size()), tiles - 1);
  double worst_iso = 0;
  std::vector<double> means;
  for (std::size_t a = 0; a < phis.size(); ++a) {
    double mean = 0, var = 0;
    for (double x : g[a]) mean += x / tiles;
    for (double x : g[a]) var += (x - mean) * (x - mean) / (tiles - 1);
    const double se = std::sqrt(var / tiles);
    const Vec3 v = dir(theta, phis[a]);
    std::printf("anisotropic (%.3f, %.3f) theta %.0f phi %.0f: G1 %.5f +- %.5f (between tiles), "
                "Smith alpha_o %.5f (alpha_o %.3f), z %.2f\n",
                ax, ay_eff, theta, phis[a], mean, se, nominal.G1(v), nominal.alpha_o(rad(phis[a])),
                (mean - nominal.G1(v)) / se);
    EXPECT_LT(std::abs(mean - nominal.G1(v)) / se, zmax) << "phi " << phis[a];
    worst_iso = std::max(worst_iso, std::abs(mean - iso.G1(v)) / se);
    means.push_back(mean);
  }
  EXPECT_GT(worst_iso, zmax);            // an isotropic model is rejected
  // Smoother along x: less masked at phi = 0 than at 90 (difference of two ensemble means).
  {
    double v0 = 0, v3 = 0;
    for (int k = 0; k < tiles; ++k) {
      v0 += (g[0][k] - means[0]) * (g[0][k] - means[0]) / (tiles - 1);
      v3 += (g[3][k] - means[3]) * (g[3][k] - means[3]) / (tiles - 1);
    }
    EXPECT_GT((means[0] - means[3]) / std::sqrt((v0 + v3) / tiles), sidak_t(0.01, 1, tiles - 1));
  }
}
