// Tests of include/microsim/models/ndf.hpp: NDFs, Smith Lambda / G1 / G2, VNDF and its sampler,
// V-cavity. Where theory is exact the tests use deterministic quadrature with tolerances far above
// the quadrature error and far below the size of a plausible formula mistake; the statistical
// tests use fixed seeds and thresholds derived from the estimator's own standard error or the
// chi-square harness of microsim/statistics.hpp.
#include <gtest/gtest.h>

#include <microsim/models/ndf.hpp>
#include <microsim/statistics.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>
#include <vector>

namespace {

using microsim::models::Distribution;
using microsim::models::Ndf;
using microsim::models::Vec3;
namespace mm = microsim::models;

constexpr double kPi = 3.14159265358979323846;

Vec3 dir(double theta, double phi) {
  return Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
}
double deg(double d) { return d * kPi / 180.0; }

Ndf make(Distribution d, double ax, double ay) {
  return d == Distribution::Beckmann ? Ndf::beckmann(ax, ay) : Ndf::ggx(ax, ay);
}

// ---------------------------------------------------------------------------------------------
// Quadrature helpers (composite Gauss-Legendre with panels refined geometrically around a point)
// ---------------------------------------------------------------------------------------------
struct Rule {
  std::vector<double> x, w;
};

// Panels on [a, b] with edges center +- c 2^k (k = 0, 1, ...) around each center, panels no
// wider than max_width, n Gauss-Legendre nodes each: resolves peaks and endpoint singularities
// at the given centers.
Rule refined_rule(double a, double b, const std::vector<double>& centers, double c, int n,
                  double max_width = 0.25) {
  std::vector<double> edges = {a, b};
  for (double center : centers) {
    if (center > a && center < b) edges.push_back(center);
    for (double d = c; d < 2.0 * (b - a); d *= 2.0) {
      if (center - d > a && center - d < b) edges.push_back(center - d);
      if (center + d > a && center + d < b) edges.push_back(center + d);
    }
  }
  const int nuni = static_cast<int>(std::ceil((b - a) / max_width));
  for (int k = 1; k < nuni; ++k) edges.push_back(a + (b - a) * k / nuni);
  std::sort(edges.begin(), edges.end());
  const auto gl = mm::detail::gauss_legendre(n);
  Rule r;
  for (std::size_t k = 0; k + 1 < edges.size(); ++k) {
    if (edges[k + 1] - edges[k] < 1e-14) continue;
    const double m = 0.5 * (edges[k] + edges[k + 1]), h = 0.5 * (edges[k + 1] - edges[k]);
    for (const auto& [x, w] : gl) {
      r.x.push_back(m + h * x);
      r.w.push_back(w * h);
    }
  }
  return r;
}

// Integral over the hemisphere of normals m of f(m) dw_m (theta refined near 0 at the roughness
// scale, phi by the periodic trapezoid rule, spectrally accurate for smooth periodic integrands).
template <class F>
double integrate_hemisphere(const F& f, double scale, int nphi = 512) {
  const Rule th = refined_rule(0.0, kPi / 2, {0.0}, scale / 8.0, 16);
  double sum = 0.0;
  for (std::size_t a = 0; a < th.x.size(); ++a) {
    const double st = std::sin(th.x[a]);
    double row = 0.0;
    for (int b = 0; b < nphi; ++b) row += f(dir(th.x[a], 2 * kPi * b / nphi));
    sum += th.w[a] * st * row * (2 * kPi / nphi);
  }
  return sum;
}

// [Heitz14, eq. 19] weak white furnace integral over the sphere of incident directions i:
// int G1(o, h) D(h) / (4 |o.n|) dw_i, h = (o + i)/|o + i|. Integrated in theta_i over
// [0, pi - theta_o] only: beyond, h.z <= 0 and D(h) = 0 (for GGX D jumps there, so the jump is
// put on the domain boundary). Product Gauss-Legendre, with panels refined geometrically around
// the mirror direction (theta_i = theta_o, phi_i = phi_o + pi) and around i = -o (theta_i =
// pi - theta_o, same phi): near -o, h = (o+i)/|o+i| sweeps a whole great circle, so for a
// grazing o the lobe of D is squeezed into a tiny neighbourhood of -o (the reason why the
// uniform grid of [Heitz14, App. C] needs small steps). Quadrature error measured < 3e-6.
template <class G1>
double weak_white_furnace(const Ndf& ndf, const Vec3& o, const G1& g1) {
  const double to = std::acos(std::clamp(o.z(), -1.0, 1.0));
  const double po = std::atan2(o.y(), o.x());
  const double c = std::min(ndf.alpha_x, ndf.alpha_y) / 16.0;
  const Rule th = refined_rule(0.0, kPi - to, {to, kPi - to}, c, 8);
  const Rule ph = refined_rule(po, po + 2 * kPi, {po + kPi}, c, 8);
  double sum = 0.0;
  for (std::size_t a = 0; a < th.x.size(); ++a) {
    double row = 0.0;
    for (std::size_t b = 0; b < ph.x.size(); ++b) {
      const Vec3 i = dir(th.x[a], ph.x[b]);
      const Vec3 hsum = o + i;
      const double len = hsum.norm();
      if (len == 0.0) continue;
      const Vec3 h = hsum / len;
      row += ph.w[b] * g1(o, h) * ndf.D(h) / (4.0 * std::abs(o.z()));
    }
    sum += th.w[a] * std::sin(th.x[a]) * row;
  }
  return sum;
}

TEST(Quadrature, GaussLegendreIsExactForPolynomials) {
  for (int n : {5, 10, 16}) {
    const auto r = mm::detail::gauss_legendre(n);
    for (int deg = 0; deg <= 2 * n - 1; ++deg) {
      double s = 0.0;
      for (const auto& [x, w] : r) s += w * std::pow(x, deg);
      const double exact = (deg % 2) ? 0.0 : 2.0 / (deg + 1);
      EXPECT_NEAR(s, exact, 1e-14) << "n=" << n << " deg=" << deg;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Construction, conventions, edge cases
// ---------------------------------------------------------------------------------------------
TEST(Ndf, ConstructorsValidateRoughness) {
  EXPECT_THROW(Ndf::beckmann(0.0, 0.5), std::invalid_argument);
  EXPECT_THROW(Ndf::beckmann(0.5, -0.1), std::invalid_argument);
  EXPECT_THROW(Ndf::ggx(std::nan(""), 0.5), std::invalid_argument);
  EXPECT_THROW(Ndf::ggx(0.5, std::numeric_limits<double>::infinity()), std::invalid_argument);
  const Ndf n = Ndf::ggx(0.3, 0.6);
  EXPECT_EQ(n.kind, Distribution::GGX);
  EXPECT_FALSE(n.isotropic());
  EXPECT_TRUE(Ndf::beckmann(0.4, 0.4).isotropic());
  EXPECT_STREQ(mm::to_string(Distribution::Beckmann), "beckmann");
  EXPECT_STREQ(mm::to_string(Distribution::GGX), "ggx");
}

TEST(Ndf, DEqualsSlopeDistributionOverCos4) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (auto kind : {Distribution::Beckmann, Distribution::GGX}) {
    const Ndf ndf = make(kind, 0.35, 0.8);
    for (int k = 0; k < 200; ++k) {
      const double ut = u(rng), up = u(rng);  // named: argument evaluation order is unspecified
      const Vec3 m = dir(std::acos(ut), 2 * kPi * up);
      const double expect = ndf.P22(-m.x() / m.z(), -m.y() / m.z()) / std::pow(m.z(), 4);
      EXPECT_NEAR(ndf.D(m), expect, 1e-12 * std::max(1.0, expect));
    }
    EXPECT_EQ(ndf.D(Vec3(0.6, 0.0, -0.8)), 0.0);
    EXPECT_TRUE(std::isfinite(ndf.D(Vec3(1.0, 0.0, 1e-200).normalized())));
  }
  // Beckmann slope variance per axis is alpha^2 / 2: P22 is the product of two Gaussians.
  const Ndf b = Ndf::beckmann(0.3, 0.7);
  const double sx = 0.3 / std::sqrt(2.0), sy = 0.7 / std::sqrt(2.0);
  const double x = 0.2, y = -0.5;
  const double gauss = std::exp(-x * x / (2 * sx * sx) - y * y / (2 * sy * sy)) / (2 * kPi * sx * sy);
  EXPECT_NEAR(b.P22(x, y), gauss, 1e-14);
}

TEST(Ndf, EdgeCases) {
  for (auto kind : {Distribution::Beckmann, Distribution::GGX}) {
    const Ndf ndf = make(kind, 0.3, 0.5);
    EXPECT_EQ(ndf.Lambda(Vec3(0, 0, 1)), 0.0);
    EXPECT_EQ(ndf.G1(Vec3(0, 0, 1)), 1.0);
    EXPECT_TRUE(std::isinf(ndf.Lambda(Vec3(1, 0, 0))));
    EXPECT_TRUE(std::isinf(ndf.Lambda(dir(deg(100), 0.3))));
    EXPECT_EQ(ndf.G1(dir(deg(100), 0.3)), 0.0);
    EXPECT_EQ(ndf.G1(Vec3(1, 0, 0)), 0.0);
    EXPECT_EQ(ndf.D_visible(dir(deg(100), 0.3), Vec3(0, 0, 1)), 0.0);
    EXPECT_EQ(ndf.G1(dir(deg(40), 0.0), dir(deg(60), kPi)), 0.0);  // back-facing normal
    // grazing but above the horizon: finite, small G1
    const double g = ndf.G1(dir(deg(89.999), 0.2));
    EXPECT_GT(g, 0.0);
    EXPECT_LT(g, 0.01);
    EXPECT_THROW(ndf.sample_visible_normal(dir(deg(100), 0.0), 0.5, 0.5), std::invalid_argument);
    // exactly grazing view: sampler is defined (limit), returns front-facing upper normals
    const Vec3 vg(std::cos(0.4), std::sin(0.4), 0.0);
    for (double u1 : {0.0, 0.1, 0.5, 0.9, 1.0})
      for (double u2 : {0.0, 0.3, 0.999999, 1.0}) {
        const Vec3 m = ndf.sample_visible_normal(vg, u1, u2);
        EXPECT_NEAR(m.norm(), 1.0, 1e-12);
        EXPECT_GE(m.z(), 0.0);
        EXPECT_GE(vg.dot(m), -1e-12);
      }
  }
  EXPECT_EQ(mm::beckmann_lambda(std::numeric_limits<double>::infinity()), 0.0);
  EXPECT_EQ(mm::ggx_lambda(std::numeric_limits<double>::infinity()), 0.0);
  EXPECT_TRUE(std::isinf(mm::beckmann_lambda(0.0)));
  EXPECT_TRUE(std::isinf(mm::ggx_lambda(0.0)));
  // large a: no cancellation (asymptotic Lambda ~ exp(-a^2) / (4 a^3 sqrt(pi)) (1 - 3/(2a^2)))
  const double a = 6.0;
  const double asym = std::exp(-a * a) / (4 * a * a * a * std::sqrt(kPi)) *
                      (1 - 3 / (2 * a * a) + 15 / (4 * a * a * a * a));
  EXPECT_NEAR(mm::beckmann_lambda(a) / asym, 1.0, 2e-3);
  EXPECT_NEAR(mm::ggx_lambda(1e5) / (0.25e-10), 1.0, 1e-9);  // Lambda ~ 1/(4 a^2)
}

// ---------------------------------------------------------------------------------------------
// [Heitz14, eq. 2]: int (n.m) D(m) dm = 1
// ---------------------------------------------------------------------------------------------
const std::vector<std::pair<double, double>> kAlphas = {
    {0.1, 0.1}, {0.3, 0.3}, {0.7, 0.7}, {1.5, 1.5}, {0.1, 0.4}, {0.6, 1.5}, {1.2, 0.25}};

TEST(Ndf, ProjectedAreaNormalization) {
  double worst = 0.0;
  for (auto kind : {Distribution::Beckmann, Distribution::GGX})
    for (const auto& [ax, ay] : kAlphas) {
      const Ndf ndf = make(kind, ax, ay);
      const double I = integrate_hemisphere([&](const Vec3& m) { return m.z() * ndf.D(m); },
                                            std::min(ax, ay));
      EXPECT_NEAR(I, 1.0, 1e-4) << mm::to_string(kind) << " " << ax << " " << ay;
      worst = std::max(worst, std::abs(I - 1.0));
    }
  std::printf("[ info ] max |int (n.m) D dm - 1| = %.2e\n", worst);
}

// ---------------------------------------------------------------------------------------------
// [Heitz14, eq. 13-14]: int D_v(m) dm = 1, and eq. (19) weak white furnace test
// ---------------------------------------------------------------------------------------------
TEST(Ndf, VisibleNormalsNormalized) {
  double worst = 0.0;
  for (auto kind : {Distribution::Beckmann, Distribution::GGX})
    for (const auto& [ax, ay] : kAlphas)
      for (double th : {0.0, 30.0, 60.0, 80.0, 89.0})
        for (double ph : {0.0, 0.7}) {
          if (ax == ay && ph != 0.0) continue;
          const Ndf ndf = make(kind, ax, ay);
          const Vec3 v = dir(deg(th), ph);
          const double I = integrate_hemisphere([&](const Vec3& m) { return ndf.D_visible(v, m); },
                                                std::min(ax, ay));
          EXPECT_NEAR(I, 1.0, 1e-4) << mm::to_string(kind) << " " << ax << " " << ay << " th=" << th;
          worst = std::max(worst, std::abs(I - 1.0));
        }
  std::printf("[ info ] max |int D_v dm - 1| = %.2e\n", worst);
}

TEST(Ndf, WeakWhiteFurnaceEq19) {
  double worst = 0.0;
  for (auto kind : {Distribution::Beckmann, Distribution::GGX})
    for (const auto& [ax, ay] : kAlphas)
      for (double th : {0.0, 30.0, 60.0, 80.0, 89.0})
        for (double ph : {0.0, 1.0}) {
          if (ax == ay && ph != 0.0) continue;
          const Ndf ndf = make(kind, ax, ay);
          const Vec3 o = dir(deg(th), ph);
          const double I =
              weak_white_furnace(ndf, o, [&](const Vec3& v, const Vec3& h) { return ndf.G1(v, h); });
          EXPECT_NEAR(I, 1.0, 1e-4) << mm::to_string(kind) << " " << ax << " " << ay << " th=" << th;
          worst = std::max(worst, std::abs(I - 1.0));
        }
  std::printf("[ info ] max |eq.(19) - 1| = %.2e\n", worst);
}

// [Heitz14, Sec. 6.2]: "The result of the integral is always 1" with the V-cavity G1 (eq. 24), for any
// symmetric D. (Pairing m with m' = (-mx, -my, mz): min(o.m, 2 mz oz) + min(o.m', 2 mz oz) = 2 mz oz.)
TEST(VCavity, WeakWhiteFurnace) {
  double worst = 0.0;
  for (auto kind : {Distribution::Beckmann, Distribution::GGX})
    for (const auto& [ax, ay] : {std::pair{0.3, 0.3}, std::pair{1.2, 0.25}})
      for (double th : {0.0, 45.0, 80.0}) {
        const Ndf ndf = make(kind, ax, ay);
        const Vec3 o = dir(deg(th), 0.4);
        const double I = weak_white_furnace(ndf, o, [](const Vec3& v, const Vec3& h) {
          return mm::vcavity_G1(v, h);
        });
        EXPECT_NEAR(I, 1.0, 1e-4) << mm::to_string(kind) << " " << ax << " th=" << th;
        worst = std::max(worst, std::abs(I - 1.0));
      }
  std::printf("[ info ] max |eq.(19) with V-cavity G1 - 1| = %.2e\n", worst);
}

// ---------------------------------------------------------------------------------------------
// Lambda: closed forms vs [Heitz14, App. A] numerical integration
// ---------------------------------------------------------------------------------------------
TEST(Lambda, MarginalFormulaMatchesClosedForms) {
  for (double alpha : {0.1, 0.5, 1.3})
    for (double mu : {0.05, 0.3, 1.0, 2.5}) {
      auto beck = [alpha](double q) { return std::exp(-q * q / (alpha * alpha)) / (alpha * std::sqrt(kPi)); };
      auto ggx = [alpha](double q) { return 0.5 / (alpha * std::pow(1 + q * q / (alpha * alpha), 1.5)); };
      const double lb = mm::beckmann_lambda(mu / alpha), lg = mm::ggx_lambda(mu / alpha);
      EXPECT_NEAR(mm::lambda_from_slope_marginal(beck, mu) / lb, 1.0, 1e-8) << alpha << " " << mu;
      EXPECT_NEAR(mm::lambda_from_slope_marginal(ggx, mu) / lg, 1.0, 1e-8) << alpha << " " << mu;
    }
  auto beck = [](double q) { return std::exp(-q * q) / std::sqrt(kPi); };
  EXPECT_EQ(mm::lambda_from_slope_marginal(beck, std::numeric_limits<double>::infinity()), 0.0);
  EXPECT_TRUE(std::isinf(mm::lambda_from_slope_marginal(beck, 0.0)));
}

struct LambdaCase {
  Distribution kind;
  double ax, ay;
  std::vector<double> phis;
};
class LambdaClosedForm : public ::testing::TestWithParam<LambdaCase> {};

TEST_P(LambdaClosedForm, MatchesSlopeDistribution) {
  const LambdaCase& c = GetParam();
  const Ndf ndf = make(c.kind, c.ax, c.ay);
  double worst = 0.0;
  for (double th : {20.0, 60.0, 85.0})
    for (double ph : c.phis) {
      const Vec3 v = dir(deg(th), ph);
      const double exact = ndf.Lambda(v);
      const double num = mm::lambda_from_slope_distribution([&](double x, double y) { return ndf.P22(x, y); }, v);
      const double rel = std::abs(num / exact - 1.0);
      EXPECT_LT(rel, 1e-6) << "th=" << th << " ph=" << ph << " closed=" << exact << " numeric=" << num;
      worst = std::max(worst, rel);
    }
  std::printf("[ info ] max relative |Lambda closed - Lambda numeric| = %.2e\n", worst);
}
std::string lambda_case_name(const ::testing::TestParamInfo<LambdaCase>& i) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%s_a%03.0fx%03.0f", mm::to_string(i.param.kind), 100 * i.param.ax, 100 * i.param.ay);
  return buf;
}
INSTANTIATE_TEST_SUITE_P(Lambda, LambdaClosedForm,
                         ::testing::Values(LambdaCase{Distribution::Beckmann, 0.3, 0.3, {0.7}},
                                           LambdaCase{Distribution::Beckmann, 0.2, 0.8, {0.0, 0.5, 2.2}},
                                           LambdaCase{Distribution::Beckmann, 1.2, 0.5, {1.1, 4.0}},
                                           LambdaCase{Distribution::GGX, 0.3, 0.3, {0.7}},
                                           LambdaCase{Distribution::GGX, 0.2, 0.8, {0.0, 0.5, 2.2}},
                                           LambdaCase{Distribution::GGX, 1.2, 0.5, {1.1, 4.0}}),
                         lambda_case_name);

TEST(Lambda, NumericOfAConstantAtNormalViewIsZero) {
  EXPECT_EQ(mm::lambda_from_slope_distribution([](double, double) { return 1.0; }, Vec3(0, 0, 1)), 0.0);
}

// Walter et al. rational approximation vs the exact erf form, on a in [0.05, 10] (step 5e-4).
// Verified: max |Lambda_rat - Lambda| = 9.85e-3 (at a ~ 0.082, where Lambda ~ 3.1; relative
// 0.35%), max |G1_rat - G1| = 3.11e-3 (at a ~ 1.34), max relative G1 error 0.313%. The relative
// error of Lambda itself is large where Lambda is small (the rational form has roots at a = 1.548
// and 1.631, and is slightly negative, down to -6.1e-5, on [1.548, 1.6)); G1 is what it was
// fitted to. Bounds tested: 1.0e-2 (Lambda, absolute), 3.2e-3 (G1 absolute and relative).
TEST(Lambda, BeckmannRationalApproximation) {
  double max_abs = 0.0, max_g1 = 0.0, max_g1_rel = 0.0, min_rat = 0.0;
  for (int k = 0; k <= 19900; ++k) {
    const double a = 0.05 + 5e-4 * k;
    const double ex = mm::beckmann_lambda(a), ap = mm::beckmann_lambda_rational(a);
    max_abs = std::max(max_abs, std::abs(ap - ex));
    const double g_ex = 1 / (1 + ex), g_ap = 1 / (1 + ap);
    max_g1 = std::max(max_g1, std::abs(g_ap - g_ex));
    max_g1_rel = std::max(max_g1_rel, std::abs(g_ap / g_ex - 1));
    min_rat = std::min(min_rat, ap);
  }
  std::printf("[ info ] rational Lambda on a in [0.05,10]: max |dLambda| %.3e, max |dG1| %.3e, "
              "max rel dG1 %.3e, min %.2e\n", max_abs, max_g1, max_g1_rel, min_rat);
  EXPECT_LT(max_abs, 1.0e-2);
  EXPECT_LT(max_g1, 3.2e-3);
  EXPECT_LT(max_g1_rel, 3.2e-3);
  // it is an approximation, not the exact formula: the error is of the published size
  EXPECT_GT(max_g1, 2e-3);
  EXPECT_NE(mm::beckmann_lambda_rational(0.8), mm::beckmann_lambda(0.8));
  EXPECT_LT(min_rat, 0.0);
  EXPECT_GT(min_rat, -1e-4);
  EXPECT_EQ(mm::beckmann_lambda_rational(1.6), 0.0);
  EXPECT_GT(mm::beckmann_lambda(1.6), 0.0);
  // for small a both tend to the same leading term 1/(2 a sqrt(pi)) vs 1/(3.535 a)
  EXPECT_NEAR(mm::beckmann_lambda_rational(1e-4) / mm::beckmann_lambda(1e-4), 2 * std::sqrt(kPi) / 3.535, 1e-3);
}

// ---------------------------------------------------------------------------------------------
// [Heitz14, eq. 11]: projected roughness
// ---------------------------------------------------------------------------------------------
TEST(Lambda, ProjectedRoughnessAndStretching) {
  for (auto kind : {Distribution::Beckmann, Distribution::GGX}) {
    const double ax = 0.15, ay = 0.9;
    const Ndf an = make(kind, ax, ay);
    EXPECT_NEAR(an.alpha_o(0.0), ax, 1e-15);
    EXPECT_NEAR(an.alpha_o(kPi / 2), ay, 1e-15);
    for (double ph : {0.0, 0.3, 1.0, 1.9, 3.5, 5.9})
      for (double th : {10.0, 45.0, 75.0, 88.0}) {
        const Vec3 v = dir(deg(th), ph);
        // isotropic surface with the projected roughness
        const Ndf iso = make(kind, an.alpha_o(ph), an.alpha_o(ph));
        EXPECT_NEAR(an.Lambda(v), iso.Lambda(v), 1e-12 * std::max(1.0, iso.Lambda(v)));
        // independent stretching [Heitz14, Sec. 3.3]: scale x by ax/ay -> isotropic roughness ay,
        // stretched view (ax/ay vx, vy, vz); alpha_o = ay tan(theta') / tan(theta).
        const Vec3 vs(ax / ay * v.x(), v.y(), v.z());
        const double tan_s = std::hypot(vs.x(), vs.y()) / vs.z();
        const double tan_t = std::hypot(v.x(), v.y()) / v.z();
        EXPECT_NEAR(an.alpha_o(ph), ay * tan_s / tan_t, 1e-12);
      }
  }
  // a wrong (non-squared) projection would differ: guard against alpha_o = |cos| ax + |sin| ay
  const Ndf an = Ndf::beckmann(0.2, 0.8);
  EXPECT_GT(std::abs(an.alpha_o(0.6) - (std::cos(0.6) * 0.2 + std::sin(0.6) * 0.8)), 1e-2);
}

// ---------------------------------------------------------------------------------------------
// Smith Lambda from facets (docs/theory/masking.md)
// ---------------------------------------------------------------------------------------------
// Symmetric V-groove of facet angle t: normals (+-sin t, 0, cos t), each of area 1/(2 cos t) per
// unit macro area. A facet is back-facing iff -v.m > 0; with v = (sin th cos ph, sin th sin ph,
// cos th), -v.m(-) = sin th |cos ph| sin t - cos th cos t, so
//   Lambda = max(0, sin th |cos ph| sin t - cos th cos t) / (2 cos t cos th)
//          = max(0, (tan th |cos ph| tan t - 1) / 2),
// zero unless the projected view is steeper than the facets (tan th |cos ph| > cot t).
TEST(Lambda, FromFacetsVGroove) {
  for (double t_deg : {20.0, 45.0, 70.0}) {
    const double t = deg(t_deg);
    const std::vector<Vec3> n = {Vec3(std::sin(t), 0, std::cos(t)), Vec3(-std::sin(t), 0, std::cos(t))};
    const std::vector<double> A = {0.5 / std::cos(t), 0.5 / std::cos(t)};
    // [GeomBSDF24, eq. 1c]: sum (n.m) A_f / A = 1
    EXPECT_NEAR(n[0].z() * A[0] + n[1].z() * A[1], 1.0, 1e-15);
    for (double th : {0.0, 10.0, 30.0, 50.0, 65.0, 75.0, 85.0})
      for (double ph : {0.0, 0.4, 1.2, kPi / 2, kPi}) {
        const Vec3 v = dir(deg(th), ph);
        const double expect = std::max(0.0, (std::tan(deg(th)) * std::abs(std::cos(ph)) * std::tan(t) - 1) / 2);
        EXPECT_NEAR(mm::lambda_from_facets(n, A, v, 1.0), expect, 1e-12) << t_deg << " " << th << " " << ph;
        if (std::tan(deg(th)) * std::abs(std::cos(ph)) < 1 / std::tan(t) - 1e-9) {
          EXPECT_EQ(mm::lambda_from_facets(n, A, v, 1.0), 0.0);
        }
      }
  }
  EXPECT_THROW(mm::lambda_from_facets({Vec3(0, 0, 1)}, {}, Vec3(0, 0, 1), 1.0), std::invalid_argument);
  EXPECT_THROW(mm::lambda_from_facets({Vec3(0, 0, 1)}, {1.0}, Vec3(0, 0, 1), 0.0), std::invalid_argument);
}

// Facets with slopes drawn from the anisotropic Beckmann P22 (projected area distribution) and
// area 1/(N mz) each: the estimate is a mean of N iid terms; |estimate - Lambda| < 4 standard errors.
TEST(Lambda, FromFacetsBeckmannSampleConverges) {
  const double ax = 0.3, ay = 0.6;
  const Ndf ndf = Ndf::beckmann(ax, ay);
  const int N = 400000;
  std::mt19937_64 rng(12345);
  std::normal_distribution<double> gx(0.0, ax / std::sqrt(2.0)), gy(0.0, ay / std::sqrt(2.0));
  std::vector<Vec3> normals(N);
  std::vector<double> areas(N);
  double proj = 0.0;
  for (int k = 0; k < N; ++k) {
    const double sx = gx(rng), sy = gy(rng);
    normals[k] = Vec3(-sx, -sy, 1.0).normalized();
    areas[k] = 1.0 / (N * normals[k].z());
    proj += areas[k] * normals[k].z();
  }
  EXPECT_NEAR(proj, 1.0, 1e-9);
  for (double th : {60.0, 70.0, 80.0})
    for (double ph : {0.0, 0.8, 2.0}) {
      const Vec3 v = dir(deg(th), ph);
      const double est = mm::lambda_from_facets(normals, areas, v, 1.0);
      // per-facet term X_k = max(0, -v.m_k) / (mz_k v.z); est = mean(X_k)
      double s1 = 0.0, s2 = 0.0;
      for (int k = 0; k < N; ++k) {
        const double x = std::max(0.0, -v.dot(normals[k])) / (normals[k].z() * v.z());
        s1 += x;
        s2 += x * x;
      }
      const double mean = s1 / N, se = std::sqrt(std::max(0.0, s2 / N - mean * mean) / (N - 1));
      EXPECT_NEAR(est, mean, 1e-9 * std::max(1.0, mean));
      const double z = (est - ndf.Lambda(v)) / se;
      EXPECT_LT(std::abs(z), 4.0) << "th=" << th << " ph=" << ph << " est=" << est
                                  << " Lambda=" << ndf.Lambda(v) << " se=" << se;
    }
}

// ---------------------------------------------------------------------------------------------
// V-cavity G1 / G2 vs 2D ray casting in the cross-section of a V-groove
// ---------------------------------------------------------------------------------------------
struct Seg {
  double x0, z0, x1, z1;
};

// Does the ray p + s d (s > eps) cross segment sg?
bool ray_hits(double px, double pz, double dx, double dz, const Seg& sg) {
  const double ex = sg.x1 - sg.x0, ez = sg.z1 - sg.z0;
  const double den = dx * ez - dz * ex;
  if (std::abs(den) < 1e-300) return false;
  const double wx = sg.x0 - px, wz = sg.z0 - pz;
  const double s = (wx * ez - wz * ex) / den;   // along the ray
  const double u = (wx * dz - wz * dx) / den;   // along the segment
  return s > 1e-12 && u >= 0.0 && u <= 1.0;
}

// Fraction of facet `f` of a V-groove (walls L and R, rim at z = 0 continued by the flat plane)
// that is visible from every 2D direction in `views`, by casting K rays from stratified points.
double groove_visible_fraction(const Seg& f, const Seg& other, const std::vector<std::pair<double, double>>& views,
                               int K = 20000) {
  int visible = 0;
  for (int k = 0; k < K; ++k) {
    const double u = (k + 0.5) / K;
    const double px = f.x0 + u * (f.x1 - f.x0), pz = f.z0 + u * (f.z1 - f.z0);
    bool vis = true;
    for (const auto& [dx, dz] : views) {
      // the facet itself must face the direction (outward normal of the wall)
      const double nx = -(f.z1 - f.z0), nz = f.x1 - f.x0;  // left-to-right walls: rotate by +90 deg
      const double facing = nx * dx + nz * dz;
      if (!(facing > 0.0) || ray_hits(px, pz, dx, dz, other)) {
        vis = false;
        break;
      }
    }
    visible += vis;
  }
  return static_cast<double>(visible) / K;
}

TEST(VCavity, G1MatchesGrooveGeometry) {
  for (double t_deg : {15.0, 40.0, 65.0}) {
    const double t = deg(t_deg), w = 1.0, h = std::tan(t);
    // left wall from the rim (-w, 0) down to (0, -h): outward normal (sin t, 0, cos t);
    // right wall from (0, -h) up to (w, 0): outward normal (-sin t, 0, cos t).
    const Seg L{-w, 0.0, 0.0, -h}, R{0.0, -h, w, 0.0};
    const Vec3 mL(std::sin(t), 0, std::cos(t)), mR(-std::sin(t), 0, std::cos(t));
    for (double th : {5.0, 30.0, 50.0, 70.0, 85.0})
      for (double ph : {0.0, 0.6, 2.0, kPi}) {
        const Vec3 v = dir(deg(th), ph);
        // the groove is extruded along y: occlusion depends on the xz projection of v only
        const double n2 = std::hypot(v.x(), v.z());
        const std::vector<std::pair<double, double>> view = {{v.x() / n2, v.z() / n2}};
        EXPECT_NEAR(mm::vcavity_G1(v, mL), groove_visible_fraction(L, R, view), 2e-4)
            << t_deg << " " << th << " " << ph;
        EXPECT_NEAR(mm::vcavity_G1(v, mR), groove_visible_fraction(R, L, view), 2e-4)
            << t_deg << " " << th << " " << ph;
      }
  }
}

TEST(VCavity, G2MatchesGrooveGeometry) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double t = deg(35.0), h = std::tan(t);
  const Seg L{-1.0, 0.0, 0.0, -h}, R{0.0, -h, 1.0, 0.0};
  const Vec3 mL(std::sin(t), 0, std::cos(t));
  for (int k = 0; k < 60; ++k) {
    const double uo_t = u(rng), uo_p = u(rng), ui_t = u(rng), ui_p = u(rng);
    const Vec3 o = dir(deg(85.0) * uo_t, 2 * kPi * uo_p);
    const Vec3 i = dir(deg(85.0) * ui_t, 2 * kPi * ui_p);
    const double no = std::hypot(o.x(), o.z()), ni = std::hypot(i.x(), i.z());
    const double geo = groove_visible_fraction(L, R, {{o.x() / no, o.z() / no}, {i.x() / ni, i.z() / ni}});
    EXPECT_NEAR(mm::vcavity_G2(o, i, mL), geo, 2e-4);
    EXPECT_NEAR(mm::vcavity_G2(o, i, mL), mm::vcavity_G2(i, o, mL), 1e-15);
    EXPECT_NEAR(mm::vcavity_G2(o, o, mL), mm::vcavity_G1(o, mL), 1e-15);
  }
}

// ---------------------------------------------------------------------------------------------
// VNDF sampling: chi-square goodness of fit against D_visible (microsim/statistics.hpp), on cells
// u = tan(theta) / (tan(theta) + s) x phi that follow the lobe for any roughness (s = sqrt(ax ay)).
// ---------------------------------------------------------------------------------------------
std::vector<Vec3> draw(const Ndf& ndf, const Vec3& v, int N, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> out(N);
  for (int k = 0; k < N; ++k) {
    const double u1 = u(rng), u2 = u(rng);
    out[k] = ndf.sample_visible_normal(v, u1, u2);
  }
  return out;
}

microsim::ChiSquareTest vndf_test(const Ndf& ndf, const Vec3& v, std::uint64_t seed, std::uint64_t n = 100000) {
  microsim::ChiSquareTest::Options o;
  o.samples = n;
  o.seed = seed;
  o.res_u = 20;
  o.res_v = 32;
  return microsim::ChiSquareTest(
      microsim::ChiSquareDomain::hemisphere_slopes(std::sqrt(ndf.alpha_x * ndf.alpha_y)),
      [ndf, v](microsim::CounterRng& rng) -> std::optional<Vec3> {
        const double u1 = rng.uniform(), u2 = rng.uniform();
        return ndf.sample_visible_normal(v, u1, u2);
      },
      [ndf, v](const Vec3& m) { return ndf.D_visible(v, m); }, o);
}

TEST(VndfSampling, SamplesAreFrontFacingUnitNormals) {
  for (auto kind : {Distribution::Beckmann, Distribution::GGX})
    for (double th : {0.0, 45.0, 89.9}) {
      const Ndf ndf = make(kind, 0.2, 0.9);
      const Vec3 v = dir(deg(th), 0.9);
      for (const Vec3& m : draw(ndf, v, 5000, 3)) {
        ASSERT_NEAR(m.norm(), 1.0, 1e-12);
        ASSERT_GT(m.z(), 0.0);
        ASSERT_GT(v.dot(m), -1e-12);
      }
    }
}

struct VndfCase {
  Distribution kind;
  double ax, ay, th, ph;
};
std::string vndf_case_name(const ::testing::TestParamInfo<VndfCase>& i) {
  const VndfCase& c = i.param;
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s_a%03.0fx%03.0f_theta%02.0f", mm::to_string(c.kind), 100 * c.ax, 100 * c.ay, c.th);
  return buf;
}
const VndfCase kVndfCases[] = {
    {Distribution::Beckmann, 0.3, 0.7, 60.0, 0.5}, {Distribution::GGX, 0.3, 0.7, 60.0, 0.5},
    {Distribution::Beckmann, 0.5, 0.5, 85.0, 2.0}, {Distribution::GGX, 0.5, 0.5, 85.0, 2.0},
    {Distribution::Beckmann, 0.8, 0.2, 0.0, 0.0},  {Distribution::GGX, 0.8, 0.2, 0.0, 0.0},
    {Distribution::Beckmann, 1.2, 0.4, 40.0, 4.0}, {Distribution::GGX, 1.2, 0.4, 40.0, 4.0}};
constexpr int kVndfTests = sizeof(kVndfCases) / sizeof(kVndfCases[0]);

class VndfSamplingChi2 : public ::testing::TestWithParam<VndfCase> {};

// The sampler passes against its own D_visible (family-wise 1% over the cases), and the same
// samples refuse a D_visible whose roughness is 5% larger.
TEST_P(VndfSamplingChi2, MatchesDVisibleAndRejectsFivePercentWrongRoughness) {
  const VndfCase& c = GetParam();
  const Ndf ndf = make(c.kind, c.ax, c.ay), wrong = make(c.kind, 1.05 * c.ax, 1.05 * c.ay);
  const Vec3 v = dir(deg(c.th), c.ph);
  const std::uint64_t seed = 2024 + 1000 * static_cast<int>(c.kind) + static_cast<int>(100 * c.ax + c.th);
  microsim::ChiSquareTest t = vndf_test(ndf, v, seed);
  const microsim::ChiSquareResult& r = t.run();
  std::printf("[ info ] %s\n", r.summary().c_str());
  EXPECT_GT(r.dof, 100);
  EXPECT_TRUE(r.passed(0.01, kVndfTests)) << t.describe();
  const microsim::ChiSquareResult w = t.run_against([&](const Vec3& m) { return wrong.D_visible(v, m); });
  std::printf("[ info ] alpha x1.05: %s\n", w.summary().c_str());
  EXPECT_LT(w.p_value, 1e-4) << w.summary();
}
INSTANTIATE_TEST_SUITE_P(Cases, VndfSamplingChi2, ::testing::ValuesIn(kVndfCases), vndf_case_name);

// ---------------------------------------------------------------------------------------------
// [Heitz14, Sec. 5]: joint masking-shadowing forms
// ---------------------------------------------------------------------------------------------
TEST(G2, IdentitiesAtCoincidentDirections) {
  for (auto kind : {Distribution::Beckmann, Distribution::GGX}) {
    const Ndf ndf = make(kind, 0.4, 0.9);
    for (double th : {0.0, 30.0, 60.0, 80.0, 88.0}) {
      const Vec3 o = dir(deg(th), 0.7);
      const Vec3 m = dir(deg(th) * 0.5, 0.7);
      const double g1 = ndf.G1(o, m), L = ndf.Lambda(o);
      EXPECT_NEAR(mm::G2_separable(ndf, o, o, m), g1 * g1, 1e-14);                       // eq. (20)
      EXPECT_NEAR(mm::G2_height_correlated(ndf, o, o, m), 1 / (1 + 2 * L), 1e-14);        // eq. (21)
      EXPECT_NEAR(mm::G2_direction_correlated(ndf, o, o, m), g1, 1e-14);                 // eq. (22), lambda(0)=0
      EXPECT_NEAR(mm::G2_height_direction_correlated(ndf, o, o, m), g1, 1e-14);          // eq. (23), lambda(0)=0
      EXPECT_NEAR(mm::vcavity_G2(o, o, m), mm::vcavity_G1(o, m), 1e-15);
    }
  }
  EXPECT_EQ(mm::van_ginneken_lambda(0.0), 0.0);
  EXPECT_NEAR(mm::van_ginneken_lambda(kPi), 4.41 * kPi / (4.41 * kPi + 1), 1e-15);
  EXPECT_NEAR(mm::azimuth_difference(dir(0.5, 0.3), dir(0.8, 0.3 + 2.5)), 2.5, 1e-12);
  EXPECT_NEAR(mm::azimuth_difference(dir(0.5, 0.3), dir(0.8, 0.3 - 2.5)), 2.5, 1e-12);
  EXPECT_NEAR(mm::azimuth_difference(dir(0.5, 0.1), dir(0.8, 0.1 + kPi)), kPi, 1e-12);
}

TEST(G2, SymmetryBoundsAndOrdering) {
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int nonzero = 0;
  for (auto kind : {Distribution::Beckmann, Distribution::GGX}) {
    const Ndf ndf = make(kind, 0.5, 0.25);
    for (int k = 0; k < 2000; ++k) {
      const double uo_t = u(rng), uo_p = u(rng), ui_t = u(rng), ui_p = u(rng);
      const Vec3 o = dir(std::acos(uo_t), 2 * kPi * uo_p);
      const Vec3 i = dir(std::acos(ui_t), 2 * kPi * ui_p);
      Vec3 m = (o + i).normalized();
      if (k % 2 == 0) {
        const double um_t = u(rng), um_p = u(rng);
        m = dir(std::acos(um_t), 2 * kPi * um_p);
      }
      const double gs = mm::G2_separable(ndf, o, i, m), gh = mm::G2_height_correlated(ndf, o, i, m);
      const double gd = mm::G2_direction_correlated(ndf, o, i, m);
      const double ghd = mm::G2_height_direction_correlated(ndf, o, i, m);
      const double gmin = std::min(ndf.G1(o, m), ndf.G1(i, m));
      for (double g : {gs, gh, gd, ghd}) {
        ASSERT_GE(g, 0.0);
        ASSERT_LE(g, 1.0);
        ASSERT_LE(g, gmin + 1e-15);
      }
      ASSERT_NEAR(gs, mm::G2_separable(ndf, i, o, m), 1e-15);
      ASSERT_NEAR(gh, mm::G2_height_correlated(ndf, i, o, m), 1e-15);
      ASSERT_NEAR(gd, mm::G2_direction_correlated(ndf, i, o, m), 1e-15);
      ASSERT_NEAR(ghd, mm::G2_height_direction_correlated(ndf, i, o, m), 1e-15);
      // correlation can only reduce the shadowing of the separable form
      ASSERT_LE(gs, gh + 1e-15);
      ASSERT_LE(gh, ghd + 1e-15);
      ASSERT_LE(gs, gd + 1e-15);
      const bool front = o.dot(m) > 0 && i.dot(m) > 0;
      if (!front) {
        ASSERT_EQ(gs + gh + gd + ghd, 0.0);
      }
      nonzero += front;
      // explicit formulas
      const double Lo = ndf.Lambda(o), Li = ndf.Lambda(i);
      if (front) {
        ASSERT_NEAR(gh, 1 / (1 + Lo + Li), 1e-14);
        ASSERT_NEAR(gs, 1 / ((1 + Lo) * (1 + Li)), 1e-14);
        const double lam = mm::van_ginneken_lambda(mm::azimuth_difference(o, i));
        ASSERT_NEAR(ghd, 1 / (1 + std::max(Lo, Li) + lam * std::min(Lo, Li)), 1e-14);
        ASSERT_NEAR(gd, lam * gs + (1 - lam) * gmin, 1e-14);
      }
    }
  }
  EXPECT_GT(nonzero, 1000);
  // below the horizon
  const Ndf ndf = Ndf::ggx(0.3, 0.3);
  const Vec3 m(0, 0, 1);
  EXPECT_EQ(mm::G2_height_direction_correlated(ndf, dir(deg(95), 0), dir(deg(95), 0), m), 0.0);
  EXPECT_EQ(mm::G2_height_correlated(ndf, dir(deg(30), 0), dir(deg(95), 0), m), 0.0);
}

}  // namespace
