// Tests of the Smith walk's faster Beckmann slope sampler (models/beckmann_slope_sampler.hpp) against its
// exact twin detail::beckmann_visible_slope_quantile (ndf.hpp): the normal quantile AS 241, the slope
// quantile over views above and below the horizon (inside and outside the table of starts), and the
// visible normals of sample_visible_normal_fast against sample_visible_normal_any.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "microsim/common.hpp"
#include "microsim/models/smith_random_walk.hpp"

using namespace microsim;
namespace mm = microsim::models;
namespace md = microsim::models::detail;

TEST(NormalQuantileAs241, MatchesTheErfcQuantile) {
  // SmithHeights::normal_quantile: Newton on erfc to full precision (the exact twin).
  double worst = 0.0;
  for (double u : {1e-300, 1e-200, 1e-30, 1e-12, 1e-6, 0.001, 0.02, 0.075, 0.0751, 0.2, 0.5, 0.6, 0.924, 0.926,
                   0.999, 1.0 - 1e-9, 1.0 - 1e-15}) {
    const double a = md::normal_quantile_as241(u), b = mm::SmithHeights::normal_quantile(u);
    worst = std::max(worst, std::abs(a - b) / (1.0 + std::abs(b)));
  }
  for (int k = 1; k < 10000; ++k) {
    const double u = k / 10000.0;
    const double a = md::normal_quantile_as241(u), b = mm::SmithHeights::normal_quantile(u);
    worst = std::max(worst, std::abs(a - b) / (1.0 + std::abs(b)));
  }
  EXPECT_LT(worst, 1e-14);
  EXPECT_EQ(md::normal_quantile_as241(0.5), 0.0);
  EXPECT_EQ(md::normal_quantile_as241(0.0), -md::kInf);
  EXPECT_EQ(md::normal_quantile_as241(1.0), md::kInf);
}

TEST(FastBeckmannSlopeQuantile, MatchesTheExactQuantile) {
  // mu = cot(theta') over the views the walk meets (above the horizon mu > 0, below mu < 0, beyond the
  // table at both ends) and u over the body and the tails of the distribution.
  double worst = 0.0;
  int compared = 0;
  for (double mu : {md::kInf, 1e3, 50.0, 36.0, 10.0, 3.0, 1.0, 0.5, 0.1, 0.0, -0.1, -0.5, -1.0, -2.0, -3.0, -3.5,
                    -6.0, -20.0})
    // (u -> 1: the CDF's rounding leaves x uncertain by ~1e-16 / density, so the twins part beyond 1 - 1e-6)
    for (double u : {1e-20, 1e-13, 1e-8, 1e-4, 0.01, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99, 0.9999, 1.0 - 1e-6}) {
      const double a = md::fast_beckmann_visible_slope_quantile(mu, u);
      const double b = md::beckmann_visible_slope_quantile(mu, u);
      ASSERT_TRUE(std::isfinite(a)) << "mu " << mu << " u " << u;
      worst = std::max(worst, std::abs(a - b) / (1.0 + std::abs(b)));
      ++compared;
    }
  // a dense sweep inside the table
  for (int i = 0; i < 200; ++i) {
    const double theta = 0.03 + (2.83 - 0.03) * i / 199.0, mu = std::cos(theta) / std::sin(theta);
    for (int j = 1; j < 200; ++j) {
      const double u = j / 200.0;
      const double a = md::fast_beckmann_visible_slope_quantile(mu, u);
      const double b = md::beckmann_visible_slope_quantile(mu, u);
      worst = std::max(worst, std::abs(a - b) / (1.0 + std::abs(b)));
      ++compared;
    }
  }
  RecordProperty("largest_relative_difference", std::to_string(worst));
  EXPECT_LT(worst, 1e-12) << compared << " compared";
}

TEST(FastBeckmannSlopeQuantile, InsideTheTableHalleyConvergesInTwoEvaluations) {
  // Inside the table every call ends in Halley's iteration (none in the exact function: a step of 0 at an end
  // of the bracket is converged, not a reason to bisect), after two CDF evaluations from the table's start
  // (the step after a step below 1e-6 is at rounding).
  int exact = 0, calls = 0, most = 0;
  long evaluations = 0;
  for (int i = 0; i < 200; ++i) {
    const double theta = 0.03 + (2.83 - 0.03) * i / 199.0, mu = std::cos(theta) / std::sin(theta);
    for (int j = 1; j < 200; ++j) {
      int e = 0;
      md::fast_beckmann_visible_slope_quantile(mu, j / 200.0, std::numeric_limits<double>::quiet_NaN(), &e);
      ++calls;
      if (e < 0) {
        ++exact;
      } else {
        evaluations += e;
        most = std::max(most, e);
      }
    }
  }
  EXPECT_EQ(exact, 0) << calls << " calls";
  EXPECT_LE(static_cast<double>(evaluations) / calls, 2.05);
  EXPECT_LE(most, 4);
  // outside the table (mu below -3.2): the exact function, reported as such
  int e = 0;
  md::fast_beckmann_visible_slope_quantile(-6.0, 0.3, std::numeric_limits<double>::quiet_NaN(), &e);
  EXPECT_EQ(e, -1);
}

