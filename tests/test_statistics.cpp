// Tests of include/microsim/statistics.hpp: the chi-square tail against closed forms, quadrature
// and Eigen's independent incomplete gamma; Pearson's statistic with pooling; the domains; and the
// goodness-of-fit harness itself: correct samplers pass, wrong densities (a missing cosine, a 5%
// wrong roughness, mass where the sampler never goes) fail, and under the null its p-values are
// uniform (neither too strict nor too lenient).
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <unsupported/Eigen/SpecialFunctions>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "microsim/models/ndf.hpp"
#include "microsim/statistics.hpp"

using namespace microsim;

namespace {

// Q(k/2, x/2) for even k: the Poisson sum e^(-x/2) sum_{j < k/2} (x/2)^j / j!.
double even_dof_tail(double x, int k) {
  double term = 1, sum = 1;
  for (int j = 1; j < k / 2; ++j) {
    term *= 0.5 * x / j;
    sum += term;
  }
  return std::exp(-0.5 * x) * sum;
}

// P(X >= x) by composite Simpson on the chi-square density over [x, x + 60 sqrt(2k) + 200].
double tail_by_quadrature(double x, int k) {
  const double a = 0.5 * k, hi = x + 60 * std::sqrt(2.0 * k) + 200;
  auto f = [&](double t) { return t <= 0 ? 0.0 : std::exp((a - 1) * std::log(t) - 0.5 * t - a * std::log(2.0) - std::lgamma(a)); };
  const int n = 200000;
  const double h = (hi - x) / n;
  double s = f(x) + f(hi);
  for (int i = 1; i < n; ++i) s += f(x + i * h) * (i % 2 ? 4 : 2);
  return s * h / 3;
}

}  // namespace

TEST(ChiSquareTail, EvenDegreesOfFreedomMatchThePoissonSum) {
  for (int k : {2, 4, 10, 50, 200})
    for (double x : {0.3, 1.0, 5.0, 0.5 * k, double(k), 1.5 * k + 10, 3.0 * k + 40}) {
      const double ref = even_dof_tail(x, k);
      EXPECT_NEAR(chi2_p_value(x, k), ref, 1e-12 + 1e-10 * ref) << "k " << k << " x " << x;
    }
}

TEST(ChiSquareTail, OddDegreesOfFreedomMatchQuadratureAndErfc) {
  for (double x : {0.1, 1.0, 4.0, 20.0}) EXPECT_NEAR(chi2_p_value(x, 1), std::erfc(std::sqrt(x / 2)), 1e-13);
  for (int k : {3, 7, 31})
    for (double x : {1.0, double(k), 2.0 * k + 5}) {
      const double q = tail_by_quadrature(x, k);
      EXPECT_NEAR(chi2_p_value(x, k), q, 1e-9 * std::max(q, 1e-3)) << "k " << k << " x " << x;
    }
}

TEST(ChiSquareTail, AgreesWithEigensIncompleteGamma) {
  // Eigen's igammac (unsupported SpecialFunctions) is an independent implementation.
  for (int k : {1, 2, 5, 17, 100, 999})
    for (double f : {0.2, 0.8, 1.0, 1.3, 2.0}) {
      const double x = f * k, ref = Eigen::numext::igammac(0.5 * k, 0.5 * x);
      EXPECT_NEAR(chi2_p_value(x, k), ref, 1e-12 + 1e-9 * ref) << "k " << k << " x " << x;
    }
}

TEST(Sidak, LevelsAndTheirZThresholds) {
  EXPECT_DOUBLE_EQ(sidak_alpha(0.05, 1), 0.05);
  EXPECT_NEAR(sidak_alpha(0.01, 10), 1 - std::pow(0.99, 0.1), 1e-15);
  EXPECT_NEAR(sidak_alpha(0.01, 1000), 1.00503e-5, 1e-9);
  for (int k : {1, 8, 500}) EXPECT_NEAR(std::erfc(sidak_z(0.01, k) / std::sqrt(2.0)), sidak_alpha(0.01, k), 1e-12);
}

