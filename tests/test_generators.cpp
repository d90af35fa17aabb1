// Structured and non-heightfield microsurfaces: exact geometric cases measured by the
// estimators (box, tiled boxes, V-groove, square wave, ellipsoid, undersurface, parallelepiped),
// the explicit V-cavity ensemble against its model, mesh validation, and the generators'
// identities [GeomBSDF24, eq. 1b/1c]. Every statistical test has a check that it can fail.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>

#include "microsim/measure/stats.hpp"
#include "microsim/statistics.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/ndf_measure.hpp"
#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/models/ndf.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/mesh_check.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/surface/undersurface.hpp"

using namespace microsim;

namespace {

using microsim::sidak_t;  // microsim/measure/stats.hpp
using microsim::sidak_z;

G1Options opts(std::uint64_t rays, std::uint64_t seed = 1) {
  G1Options o;
  o.rays = rays;
  o.seed = seed;
  return o;
}

std::string tmp(const std::string& name) { return ::testing::TempDir() + "microsim_gen_" + name; }

void write_file(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
}

// [Heitz14, eq. 24] in the cross-section plane: facet at signed angle tm, view at signed angle to.
double vgroove_g1(double to, double tm) {
  if (std::cos(to - tm) <= 0) return 0.0;
  return std::min(1.0, 2 * std::cos(tm) * std::cos(to) / std::cos(to - tm));
}

// The bin of a G1 result that holds the facet normal m.
int bin_with(const G1Result& r, const Vec3& m) { return r.binning.bin_of(m.normalized()); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Identities of the generators
// ---------------------------------------------------------------------------------------------

TEST(Generators, EveryKindSatisfiesEq1bAnd1cAndPassesMeshValidation) {
  BoxParams bp;
  bp.height = 0.7;
  BoxParams tp = bp;
  tp.tiles = 5;
  ParallelepipedParams pp;
  pp.tiles = 2;
  SquareWaveParams sw, sw2;
  sw2.two_d = true;
  sw2.duty = 0.3;
  VGrooveParams vg, pyr;
  pyr.two_d = true;
  EllipsoidParams el;
  el.rings = 16;
  el.segments = 64;
  el.alpha_y = 0.3;
  VCavityParams vc;
  vc.grooves = 64;
  std::vector<std::pair<std::string, Microsurface>> all = {
      {"box", generate_box(bp)},
      {"tiled-boxes", generate_tiled_boxes(tp)},
      {"parallelepiped", generate_parallelepiped(pp)},
      {"square-wave", generate_square_wave(sw)},
      {"square-wave-2d", generate_square_wave(sw2)},
      {"vgroove", generate_vgroove(vg)},
      {"pyramids", generate_vgroove(pyr)},
      {"ellipsoid", generate_ellipsoid(el)},
      {"vcavity", generate_vcavity(vc)}};
  for (const auto& [name, s] : all) {
    FacetSums f = facet_sums(s);
    // [GeomBSDF24, eq. 1b]: sum_f A_f m_f = n A;  eq. 1c: sum_f (n.m_f) A_f = A.
    EXPECT_LT((f.sum_area_normal / s.macro().area - Vec3::UnitZ()).norm(), 1e-9) << name;
    EXPECT_NEAR(f.sum_area_cos / s.macro().area, 1.0, 1e-9) << name;
    EXPECT_NO_THROW(check_mesh(s, name)) << name;
  }
  // The box's macro area is its base; the tiled boxes have the box's NDF (same facet areas per
  // normal, [GeomBSDF24, Fig. 6]) and the ellipsoid's rim polygon tends to pi / (ax ay).
  EXPECT_DOUBLE_EQ(all[0].second.macro().area, 1.0);
  EXPECT_NEAR(facet_sums(all[1].second).total_area, facet_sums(all[0].second).total_area, 1e-6);
  EXPECT_NEAR(all[7].second.macro().area, kPi / (0.5 * 0.3), 0.01 * kPi / 0.15);
}

TEST(Generators, ParallelepipedHasDownwardFacetsAndEq1bToRounding) {
  ParallelepipedParams p;
  p.width = 1.3;
  p.depth = 0.7;
  p.height = 0.9;
  const double L[9] = {1.1, 0.2, 0.8, -0.1, 0.9, -0.6, 0, 0, 1.2};
  std::copy(L, L + 9, p.matrix);
  Microsurface s = generate_parallelepiped(p);
  double down = 0;
  for (std::size_t k = 0; k < s.num_facets(); ++k)
    if (s.facet(k).normal().z() < -1e-3) down += s.facet(k).area();
  EXPECT_GT(down, 0.1);  // n.m < 0 present [GeomBSDF24, Fig. 3]
  FacetSums f = facet_sums(s);
  EXPECT_LT((f.sum_area_normal / s.macro().area - Vec3::UnitZ()).norm(), 1e-9);
  // The macro area is the mapped base: |det of the xy block| W D (up to float vertices).
  EXPECT_NEAR(s.macro().area, (1.1 * 0.9 + 0.2 * 0.1) * 1.3 * 0.7, 1e-6);
  p.matrix[6] = 0.1;
  EXPECT_THROW(generate_parallelepiped(p), UsageError);
}

TEST(Generators, BadParametersAreUsageErrors) {
  BoxParams b;
  b.height = 0;
  EXPECT_THROW(generate_box(b), UsageError);
  b = BoxParams{};
  b.tiles = 0;
  EXPECT_THROW(generate_tiled_boxes(b), UsageError);
  SquareWaveParams sw;
  sw.duty = 1.0;
  EXPECT_THROW(generate_square_wave(sw), UsageError);
  VGrooveParams vg;
  vg.facet_angle_deg = 90;
  EXPECT_THROW(generate_vgroove(vg), UsageError);
  EllipsoidParams el;
  el.alpha_x = -1;
  EXPECT_THROW(generate_ellipsoid(el), UsageError);
  VCavityParams vc;
  vc.ndf = "phong";
  EXPECT_THROW(generate_vcavity(vc), UsageError);
  GaussianGgxParams gg;
  gg.tail_fraction = 0;
  EXPECT_THROW(generate_gaussian_ggx(gg), UsageError);
}

// ---------------------------------------------------------------------------------------------
// Exact geometric cases, to 3 standard errors with standard error <= 1e-3
// ---------------------------------------------------------------------------------------------

TEST(ExactCases, BoxVisibleAreaRatioAcrossAFace) {
  // [GeomBSDF24, "Inherent Assumptions", Fig. 5]: seen across a face (phi = 0), the visible projected
  // area is W D cos(theta) + H D sin(theta): ratio 1 + (H/W) tan(theta).
  BoxParams p;
  p.width = 1.0;
  p.depth = 0.8;
  p.height = 0.5;
  Microsurface s = generate_box(p);
  Tracer tracer(s);
  for (double t : {30.0, 60.0, 80.0}) {
    G1Result r = measure_g1(tracer, direction_from_angles(rad(t), 0), opts(400000));
    Estimate e = r.visible_area_ratio();
    const double exact = 1 + 0.5 * std::tan(rad(t));
    EXPECT_LE(e.stderr_, 1e-3) << t;
    EXPECT_LT(std::abs(e.mean - exact), 3 * e.stderr_) << t << ": " << e.mean << " vs " << exact;
    // Power: the formula with sin instead of tan is refused.
    EXPECT_GT(std::abs(e.mean - (1 + 0.5 * std::sin(rad(t)))), 3 * e.stderr_) << t;
    // Every facet of a single box is visible from above (no masking).
    EXPECT_EQ(r.g1_area_sampling().mean, 1.0);
  }
}

TEST(ExactCases, TiledBoxesVisibleAreaRatioTendsToOne) {
  // [GeomBSDF24, Fig. 6]: N x N copies scaled by 1/N: ratio 1 + (H/(N W)) tan(theta). Of the walls facing
  // v (normal +x) only the last column's is visible: G1(v, +x) = 1/N, by both estimators (the
  // interior walls are pressed against their neighbours: buried twins).
  for (int n : {1, 4}) {
    BoxParams p;
    p.tiles = n;
    Microsurface s = generate_tiled_boxes(p);
    Tracer tracer(s);
    G1Result r = measure_g1(tracer, direction_from_angles(rad(60), 0), opts(200000));
    Estimate e = r.visible_area_ratio();
    EXPECT_LT(std::abs(e.mean - (1 + std::tan(rad(60)) / n)), 3 * e.stderr_ + 1e-12) << n;
    const int b = bin_with(r, Vec3::UnitX());
    Estimate g = r.bin_g1_area_sampling(b), gr = r.bin_g1_raycast(b);
    EXPECT_LT(std::abs(g.mean - 1.0 / n), 3 * g.stderr_ + 1e-12) << n;
    EXPECT_LT(std::abs(gr.mean - 1.0 / n), 3 * gr.stderr_ + 1e-6) << n;
  }
}

TEST(ExactCases, VGroovePerFacetG1IsEq24) {
  // [Heitz14, eq. 24] is exact on periodic V-grooves, per facet, in the cross-section plane.
  VGrooveParams p;
  p.facet_angle_deg = 45;
  Microsurface s = generate_vgroove(p);
  Tracer tracer(s);
  int tested = 0;
  for (double t : {50.0, 60.0, 70.0, 80.0}) {
    G1Result r = measure_g1(tracer, direction_from_angles(rad(t), 0), opts(300000));
    for (double sign : {1.0, -1.0}) {
      const double tm = sign * rad(45);
      const Vec3 m(std::sin(tm), 0, std::cos(tm));
      const int b = bin_with(r, m);
      const double exact = vgroove_g1(rad(t), tm);
      if (exact == 0.0) {
        EXPECT_EQ(r.bins[b].samples, 0u);  // back-facing: no sample, G1 = 0 by definition
        continue;
      }
      Estimate e = r.bin_g1_area_sampling(b), ea = r.bin_g1_raycast(b);
      EXPECT_LE(e.stderr_, 1e-3);
      // Floor 1e-6: the geometry is float (the facet angle is 45 deg to ~1e-7); the ray-cast
      // estimate is exact (error 0) when every ray lands on the one front-facing facet.
      EXPECT_LT(std::abs(e.mean - exact), 3 * std::max(e.stderr_, 1e-6)) << t << " " << sign;
      EXPECT_LT(std::abs(ea.mean - exact), 3 * std::max(ea.stderr_, 1e-6)) << t << " " << sign;
      // Power: the same data refuse eq. (24) with cos(theta_o) replaced by 1.01 cos(theta_o).
      if (exact < 1) { EXPECT_GT(std::abs(e.mean - 1.01 * exact), 3 * e.stderr_); }
      ++tested;
    }
  }
  EXPECT_EQ(tested, 4);
}

TEST(ExactCases, SquareWaveG1OfTheNormalNArea) {
  // Horizontal faces (tops and floors, normal n): the tops are all visible, a floor of width
  // (1-F)P loses a strip H tan(theta) |cos(phi)| in the shadow of the wall:
  // G1(v, n) = F + max(0, 1 - F - (H/P) tan(theta) |cos(phi)|).
  SquareWaveParams p;
  p.duty = 0.4;
  p.height = 0.3;
  Microsurface s = generate_square_wave(p);
  Tracer tracer(s);
  for (auto [t, ph] : {std::pair{20.0, 0.0}, {45.0, 0.0}, {60.0, 30.0}, {75.0, 0.0}}) {
    G1Result r = measure_g1(tracer, direction_from_angles(rad(t), rad(ph)), opts(800000));
    const int b = bin_with(r, Vec3::UnitZ());
    Estimate e = r.bin_g1_area_sampling(b);
    const double exact = 0.4 + std::max(0.0, 0.6 - 0.3 * std::tan(rad(t)) * std::abs(std::cos(rad(ph))));
    EXPECT_LE(e.stderr_, 1e-3);
    EXPECT_LT(std::abs(e.mean - exact), 3 * e.stderr_) << t << " " << ph;
    EXPECT_GT(std::abs(e.mean - (exact + 0.01)), 3 * e.stderr_);  // power
    // A periodic surface: every ray hits once, the visible area ratio is exactly 1.
    EXPECT_EQ(r.counters.lost_below + r.counters.unresolved, 0u);
    EXPECT_NEAR(r.visible_area_ratio().mean, 1.0, 1e-12);
  }
}

TEST(ExactCases, EllipsoidDIsGgxByChiSquare) {
  // [TSBlog24]: the upper half ellipsoid's normals are GGX(ax, ay). Vertical rays sample its normals
  // with density (n.m) D(m) (a heightfield over its base: G1(n, m) = 1), so the first-hit
  // histogram is multinomial with cell probabilities (A/W) int_B (n.m) D(m) dm, and a miss
  // probability 1 - A/W. Pearson chi^2 against GGX; the same counts refuse a 3% wrong alpha.
  EllipsoidParams p;
  p.alpha_x = 0.5;
  p.alpha_y = 0.35;
  p.rings = 192;  // the faceted D tends to GGX as (step)^2; at 96 x 384 chi^2 sees the bias
  p.segments = 768;
  Microsurface s = generate_ellipsoid(p);
  Tracer tracer(s);
  G1Options o = opts(3000000);
  o.normal_theta_bins = 18;  // 10 degree rings over the sphere, 45 degree sectors
  G1Result r = measure_g1(tracer, Vec3::UnitZ(), o);
  // Cells: the normal bins plus the misses; pooling and p-value by microsim/statistics.hpp.
  auto chi2 = [&](const models::Ndf& ndf) {
    const double n = static_cast<double>(r.raycast_rays), aw = s.macro().area / r.window_area_perp;
    std::vector<double> observed, expected;
    double hits = 0;
    for (int b = 0; b < r.binning.size(); ++b) {
      expected.push_back(n * aw * r.binning.solid_angle(b) *
                         r.binning.bin_average(b, [&](const Vec3& m) { return m.z() * ndf.D(m); }));
      observed.push_back(static_cast<double>(r.bins[b].raycast_hits));
      hits += observed.back();
    }
    observed.push_back(n - hits);
    expected.push_back(n * (1 - aw));
    return pearson_chi2(observed, expected);
  };
  const ChiSquareResult c = chi2(models::Ndf::ggx(0.5, 0.35));
  ASSERT_GT(c.dof, 40);
  EXPECT_GT(c.p_value, 1e-3) << c.summary();
  const ChiSquareResult c2 = chi2(models::Ndf::ggx(0.5 * 1.03, 0.35 * 1.03));
  EXPECT_LT(c2.p_value, 1e-3) << c2.summary();
  std::printf("[ info ] %s\n[ info ] alpha x1.03: %s\n", c.summary().c_str(), c2.summary().c_str());
}

TEST(ExactCases, EllipsoidNormalsAreGgxRingByRingAndBinnedDQuantizedByRings) {
  // The tessellation maps the u-rings theta_u = (pi/2) k / R of the unit hemisphere by
  // diag(1/a, 1/a, 1); on the smooth ellipsoid the normal there has tan(theta_m) = a tan(theta_u),
  // and the GGX mass of normals below theta_m, weighted by (n.m), is the CDF
  // F = tan^2 / (a^2 + tan^2) = sin^2(theta_u) ([TSBlog24]: the projected area of the cap over the base
  // ellipse's). Every facet of band k has its normal inside [m_k, m_k+1) and the bands' projected
  // areas are those of the rim polygons, so per band sum A_f (n.m_f) / A = F(m_k+1) - F(m_k)
  // exactly, up to the float rounding of the stored vertices. Isotropic: all S facets of a band
  // share one theta_m, so a fixed theta bin holds whole bands and its D differs from GGX by the
  // parts of the two bands its edges cut (a limit of the faceting, O(1/R) per bin).
  const double a = 0.5;
  EllipsoidParams p;
  p.alpha_x = p.alpha_y = a;
  p.rings = 64;
  p.segments = 256;
  const Microsurface s = generate_ellipsoid(p);
  const int R = p.rings;
  std::vector<double> theta(s.num_facets()), proj(s.num_facets());
  for (std::size_t k = 0; k < s.num_facets(); ++k) {
    const Vec3 c = s.facet(k).cross();
    theta[k] = std::acos(std::clamp(c.z() / c.norm(), -1.0, 1.0));
    proj[k] = 0.5 * c.z() / s.macro().area;  // A_f (n.m_f) / A
  }
  auto band_edge = [&](double alpha, int k) {  // theta_m of the u-ring k on GGX(alpha)'s ellipsoid
    return k == R ? 0.5 * kPi : std::atan(alpha * std::tan(0.5 * kPi * k / R));
  };
  auto cdf = [&](double alpha, double t) {  // int_{theta_m < t} D(m) (n.m) dm of GGX(alpha)
    if (t >= 0.5 * kPi) return 1.0;
    const double t2 = std::tan(t) * std::tan(t);
    return t2 / (alpha * alpha + t2);
  };
  auto sum_in = [&](double lo, double hi) {
    double sum = 0;
    for (std::size_t k = 0; k < theta.size(); ++k)
      if (theta[k] >= lo && theta[k] < hi) sum += proj[k];
    return sum;
  };
  // Vertices are floats: relative rounding 2^-24 per coordinate; a band's projected area is a
  // difference of two polygon areas, so a few float epsilons of the total (1) bound it.
  const double tol = 8 * std::numeric_limits<float>::epsilon();
  auto ring_error = [&](double alpha) {
    double worst = 0;
    for (int k = 0; k < R; ++k) {
      const double lo = band_edge(a, k), hi = band_edge(a, k + 1);
      worst = std::max(worst, std::abs(sum_in(lo, hi) - (cdf(alpha, hi) - cdf(alpha, lo))));
    }
    return worst;
  };
  EXPECT_LT(ring_error(a), tol);
  const double wrong = ring_error(1.001 * a);
  EXPECT_GT(wrong, tol);  // power: a 0.1% wrong alpha fails band by band

  // 5 degree bins: the facet sum is the GGX mass of the whole bands whose normals fall inside
  // (the same identity), and that differs from the bin's own GGX mass by up to the two cut bands.
  double worst_rel = 0;
  for (int b = 0; b < 18; ++b) {
    const double lo = rad(5.0 * b), hi = rad(5.0 * (b + 1));
    double whole = 0, cut = 0;
    for (int k = 0; k < R; ++k) {
      const double blo = band_edge(a, k), bhi = band_edge(a, k + 1);
      const double w = cdf(a, bhi) - cdf(a, blo);
      const double theta_band = theta[k == 0 ? 0 : static_cast<std::size_t>(p.segments) * (2 * k - 1)];
      if (theta_band >= lo && theta_band < hi) whole += w;
      if ((blo < lo && lo < bhi) || (blo < hi && hi < bhi)) cut += w;
    }
    const double measured = sum_in(lo, hi), model = cdf(a, hi) - cdf(a, lo);
    EXPECT_NEAR(measured, whole, tol) << b;
    EXPECT_LE(std::abs(measured - model), cut + tol) << b;
    worst_rel = std::max(worst_rel, std::abs(measured / model - 1));
  }
  // The limit is real: at 64 rings some 5 degree bin is off GGX by more than 30% (docs/theory/ndf.md:
  // 8.5% at the default 256 rings, 1.9% at 1024).
  EXPECT_GT(worst_rel, 0.3);
  std::printf("[ info ] band-by-band |error| %.2e (alpha x1.001: %.2e, tolerance %.2e); 5 deg bins "
              "worst |D/GGX - 1| %.3f at 64 rings\n", ring_error(a), wrong, tol, worst_rel);
}

TEST(ExactCases, EllipsoidLambdaIsGgxLambda) {
  // A convex object masks none of its front faces: its visible projected area along v is the
  // front-facing projected area, (v.n) A (1 + Lambda_GGX(v)) [TSBlog24, "G1 from projected areas"].
  EllipsoidParams p;
  p.alpha_x = p.alpha_y = 0.6;
  p.rings = 64;
  p.segments = 256;
  Microsurface s = generate_ellipsoid(p);
  Tracer tracer(s);
  const models::Ndf ggx = models::Ndf::ggx(0.6, 0.6);
  // Rays for a binomial standard error <= 1e-3 (it grows as 1/cos(theta)).
  for (auto [t, rays] : {std::pair{45.0, 600000}, {60.0, 800000}, {70.0, 1200000}}) {
    const Vec3 v = direction_from_angles(rad(t), rad(20));
    G1Result r = measure_g1(tracer, v, opts(rays));
    Estimate e = r.visible_area_ratio();
    EXPECT_LE(e.stderr_, 1e-3) << t;
    EXPECT_LT(std::abs(e.mean - 1 - ggx.Lambda(v)), 3 * e.stderr_) << t;
    EXPECT_GT(std::abs(e.mean - 1 - models::Ndf::ggx(0.63, 0.63).Lambda(v)), 3 * e.stderr_) << t;
    EXPECT_EQ(r.g1_area_sampling().mean, 1.0);  // convex: no masking
  }
}

TEST(ExactCases, BoxUndersurfaceVersusReverseAndReflectApproximations) {
  // From below (theta > 90) the box's undersurface is the inside of a box-shaped cavity: its
  // visible projected area is the opening, W D |cos(theta)|, of a front-facing projected area
  // W D |cos| + H D sin, so G1 = 1 / (1 + (H/W) tan(pi - theta)); both approximations of
  // [GeomBSDF24, "Inherent Assumptions"] use the box seen from above, where G1 = 1.
  BoxParams p;
  p.height = 0.5;
  Microsurface s = generate_box(p);
  Tracer tracer(s);
  const Vec3 v = direction_from_angles(rad(120), 0);
  G1Result under = measure_g1(tracer, v, opts(400000));
  EXPECT_TRUE(under.undersurface);
  Estimate e = under.g1_area_sampling();
  const double exact = 1 / (1 + 0.5 * std::tan(rad(60)));
  EXPECT_LE(e.stderr_, 1e-3);
  EXPECT_LT(std::abs(e.mean - exact), 3 * e.stderr_);
  EXPECT_NEAR(under.visible_area_ratio().mean, 1.0, 3 * under.visible_area_ratio().stderr_);
  EXPECT_EQ(measure_g1(tracer, -v, opts(100000)).g1_area_sampling().mean, 1.0);
  EXPECT_EQ(measure_g1(tracer, mirror_z(v), opts(100000)).g1_area_sampling().mean, 1.0);
  // Heightfields keep refusing views from below.
  Microsurface flat = generate_flat(FlatParams{});
  Tracer tf(flat);
  EXPECT_THROW(measure_g1(tf, v, opts(1000)), UsageError);
  EXPECT_THROW(measure_g1(tf, Vec3(1, 0, 0), opts(1000)), UsageError);
}

TEST(ExactCases, TiledParallelepipedsAreMaskedFromAbove) {
  // Sheared N x N tiles: the upward-facing slanted walls (normal ~ (-1, 0, s)) of all but the
  // first column lie against a neighbour: G1(n, m) = 1/N (not 1 as on a heightfield). A single
  // sheared box sticks out of its base: eq. 2b, the visible area ratio at v = n, is 1 + s H / W.
  ParallelepipedParams p;
  p.tiles = 3;  // shear x += 0.5 z by default
  Microsurface s = generate_parallelepiped(p);
  Tracer tracer(s);
  G1Result r = measure_g1(tracer, Vec3::UnitZ(), opts(400000));
  const int b = bin_with(r, Vec3(-1, 0, 0.5));
  Estimate e = r.bin_g1_area_sampling(b);
  EXPECT_LT(std::abs(e.mean - 1.0 / 3), 3 * e.stderr_);
  p.tiles = 1;
  Microsurface one = generate_parallelepiped(p);
  Tracer t1(one);
  Estimate ratio = measure_g1(t1, Vec3::UnitZ(), opts(400000)).visible_area_ratio();
  EXPECT_LT(std::abs(ratio.mean - 1.5), 3 * ratio.stderr_ + 1e-12);
}

// ---------------------------------------------------------------------------------------------
// The explicit V-cavity ensemble
// ---------------------------------------------------------------------------------------------

TEST(VCavity, EnsembleMatchesTheVCavityModelPerNormalBinNotSmith) {
  VCavityParams p;
  p.alpha_x = p.alpha_y = 0.6;
  p.grooves = 512;
  Microsurface s = generate_vcavity(p);
  // The stored strips carry the ensemble's D: Beckmann(0.6) sampled by projected area.
  std::vector<G1Result> res = measure_g1(vcavity_grooves(s, "test", GrooveFrames::StoredNormalOverHypot),
                                         {direction_from_angles(rad(70), rad(10)), direction_from_angles(rad(80), 0)},
                                         opts(1000000));
  for (const G1Result& r : res) {
    std::vector<double> z_vc, z_smith;
    for (int b = 0; b < r.binning.size(); ++b) {
      const G1NormalBin& nb = r.bins[b];
      if (nb.samples < 2000) continue;
      Estimate e = r.bin_g1_area_sampling(b);
      const double se = std::max(e.stderr_, 1.0 / nb.samples);
      z_vc.push_back((e.mean - nb.vcavity_weighted / nb.front_projected) / se);
      z_smith.push_back((e.mean - 1 / (1 + r.lambda_numeric)) / se);
    }
    ASSERT_GT(z_vc.size(), 10u);
    const double zmax = sidak_z(0.01, static_cast<int>(z_vc.size()));
    double worst_smith = 0;
    for (std::size_t k = 0; k < z_vc.size(); ++k) {
      EXPECT_LT(std::abs(z_vc[k]), zmax);
      worst_smith = std::max(worst_smith, std::abs(z_smith[k]));
    }
    EXPECT_GT(worst_smith, 10 * zmax);  // the ensemble is not Smith-masked per normal
    // Pooled over normals the visible area is (v.n) A: the averaged G1 equals Smith's exactly.
    EXPECT_NEAR(r.visible_area_ratio().mean, 1.0, 1e-12);
    Estimate g = r.g1_area_sampling();
    EXPECT_LT(std::abs(g.mean - 1 / (1 + r.lambda_numeric)), 3 * g.stderr_);
  }
}

// The grooves' normals are draws of the projected-area density (n.m) D(m) [Heitz14, Sec. 6.1]: the
// chi-square harness on lobe-following cells, for both NDFs and an anisotropic roughness; a 5%
// wrong roughness is refused by the same normals. (The generator stratifies the slope radius,
// which can only lower chi2: the pass is conservative, the power check is not weakened.)
TEST(VCavity, GrooveNormalsFollowTheProjectedNdf) {
  for (const char* ndf : {"beckmann", "ggx"}) {
    VCavityParams p;
    p.ndf = ndf;
    p.alpha_x = 0.3;
    p.alpha_y = 0.6;
    p.grooves = 100000;
    p.seed = 3;
    const Microsurface s = generate_vcavity(p);
    std::vector<Vec3> normals;
    for (int k = 0; k < p.grooves; ++k) normals.push_back(vcavity_groove_normal(s, k));
    const models::Ndf nominal = *s.nominal;
    const models::Ndf wrong = std::string(ndf) == "ggx" ? models::Ndf::ggx(0.315, 0.63) : models::Ndf::beckmann(0.315, 0.63);
    ChiSquareTest::Options o;
    o.res_u = 16;
    o.res_v = 32;
    ChiSquareTest t(ChiSquareDomain::hemisphere_slopes(std::sqrt(0.3 * 0.6)), normals,
                    [&](const Vec3& m) { return m.z() * nominal.D(m); }, o);
    EXPECT_TRUE(t.run().passed(0.01, 2)) << t.describe();
    EXPECT_NEAR(t.pdf_integral(), 1.0, 1e-4) << "the projected area of D is 1 [GeomBSDF24, eq. 1c]";
    const ChiSquareResult w = t.run_against([&](const Vec3& m) { return m.z() * wrong.D(m); });
    EXPECT_LT(w.p_value, 1e-4) << w.summary();
    std::printf("[ info ] %s: %s\n[ info ] alpha x1.05: %s\n", ndf, t.result().summary().c_str(), w.summary().c_str());
  }
}

TEST(VCavity, IdenticalForAnyThreadCount) {
  VCavityParams p;
  p.grooves = 64;
  Microsurface s = generate_vcavity(p);
  const std::vector<Vec3> views = {direction_from_angles(rad(75), rad(30))};
  std::vector<G1Result> a = measure_g1(vcavity_grooves(s, "test", GrooveFrames::StoredNormalOverHypot), views, opts(50000));
  std::vector<G1Result> b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    b = measure_g1(vcavity_grooves(s, "test", GrooveFrames::StoredNormalOverHypot), views, opts(50000));
  }
  EXPECT_EQ(a[0].raycast_hits, b[0].raycast_hits);
  EXPECT_EQ(a[0].sample_visible, b[0].sample_visible);
  for (int k = 0; k < a[0].binning.size(); ++k) {
    EXPECT_EQ(a[0].bins[k].visible, b[0].bins[k].visible);
    EXPECT_EQ(a[0].bins[k].visible_r, b[0].bins[k].visible_r);  // every replicate
    EXPECT_EQ(a[0].bins[k].raycast_hits_r, b[0].bins[k].raycast_hits_r);
  }
  EXPECT_EQ(a[0].counters.rays, b[0].counters.rays);
}

// ---------------------------------------------------------------------------------------------
// gaussian-ggx
// ---------------------------------------------------------------------------------------------

TEST(GaussianGgx, TheScaleMixtureIdentityHolds) {
  // GGX(alpha) = int_0^inf Beckmann(alpha / sqrt(E)) e^-E dE, checked on D (the generator's
  // construction principle) by Gauss-Laguerre-like quadrature on a fine grid in E.
  const double alpha = 0.4;
  const models::Ndf ggx = models::Ndf::ggx(alpha, alpha);
  for (double t : {0.0, 15.0, 40.0, 70.0}) {
    const Vec3 m = direction_from_angles(rad(t), 0.3);
    double sum = 0;
    const int n = 200000;
    for (int k = 0; k < n; ++k) {  // substitution E = -ln(u): int_0^1 Beckmann(alpha/sqrt(E)) du
      const double u = (k + 0.5) / n, e = -std::log(u);
      sum += models::Ndf::beckmann(alpha / std::sqrt(e), alpha / std::sqrt(e)).D(m) / n;
    }
    EXPECT_NEAR(sum / ggx.D(m), 1.0, 2e-3) << t;
  }
}

TEST(GaussianGgx, TileHasHeavierTailsThanBeckmannWithTheSameCore) {
  GaussianGgxParams p;
  p.resolution = 512;
  p.correlation_length = 4.0 / 512;  // 4 cells per l
  p.alpha_x = p.alpha_y = 0.3;
  // Roughness field E(x) correlated over 16 cells (4 correlation lengths of the heights): 1024
  // roughness patches on the tile.
  p.roughness_correlation_length = 16.0 / 512;
  Microsurface s = generate_gaussian_ggx(p);
  ASSERT_TRUE(s.nominal.has_value());
  EXPECT_EQ(s.nominal->kind, models::Distribution::GGX);
  // Projected-area fraction with slope beyond 3 alpha: GGX 1/(1+9) = 0.10, Beckmann e^-9.
  // The fraction varies from roughness patch to patch: its error is the spread of 16 x 16 blocks
  // of 32 x 32 cells (Student t with 255 degrees of freedom).
  constexpr int nb = 16;
  std::vector<double> beyond(nb * nb, 0.0), total(nb * nb, 0.0);
  for (std::size_t k = 0; k < s.num_facets(); ++k) {
    Triangle t = s.facet(k);
    const Vec3 m = t.normal();
    const Vec3 c = (t.p0 + t.p1 + t.p2) / 3.0;
    const int bx = std::clamp(static_cast<int>((c.x() / p.size + 0.5) * nb), 0, nb - 1);
    const int by = std::clamp(static_cast<int>((c.y() / p.size + 0.5) * nb), 0, nb - 1);
    const double w = t.area() * m.z();
    total[bx + nb * by] += w;
    if (std::hypot(m.x(), m.y()) / m.z() > 0.9) beyond[bx + nb * by] += w;
  }
  double mean = 0, ss = 0;
  std::vector<double> f(nb * nb);
  for (int b = 0; b < nb * nb; ++b) mean += (f[b] = beyond[b] / total[b]) / (nb * nb);
  for (double x : f) ss += (x - mean) * (x - mean);
  const double se = std::sqrt(ss / (nb * nb - 1) / (nb * nb));
  const double tt = sidak_t(0.01, 1, nb * nb - 1);
  EXPECT_LT(std::abs(mean - 0.10) / se, tt) << mean << " +- " << se;
  // Power: Beckmann's tail (e^-9) and GGX with alpha 25% smaller or larger (1/(1 + 9 * 1.25^2),
  // 1/(1 + 9 / 1.25^2)) are rejected.
  EXPECT_GT(std::abs(mean - std::exp(-9.0)) / se, tt) << mean << " +- " << se;
  EXPECT_GT(std::abs(mean - 1 / (1 + 9 * 1.25 * 1.25)) / se, tt) << mean << " +- " << se;
  EXPECT_GT(std::abs(mean - 1 / (1 + 9 / (1.25 * 1.25))) / se, tt) << mean << " +- " << se;
}

// ---------------------------------------------------------------------------------------------
// Mesh files: validation and round trips
// ---------------------------------------------------------------------------------------------

TEST(MeshFiles, RoundTripKeepsFacetsMacrosurfaceAndKind) {
  BoxParams bp;
  bp.tiles = 2;
  VCavityParams vp;
  vp.grooves = 10;
  for (const Microsurface& s : {generate_tiled_boxes(bp), generate_vcavity(vp), generate_square_wave({})}) {
    for (const char* ext : {"ply", "obj", "off"}) {
      const std::string path = tmp(std::string("rt.") + ext);
      save_surface(s, path);
      Microsurface t = load_surface(path);
      ASSERT_EQ(t.num_facets(), s.num_facets()) << ext;
      for (std::size_t k = 0; k < s.num_facets(); ++k)
        EXPECT_LT((t.facet(k).p0 - s.facet(k).p0).norm(), 1e-6) << ext;
      EXPECT_EQ(t.macro().periodic, s.macro().periodic);
      EXPECT_DOUBLE_EQ(t.macro().area, s.macro().area);
      EXPECT_EQ(is_vcavity(t), is_vcavity(s));
      std::remove(path.c_str());
      std::remove((path + ".json").c_str());
    }
  }
}

struct BadMesh {
  const char* name;
  const char* off;
  const char* needle;
};
const BadMesh kBadMeshes[] = {
    // Three triangles on one edge.
    {"nonmanifold", "OFF\n5 3 0\n0 0 1\n1 0 1\n0 1 1\n0 -1 1\n0 0 2\n3 0 1 2\n3 1 0 3\n3 0 1 4\n",
     "non-manifold"},
    // Two triangles running their shared edge the same way.
    {"flipped", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 0 1 3\n", "non-manifold"},
    {"repeated", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 0 1\n", "degenerate"},
    {"zero_area", "OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n", "degenerate"},
    // A box without its top: open where it must be closed.
    {"open", "OFF\n8 8 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
             "3 1 2 6\n3 1 6 5\n3 0 4 7\n3 0 7 3\n3 3 7 6\n3 3 6 2\n3 0 1 5\n3 0 5 4\n",
     "open mesh"},
    // A closed tetrahedron has no rim: zero signed projected area.
    {"closed", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n",
     "closed mesh"},
    {"notamesh", "hello\n", "not a readable mesh"},
};
class BadMeshes : public ::testing::TestWithParam<BadMesh> {};

TEST_P(BadMeshes, AreRefusedWithOneLine) {
  const BadMesh& c = GetParam();
  const std::string path = tmp(std::string(c.name) + ".off");
  write_file(path, c.off);
  MeshImportParams p;
  p.input = path;
  try {
    import_mesh(p);
    ADD_FAILURE() << c.name << " was accepted";
  } catch (const UsageError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(c.needle), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos);
  }
  std::remove(path.c_str());
}
INSTANTIATE_TEST_SUITE_P(MeshFiles, BadMeshes, ::testing::ValuesIn(kBadMeshes),
                         [](const ::testing::TestParamInfo<BadMesh>& i) { return std::string(i.param.name); });

TEST(MeshFiles, ImportOfAPeriodicTileChecksItsBorders) {
  // The square wave without its sidecar, declared periodic: accepted with the right tile,
  // refused when the tile is too small (vertices outside) or too large (boundary off the border).
  const std::string path = tmp("tile.ply");
  save_surface(generate_square_wave({}), path);
  std::remove((path + ".json").c_str());
  MeshImportParams p;
  p.input = path;
  p.periodic = true;
  p.tile_x = p.tile_y = 1.0;
  Microsurface s = import_mesh(p);
  EXPECT_TRUE(s.macro().periodic);
  EXPECT_DOUBLE_EQ(s.macro().area, 1.0);
  p.tile_x = 0.9;
  EXPECT_THROW(import_mesh(p), UsageError);
  p.tile_x = 1.2;
  EXPECT_THROW(import_mesh(p), UsageError);
  std::remove(path.c_str());
}

TEST(MeshFiles, ImportRotatesTheDeclaredNormalAndFindsTheArea) {
  // An open unit cube standing on the plane x = 0 (its rim), outward normals: declared n = -x
  // ... becomes a box on z = 0 with A = 1 and eq. 1b exact.
  const std::string path = tmp("sideways.off");
  // Box [0,1]^3 without its x = 0 face, oriented outward.
  write_file(path,
             "OFF\n8 10 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
             "3 0 2 1\n3 0 3 2\n3 4 5 6\n3 4 6 7\n3 1 2 6\n3 1 6 5\n3 0 1 5\n3 0 5 4\n"
             "3 3 7 6\n3 3 6 2\n");
  MeshImportParams p;
  p.input = path;
  p.normal = Vec3(1, 0, 0);
  Microsurface s = import_mesh(p);
  EXPECT_NEAR(s.macro().area, 1.0, 1e-6);
  EXPECT_FALSE(s.macro().periodic);
  EXPECT_NEAR(s.bounds().min().z(), 0.0, 1e-6);
  EXPECT_NEAR(s.bounds().max().z(), 1.0, 1e-6);
  p.normal = Vec3(-1, 0, 0);  // wrong side: the mesh is inside-out for this normal
  EXPECT_THROW(import_mesh(p), UsageError);
  std::remove(path.c_str());
}