TEST(FastBeckmannSlopeQuantile, TheComparisonSeesAWrongQuantile) {
  // Power: the start alone (no Halley step), or the quantile of a neighbouring mu, is far from the exact one.
  double x = 0.0;
  const double theta = 1.0, mu = std::cos(theta) / std::sin(theta), u = 0.37;
  ASSERT_TRUE(md::BeckmannSlopeStarts::instance().start(theta + 0.01, md::normal_quantile_as241(u), &x));
  EXPECT_GT(std::abs(x - md::beckmann_visible_slope_quantile(mu, u)), 1e-6);
  EXPECT_GT(std::abs(md::fast_beckmann_visible_slope_quantile(mu * 1.001, u) - md::beckmann_visible_slope_quantile(mu, u)),
            1e-6);
}

TEST(FastBeckmannSlopeQuantile, VisibleNormalsMatchTheExactSampler) {
  const mm::Ndf ndf = mm::Ndf::beckmann(0.5, 0.8);
  double worst = 0.0;
  CounterRng rng(11, 3, 0);
  for (int k = 0; k < 20000; ++k) {
    // directions above and below the horizon, and straight up
    const double z = k == 0 ? 1.0 : 2.0 * rng.uniform() - 1.0, phi = 2.0 * 3.14159265358979 * rng.uniform();
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    const Vec3 v(s * std::cos(phi), s * std::sin(phi), z);
    const double u1 = rng.uniform(), u2 = rng.uniform();
    const Vec3 a = mm::sample_visible_normal_fast(ndf, v, u1, u2), b = mm::sample_visible_normal_any(ndf, v, u1, u2);
    worst = std::max(worst, (a - b).norm());
    // with the leg's Lambda given (the walk's normalization without erfc)
    const double leg = v.z() > 0.0 ? ndf.Lambda(v) : ndf.Lambda(-v);
    worst = std::max(worst, (mm::sample_visible_normal_fast(ndf, v, u1, u2, leg) - b).norm());
  }
  EXPECT_LT(worst, 1e-11);
  // Power: a wrong leg Lambda (the normalization 10% off) moves the normals.
  const Vec3 v = Vec3(0.5, 0.2, 0.6).normalized();
  EXPECT_GT((mm::sample_visible_normal_fast(ndf, v, 0.3, 0.6, 1.1 * ndf.Lambda(v) + 0.1) -
             mm::sample_visible_normal_any(ndf, v, 0.3, 0.6)).norm(), 1e-4);
  // GGX: the exact sampler itself
  const mm::Ndf ggx = mm::Ndf::ggx(0.4, 0.4);
  const Vec3 w = Vec3(0.3, -0.2, -0.5).normalized();
  EXPECT_EQ(mm::sample_visible_normal_fast(ggx, w, 0.3, 0.6), mm::sample_visible_normal_any(ggx, w, 0.3, 0.6));
}

TEST(FastBeckmannSlopeQuantile, WalkWithTheFastSamplerFollowsTheSamePaths) {
  // The walk's events depend on the slopes through comparisons with uniforms: equal slopes to ~1e-14 give
  // the same orders and exits (to rounding) on all but a vanishing fraction of walks.
  const mm::SmithRandomWalk exact(mm::Ndf::beckmann(0.7, 0.7), mm::Material::mirror());
  const mm::SmithRandomWalk fast = exact.with_fast_slope_sampler();
  EXPECT_FALSE(exact.fast_slope_sampler());
  EXPECT_TRUE(fast.fast_slope_sampler());
  struct Rng {
    CounterRng c;
    double uniform() { return c.uniform(); }
  };
  int same = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    Rng a{CounterRng(5, 1, static_cast<std::uint64_t>(i))}, b{CounterRng(5, 1, static_cast<std::uint64_t>(i))};
    const Vec3 wi = direction_from_angles(rad(70.0), 0.3);
    const mm::WalkExit x = exact.walk(wi, a), y = fast.walk(wi, b);
    if (x.order == y.order && (x.direction - y.direction).norm() < 1e-9) ++same;
  }
  EXPECT_GE(same, n - 2);
}