TEST(PearsonChi2, HandComputedValuesAndPooling) {
  const ChiSquareResult a = pearson_chi2({10, 20, 30}, {20, 20, 20});
  EXPECT_DOUBLE_EQ(a.chi2, 10.0);
  EXPECT_EQ(a.dof, 2);
  EXPECT_NEAR(a.p_value, std::exp(-5.0), 1e-14);
  EXPECT_TRUE(a.error.empty());
  // 1 + 2 + 3 < 5 pooled with the next smallest (4): one cell of 10 observed 14.
  const ChiSquareResult b = pearson_chi2({0, 5, 5, 4, 40, 46}, {1, 2, 3, 4, 40, 50});
  EXPECT_EQ(b.pooled, 4);
  EXPECT_EQ(b.cells, 3);
  EXPECT_DOUBLE_EQ(b.pooled_expected, 10.0);
  EXPECT_NEAR(b.chi2, 16.0 / 10 + 0 + 16.0 / 50, 1e-14);
  // A draw where the density is zero fails whatever the statistic says.
  EXPECT_FALSE(pearson_chi2({1, 50, 49}, {0, 50, 50}).error.empty());
  EXPECT_FALSE(pearson_chi2({1, 50, 49}, {0, 50, 50}).passed());
  EXPECT_TRUE(pearson_chi2({0, 50, 50}, {0, 50, 50}).passed());
  // Too few draws for two cells.
  EXPECT_FALSE(pearson_chi2({1, 2}, {1, 2}).passed());
}

TEST(ChiSquareDomain, ParametersRoundTripAndJacobiansGiveTheMeasure) {
  for (const ChiSquareDomain& d : {ChiSquareDomain::sphere(), ChiSquareDomain::hemisphere(),
                                   ChiSquareDomain::hemisphere_slopes(0.3), ChiSquareDomain::rectangle(-1, 2, 0.5, 1)}) {
    for (double u : {0.01, 0.3, 0.77, 0.99})
      for (double v : {0.02, 0.5, 0.93}) {
        double uu = -1, vv = -1;
        ASSERT_TRUE(d.param(d.point(u, v), uu, vv)) << d.name;
        EXPECT_NEAR(uu, u, 1e-12) << d.name;
        EXPECT_NEAR(vv, v, 1e-12) << d.name;
      }
    // Total measure by a midpoint rule: 4 pi, 2 pi, 2 pi, 3 x 0.5.
    double m = 0;
    const int n = 2000;
    for (int i = 0; i < n; ++i) m += d.jacobian((i + 0.5) / n, 0.5) / n;
    const double want = d.name == "sphere" ? 4 * kPi : d.name == "rectangle" ? 1.5 : 2 * kPi;
    EXPECT_NEAR(m, want, 1e-5 * want) << d.name;
  }
  double u, v;
  EXPECT_FALSE(ChiSquareDomain::hemisphere().param(Vec3(0, 0.1, -1), u, v));
  EXPECT_FALSE(ChiSquareDomain::rectangle(0, 1, 0, 1).param(Vec3(1.5, 0.5, 0), u, v));
}

namespace {

// Cosine-weighted hemisphere sampling (Malley) and its density cos(theta) / pi.
std::optional<Vec3> cosine_sample(CounterRng& rng) {
  const double r = std::sqrt(rng.uniform()), ph = 2 * kPi * rng.uniform();
  return Vec3(r * std::cos(ph), r * std::sin(ph), std::sqrt(std::max(0.0, 1 - r * r)));
}
double cosine_pdf(const Vec3& w) { return std::max(0.0, w.z()) / kPi; }

ChiSquareTest::Options small(std::uint64_t n, int nu, int nv, std::uint64_t seed = 1) {
  ChiSquareTest::Options o;
  o.samples = n;
  o.res_u = nu;
  o.res_v = nv;
  o.seed = seed;
  return o;
}

}  // namespace

