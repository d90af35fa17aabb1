// The slope fits and the ACF of `info` run in parallel, in fixed blocks, with the slopes
// recomputed from the heights in every pass: checked against a plain serial computation over a
// stored slope list (the definitions of include/microsim/surface/metrology.hpp, written out
// once more here), bit for bit where one block holds every slope, to rounding otherwise, and
// bit for bit between thread counts.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <random>

#include "microsim/surface/metrology.hpp"

using namespace microsim;

namespace {

// A periodic Gaussian-looking field: a few random waves plus white noise (float heights).
std::vector<float> random_heights(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> u(0, 1);
  struct Wave { int kx, ky; double a, ph; };
  std::vector<Wave> waves;
  for (int w = 0; w < 12; ++w) {
    const int kx = static_cast<int>(u(rng) * 7) - 3, ky = static_cast<int>(u(rng) * 7) - 3;
    const double a = g(rng);
    const double ph = 2 * kPi * u(rng);
    waves.push_back({kx, ky, a, ph});
  }
  std::vector<float> z(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double v = 0.05 * g(rng);
      for (const Wave& w : waves) v += 0.1 * w.a * std::cos(2 * kPi * (w.kx * i + w.ky * j) / n + w.ph);
      z[static_cast<std::size_t>(j) * n + i] = static_cast<float>(v);
    }
  return z;
}

HeightGridView view(const std::vector<float>& z, int n, bool periodic) {
  HeightGridView g;
  g.nx = g.ny = n;
  g.dx = g.dy = 1.0 / n;
  g.z = &z;
  g.periodic = periodic;
  return g;
}

// The facet slopes as Microsurface::facet's planes give them, divided out plainly.
std::vector<std::array<double, 2>> plain_slopes(const HeightGridView& g) {
  std::vector<std::array<double, 2>> out;
  const int cx = g.periodic ? g.nx : g.nx - 1, cy = g.periodic ? g.ny : g.ny - 1;
  auto z = [&](int i, int j) { return static_cast<double>((*g.z)[static_cast<std::size_t>(j % g.ny) * g.nx + i % g.nx]); };
  for (int j = 0; j < cy; ++j)
    for (int i = 0; i < cx; ++i) {
      out.push_back({(z(i + 1, j) - z(i, j)) / g.dx, (z(i, j + 1) - z(i, j)) / g.dy});
      out.push_back({(z(i + 1, j + 1) - z(i, j + 1)) / g.dx, (z(i + 1, j + 1) - z(i + 1, j)) / g.dy});
    }
  return out;
}

bool same_slopes(const std::vector<std::array<double, 2>>& a, const std::vector<std::array<double, 2>>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
}

// The serial fits: one loop over the slope list per pass, 200 bisection steps.
struct SerialFit {
  double mean_x = 0, mean_y = 0, vx = 0, vy = 0, sg2 = 0, ggx = 0, ax2 = 0, ay2 = 0;
  int iterations = 0;
};
SerialFit serial_fit(const std::vector<std::array<double, 2>>& s) {
  SerialFit f;
  const double n = static_cast<double>(s.size());
  for (const auto& p : s) {
    f.mean_x += p[0] / n;
    f.mean_y += p[1] / n;
    f.sg2 += (p[0] * p[0] + p[1] * p[1]) / n;
  }
  for (const auto& p : s) {
    f.vx += (p[0] - f.mean_x) * (p[0] - f.mean_x) / n;
    f.vy += (p[1] - f.mean_y) * (p[1] - f.mean_y) / n;
  }
  const double sdq = std::sqrt(f.sg2);
  double lo = std::log(1e-12 + 1e-6 * sdq), hi = std::log(1e6 * (sdq + 1e-300));
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi), a2 = std::exp(2 * mid);
    double sum = 0;
    for (const auto& p : s) {
      const double x = p[0] - f.mean_x, y = p[1] - f.mean_y, v = x * x + y * y;
      sum += v / (a2 + v);
    }
    if (sum > 0.5 * n) lo = mid; else hi = mid;
  }
  f.ggx = std::exp(0.5 * (lo + hi));
  f.ax2 = 2 * f.vx;
  f.ay2 = 2 * f.vy;
  for (f.iterations = 1; f.iterations <= 2000; ++f.iterations) {
    double nx2 = 0, ny2 = 0;
    for (const auto& p : s) {
      const double x = p[0] - f.mean_x, y = p[1] - f.mean_y;
      const double w = 4.0 / (1.0 + x * x / f.ax2 + y * y / f.ay2);
      nx2 += w * x * x / n;
      ny2 += w * y * y / n;
    }
    const bool done = std::abs(nx2 - f.ax2) <= 1e-12 * f.ax2 && std::abs(ny2 - f.ay2) <= 1e-12 * f.ay2;
    f.ax2 = nx2;
    f.ay2 = ny2;
    if (done) break;
  }
  return f;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_identical(const SlopeStats& a, const SlopeStats& b) {
  for (auto [x, y] : {std::pair{a.mean_x, b.mean_x}, {a.mean_y, b.mean_y}, {a.rms_x, b.rms_x}, {a.rms_y, b.rms_y},
                      {a.sdq, b.sdq}, {a.ggx_alpha, b.ggx_alpha}, {a.ggx_alpha_x, b.ggx_alpha_x},
                      {a.ggx_alpha_y, b.ggx_alpha_y}, {a.beckmann_fit.chi2, b.beckmann_fit.chi2},
                      {a.ggx_fit.chi2, b.ggx_fit.chi2}})
    EXPECT_TRUE(same_bits(x, y)) << x << " vs " << y;
  EXPECT_EQ(a.ggx_iterations, b.ggx_iterations);
  EXPECT_EQ(a.beckmann_fit.observed, b.beckmann_fit.observed);
  EXPECT_EQ(a.ggx_fit.observed, b.ggx_fit.observed);
}