TEST(ChiSquareHarness, CorrectSamplersPass) {
  const int tests = 4;
  // Uniform sphere.
  ChiSquareTest sphere(ChiSquareDomain::sphere(),
                       [](CounterRng& rng) -> std::optional<Vec3> {
                         const double z = 1 - 2 * rng.uniform(), ph = 2 * kPi * rng.uniform();
                         const double s = std::sqrt(std::max(0.0, 1 - z * z));
                         return Vec3(s * std::cos(ph), s * std::sin(ph), z);
                       },
                       [](const Vec3&) { return 1 / (4 * kPi); }, small(200000, 16, 32));
  EXPECT_TRUE(sphere.run().passed(0.01, tests)) << sphere.describe();
  EXPECT_NEAR(sphere.pdf_integral(), 1.0, 1e-12);
  // Cosine-weighted hemisphere, on the sphere domain (the lower half must stay empty).
  ChiSquareTest cosine(ChiSquareDomain::sphere(), cosine_sample, cosine_pdf, small(200000, 32, 32));
  EXPECT_TRUE(cosine.run().passed(0.01, tests)) << cosine.describe();
  // A density on a rectangle, p(x, y) = 2x (1/2) on [0, 1] x [0, 2], by inversion.
  ChiSquareTest rect(ChiSquareDomain::rectangle(0, 1, 0, 2),
                     [](CounterRng& rng) -> std::optional<Vec3> {
                       const double x = std::sqrt(rng.uniform()), y = 2 * rng.uniform();
                       return Vec3(x, y, 0);
                     },
                     [](const Vec3& p) { return p.x(); }, small(100000, 20, 10));
  EXPECT_TRUE(rect.run().passed(0.01, tests)) << rect.describe();
  // GGX visible normals [Heitz14, eq. 13] at 60 degrees, anisotropic, on lobe-following cells.
  const models::Ndf ggx = models::Ndf::ggx(0.3, 0.6);
  const Vec3 v = direction_from_angles(rad(60.0), 0.4);
  ChiSquareTest vndf(ChiSquareDomain::hemisphere_slopes(std::sqrt(0.3 * 0.6)),
                     [&](CounterRng& rng) -> std::optional<Vec3> {
                       const double u1 = rng.uniform(), u2 = rng.uniform();
                       return ggx.sample_visible_normal(v, u1, u2);
                     },
                     [&](const Vec3& m) { return ggx.D_visible(v, m); }, small(400000, 24, 48));
  const ChiSquareResult& r = vndf.run();
  EXPECT_TRUE(r.passed(0.01, tests)) << vndf.describe();
  std::printf("[ info ] sphere %s\n[ info ] cosine %s\n[ info ] rectangle %s\n[ info ] ggx vndf %s\n",
              sphere.result().summary().c_str(), cosine.result().summary().c_str(), rect.result().summary().c_str(),
              r.summary().c_str());
  EXPECT_GT(r.dof, 500);
  EXPECT_NEAR(vndf.pdf_integral(), 1.0, 1e-4);
}