SlopeStats in_arena(int threads, const HeightGridView& g) {
  tbb::task_arena arena(threads);
  SlopeStats s;
  arena.execute([&] { s = slope_stats(g); });
  return s;
}

}  // namespace

TEST(MetrologyParallel, OneBlockEqualsTheSerialLoopBitForBit) {
  // 128^2 cells, 32768 facets: one block, so the sums run in the serial order.
  const int n = 128;
  const auto z = random_heights(n, 3);
  const HeightGridView g = view(z, n, true);  // cell size 1/128: slopes by multiplication
  const auto slopes = plain_slopes(g);
  ASSERT_TRUE(same_slopes(slopes, facet_slopes(g)));
  const SerialFit f = serial_fit(slopes);
  const SlopeStats s = slope_stats(g);
  EXPECT_TRUE(same_bits(s.mean_x, f.mean_x));
  EXPECT_TRUE(same_bits(s.rms_x, std::sqrt(f.vx)));
  EXPECT_TRUE(same_bits(s.rms_y, std::sqrt(f.vy)));
  EXPECT_TRUE(same_bits(s.sdq, std::sqrt(f.sg2)));
  EXPECT_TRUE(same_bits(s.ggx_alpha, f.ggx)) << s.ggx_alpha << " vs " << f.ggx;
  EXPECT_TRUE(same_bits(s.ggx_alpha_x, std::sqrt(f.ax2)));
  EXPECT_TRUE(same_bits(s.ggx_alpha_y, std::sqrt(f.ay2)));
  EXPECT_EQ(s.ggx_iterations, f.iterations);
  // The grid's slopes computed pass by pass are the listed ones.
  expect_identical(s, slope_stats(slopes));
  // Power: one height moved by 1e-7 (heights of order 1) changes the fit's bits.
  auto z2 = z;
  z2[777] += 1e-7f;
  EXPECT_FALSE(same_bits(slope_stats(view(z2, n, true)).ggx_alpha, s.ggx_alpha));
}

TEST(MetrologyParallel, ManyBlocksAgreeWithTheSerialLoopToRounding) {
  // 300^2 cells, 180000 facets in 3 blocks: the block sums differ from one serial sum by
  // rounding only. Bound: n eps relative for each sum of positive terms (the mean's sum of
  // signed terms is bounded by n eps times the mean of |s|, rms scale).
  const int n = 300;
  const auto z = random_heights(n, 4);
  const HeightGridView g = view(z, n, true);  // cell size 1/300: slopes by division
  const auto slopes = plain_slopes(g);
  ASSERT_TRUE(same_slopes(slopes, facet_slopes(g)));
  const SerialFit f = serial_fit(slopes);
  const SlopeStats s = slope_stats(g);
  const double tol = static_cast<double>(slopes.size()) * 2.3e-16;
  const double rms = std::sqrt(f.vx);
  EXPECT_NEAR(s.mean_x, f.mean_x, tol * rms);
  EXPECT_NEAR(s.rms_x, std::sqrt(f.vx), tol * rms);
  EXPECT_NEAR(s.rms_y, std::sqrt(f.vy), tol * std::sqrt(f.vy));
  EXPECT_NEAR(s.ggx_alpha, f.ggx, tol * f.ggx);
  EXPECT_NEAR(s.ggx_alpha_x, std::sqrt(f.ax2), tol * std::sqrt(f.ax2));
  EXPECT_NEAR(s.ggx_alpha_y, std::sqrt(f.ay2), tol * std::sqrt(f.ay2));
  EXPECT_NEAR(s.ggx_iterations, f.iterations, 1);
  // Power: an alpha 1e-9 off (a thousand times the bound) is told apart.
  EXPECT_GT(std::abs(f.ggx * (1 + 1e-9) - s.ggx_alpha), tol * f.ggx);
  EXPECT_GT(std::abs(std::sqrt(f.ax2) * (1 + 1e-9) - s.ggx_alpha_x), tol * std::sqrt(f.ax2));
}

TEST(MetrologyParallel, ResultsDoNotDependOnTheThreadCount) {
  const int n = 200;  // 80000 facets: 2 blocks, the second one partial
  const auto z = random_heights(n, 5);
  for (bool periodic : {true, false}) {
    const HeightGridView g = view(z, n, periodic);
    const SlopeStats one = in_arena(1, g);
    expect_identical(one, in_arena(2, g));
    // The listed slopes in the same blocks give the same bits.
    ASSERT_TRUE(same_slopes(plain_slopes(g), facet_slopes(g)));
    expect_identical(one, slope_stats(plain_slopes(g)));
    // The ACF (row and column transforms in parallel) too.
    std::vector<double> a1, a2;
    tbb::task_arena(1).execute([&] { a1 = autocorrelation(g); });
    tbb::task_arena(2).execute([&] { a2 = autocorrelation(g); });
    ASSERT_EQ(a1.size(), a2.size());
    EXPECT_EQ(0, std::memcmp(a1.data(), a2.data(), a1.size() * sizeof(double)));
  }
}

TEST(MetrologyParallel, AcfEqualsTheDirectSumOnASmallGrid) {
  // Independent route: the circular ACF as the direct sum over all pairs, normalized at lag 0.
  const int n = 24;
  const auto z = random_heights(n, 6);
  const HeightGridView g = view(z, n, true);
  const auto acf = autocorrelation(g);
  double mean = 0;
  for (float v : z) mean += v;
  mean /= z.size();
  auto c = [&](int di, int dj) {
    double sum = 0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        sum += (z[j * n + i] - mean) * (z[((j + dj) % n) * n + (i + di) % n] - mean);
    return sum;
  };
  const double c0 = c(0, 0);
  double worst = 0;
  for (int dj = 0; dj < n; ++dj)
    for (int di = 0; di < n; ++di) worst = std::max(worst, std::abs(acf[dj * n + di] - c(di, dj) / c0));
  EXPECT_LT(worst, 1e-12);
  // Power: the ACF of a shifted lag is not the direct sum.
  EXPECT_GT(std::abs(acf[1] - c(2, 0) / c0), 1e-3);
}