TEST(ChiSquareHarness, WrongDensitiesFail) {
  // A missing cosine: cosine-weighted samples against the uniform hemisphere density.
  ChiSquareTest cosine(ChiSquareDomain::hemisphere(), cosine_sample, cosine_pdf, small(20000, 8, 16));
  EXPECT_TRUE(cosine.run().passed()) << cosine.describe();
  const ChiSquareResult no_cos = cosine.run_against([](const Vec3&) { return 1 / (2 * kPi); });
  EXPECT_LT(no_cos.p_value, 1e-6) << no_cos.summary();
  EXPECT_FALSE(no_cos.passed());
  // Renormalized, a density three times too large has the same shape: the same statistic.
  const ChiSquareResult no_cos3 = cosine.run_against([](const Vec3&) { return 3 / (2 * kPi); }, true);
  EXPECT_NEAR(no_cos3.chi2, no_cos.chi2, 1e-9 * no_cos.chi2);
  EXPECT_TRUE(no_cos3.error.empty()) << no_cos3.error;
  // A roughness 5% off: GGX 0.5 visible normals against the D_v of 0.525.
  const models::Ndf ggx = models::Ndf::ggx(0.5, 0.5), wrong = models::Ndf::ggx(0.525, 0.525);
  const Vec3 v = direction_from_angles(rad(40.0), 0.0);
  ChiSquareTest vndf(ChiSquareDomain::hemisphere_slopes(0.5),
                     [&](CounterRng& rng) -> std::optional<Vec3> {
                       const double u1 = rng.uniform(), u2 = rng.uniform();
                       return ggx.sample_visible_normal(v, u1, u2);
                     },
                     [&](const Vec3& m) { return ggx.D_visible(v, m); }, small(400000, 20, 40));
  EXPECT_TRUE(vndf.run().passed()) << vndf.describe();
  const ChiSquareResult w = vndf.run_against([&](const Vec3& m) { return wrong.D_visible(v, m); });
  EXPECT_LT(w.p_value, 1e-6) << w.summary();
  std::printf("[ info ] no cosine: %s\n[ info ] alpha x1.05: %s\n", no_cos.summary().c_str(), w.summary().c_str());
  // A pdf that claims mass where the sampler never goes (the lower hemisphere): the refused
  // cell is empty while the pdf leaves half its mass there.
  ChiSquareTest half(ChiSquareDomain::sphere(), cosine_sample,
                     [](const Vec3& w) { return std::abs(w.z()) / (2 * kPi); }, small(20000, 8, 16));
  EXPECT_FALSE(half.run().passed()) << half.describe();
  // Samples where the pdf is zero fail outright, even when few.
  ChiSquareTest leak(ChiSquareDomain::sphere(),
                     [](CounterRng& rng) -> std::optional<Vec3> {
                       auto w = cosine_sample(rng);
                       if (rng.uniform() < 1e-3) w->z() = -w->z();
                       return w;
                     },
                     cosine_pdf, small(20000, 8, 16));
  const ChiSquareResult& l = leak.run();
  EXPECT_FALSE(l.passed());
  EXPECT_NE(l.error.find("zero"), std::string::npos) << l.summary();
  // A pdf normalized to more than 1.
  const ChiSquareResult big = cosine.run_against([](const Vec3& w) { return 1.01 * cosine_pdf(w); });
  EXPECT_NE(big.error.find("integrates"), std::string::npos) << big.summary();
  // Refused samples are counted against the mass the pdf leaves outside the domain:
  // a sampler refusing 10% of its draws with a pdf scaled by 0.9 passes; unscaled it fails.
  ChiSquareTest refuse(ChiSquareDomain::hemisphere(),
                       [](CounterRng& rng) -> std::optional<Vec3> {
                         if (rng.uniform() < 0.1) return std::nullopt;
                         return cosine_sample(rng);
                       },
                       [](const Vec3& w) { return 0.9 * cosine_pdf(w); }, small(50000, 8, 16));
  EXPECT_TRUE(refuse.run().passed()) << refuse.describe();
  EXPECT_FALSE(refuse.run_against(cosine_pdf).passed());
}

TEST(ChiSquareHarness, PValuesAreUniformUnderTheNull) {
  // 200 independent tests of a correct sampler: the p-values' empirical distribution against
  // U(0, 1) by Kolmogorov-Smirnov (D > 1.63 / sqrt(n) has probability 1%).
  const int runs = 200;
  std::vector<double> p;
  for (int s = 0; s < runs; ++s) {
    ChiSquareTest t(ChiSquareDomain::hemisphere(), cosine_sample, cosine_pdf, small(3000, 6, 8, 100 + s));
    p.push_back(t.run().p_value);
  }
  std::sort(p.begin(), p.end());
  double d = 0;
  for (int i = 0; i < runs; ++i) d = std::max({d, p[i] - double(i) / runs, double(i + 1) / runs - p[i]});
  EXPECT_LT(d, 1.63 / std::sqrt(double(runs)));
}

TEST(ChiSquareHarness, SameHistogramForAnyThreadCountAndSeedsDiffer) {
  ChiSquareTest a(ChiSquareDomain::hemisphere(), cosine_sample, cosine_pdf, small(50000, 8, 8, 3));
  ChiSquareTest b(ChiSquareDomain::hemisphere(), cosine_sample, cosine_pdf, small(50000, 8, 8, 3));
  ChiSquareTest c(ChiSquareDomain::hemisphere(), cosine_sample, cosine_pdf, small(50000, 8, 8, 4));
  a.run();
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    b.run();
  }
  c.run();
  EXPECT_EQ(a.observed(), b.observed());
  EXPECT_NE(a.observed(), c.observed());
  // The same draws handed over as a fixed set of points give the same histogram and statistic.
  std::vector<Vec3> points;
  for (std::uint64_t k = 0; k < 50000; ++k) {
    CounterRng rng(3, 0xC41507E57ull, k);
    points.push_back(*cosine_sample(rng));
  }
  ChiSquareTest d(ChiSquareDomain::hemisphere(), points, cosine_pdf, small(1, 8, 8));
  EXPECT_DOUBLE_EQ(d.run().chi2, a.result().chi2);
  EXPECT_EQ(d.observed(), a.observed());
}
