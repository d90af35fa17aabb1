// Stratified origins along the Morton curve (measure/sampling.hpp): exactly the requested
// count, each point inside its own piece of the curve, uniform over the square, and a lower
// variance than independent points.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/statistics.hpp"

using namespace microsim;

namespace {

constexpr int kBits = Strata::kFineBits;
constexpr std::uint64_t kFineCells = std::uint64_t(1) << (2 * kBits);

// Morton code of the fine cell holding p (inverse of morton_decode, written bit by bit).
std::uint64_t fine_cell_code(const Vec2& p) {
  const auto fx = static_cast<std::uint64_t>(std::floor(p.x() * (1u << kBits)));
  const auto fy = static_cast<std::uint64_t>(std::floor(p.y() * (1u << kBits)));
  std::uint64_t code = 0;
  for (int b = 0; b < kBits; ++b) {
    code |= ((fx >> b) & 1u) << (2 * b);
    code |= ((fy >> b) & 1u) << (2 * b + 1);
  }
  return code;
}

// First and last fine cell (Morton code) that piece i of n touches.
void piece_cells(std::uint64_t i, std::uint64_t n, std::uint64_t& first, std::uint64_t& last) {
  first = static_cast<std::uint64_t>(std::floor(double(i) / double(n) * double(kFineCells)));
  last = std::min(kFineCells - 1,
                  static_cast<std::uint64_t>(std::ceil(double(i + 1) / double(n) * double(kFineCells))));
}

// The same points with the position along the piece fixed at its start (a deliberately wrong
// sampler: it covers only the fine cells where pieces begin).
Vec2 piece_start_point(std::uint64_t i, std::uint64_t n, CounterRng& rng) {
  const double jx = rng.uniform();
  const double jy = rng.uniform();
  std::uint64_t first, last;
  piece_cells(i, n, first, last);
  std::uint32_t fx, fy;
  morton_decode(first, fx, fy);
  return Vec2((fx + jx) / double(1u << kBits), (fy + jy) / double(1u << kBits));
}

}  // namespace

TEST(Strata, CountIsExactlyTheRequest) {
  for (std::uint64_t n : {1ull, 2ull, 3ull, 7ull, 1000ull, 1000003ull, 1ull << 20})
    EXPECT_EQ(Strata(n).total(), n);
  // Replicates: the request rounded up to a multiple of R, no further.
  EXPECT_EQ(ReplicatePlan(10000000, 32).total(), 10000000u);
  EXPECT_EQ(ReplicatePlan(2500000, 32).total(), 2500000u);
  EXPECT_EQ(ReplicatePlan(1000001, 32).total(), 32u * 31251u);
  EXPECT_EQ(ReplicatePlan(5, 32).total(), 5u);  // R lowered to the request
}

TEST(Strata, EveryPointLiesInItsOwnPieceOfTheCurve) {
  const std::uint64_t n = 1003;  // not a power of two: pieces cut fine cells
  const Strata strata(n);
  int outside = 0, outside_next = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed)
    for (std::uint64_t i = 0; i < n; ++i) {
      CounterRng rng(seed, 77, i);
      const Vec2 p = strata.point(i, rng);
      ASSERT_GE(p.x(), 0.0);
      ASSERT_LT(p.x(), 1.0);
      ASSERT_GE(p.y(), 0.0);
      ASSERT_LT(p.y(), 1.0);
      const std::uint64_t code = fine_cell_code(p);
      std::uint64_t first, last;
      piece_cells(i, n, first, last);
      outside += code < first || code > last;
      // Power: the neighbouring piece's bounds do not hold these points.
      piece_cells((i + 1) % n, n, first, last);
      outside_next += code < first || code > last;
    }
  EXPECT_EQ(outside, 0);
  EXPECT_EQ(outside_next, 20 * int(n));
}

TEST(Strata, PointsCoverTheSquareUniformly) {
  // Pooled over seeds, the points of n = 1003 pieces fall uniformly into a 16 x 16 grid
  // (Pearson chi-square); the sampler that fixes each point at its piece's start is told apart.
  const std::uint64_t n = 1003;
  const int G = 16, seeds = 400;
  const Strata strata(n);
  std::vector<double> right(G * G, 0.0), wrong(G * G, 0.0);
  for (std::uint64_t seed = 1; seed <= seeds; ++seed)
    for (std::uint64_t i = 0; i < n; ++i) {
      CounterRng rng(seed, 5, i);
      const Vec2 p = strata.point(i, rng);
      right[int(p.y() * G) * G + int(p.x() * G)] += 1;
      CounterRng rng2(seed, 5, i);
      const Vec2 q = piece_start_point(i, n, rng2);
      wrong[int(q.y() * G) * G + int(q.x() * G)] += 1;
    }
  const std::vector<double> expected(G * G, double(n) * seeds / (G * G));
  const ChiSquareResult ok = pearson_chi2(right, expected);
  EXPECT_TRUE(ok.passed()) << ok.summary();
  const ChiSquareResult bad = pearson_chi2(wrong, expected);
  EXPECT_FALSE(bad.passed()) << bad.summary();
}

TEST(Strata, MeanOfAnIndicatorVariesLessThanWithIndependentPoints) {
  // The area of a disk by n points: stratified, its error comes from the pieces the edge
  // crosses only, far below the binomial p (1 - p) / n of independent points.
  const std::uint64_t n = 1003;
  const int seeds = 300;
  const Strata strata(n);
  auto inside = [](const Vec2& p) {
    return (p.x() - 0.5) * (p.x() - 0.5) + (p.y() - 0.45) * (p.y() - 0.45) < 0.16;
  };
  double s1 = 0, s2 = 0, i1 = 0, i2 = 0;
  for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
    double a = 0, b = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
      CounterRng rng(seed, 9, i);
      a += inside(strata.point(i, rng));
      CounterRng rng2(seed, 10, i);
      const double x = rng2.uniform();
      const double y = rng2.uniform();
      b += inside(Vec2(x, y));
    }
    a /= n;
    b /= n;
    s1 += a;
    s2 += a * a;
    i1 += b;
    i2 += b * b;
  }
  const double area = M_PI * 0.16;
  const double var_strat = (s2 - s1 * s1 / seeds) / (seeds - 1);
  const double var_indep = (i2 - i1 * i1 / seeds) / (seeds - 1);
  const double binomial = area * (1 - area) / n;
  // Unbiased: the stratified mean within 4 of its own standard errors of pi r^2.
  EXPECT_NEAR(s1 / seeds, area, 4 * std::sqrt(var_strat / seeds));
  EXPECT_LT(var_strat, binomial / 10);
  // Power: independent points reach the binomial variance and fail the same bound.
  EXPECT_GT(var_indep, binomial / 2);
}

TEST(Strata, MortonEncodeInterleavesTheBitsAndInvertsDecode) {
  CounterRng rng(5, 9, 0);
  for (int t = 0; t < 2000; ++t) {
    const auto x = static_cast<std::uint32_t>(rng.next_u64()), y = static_cast<std::uint32_t>(rng.next_u64());
    std::uint64_t bitwise = 0;  // the same interleaving written bit by bit
    for (int b = 0; b < 32; ++b) {
      bitwise |= static_cast<std::uint64_t>((x >> b) & 1u) << (2 * b);
      bitwise |= static_cast<std::uint64_t>((y >> b) & 1u) << (2 * b + 1);
    }
    ASSERT_EQ(morton_encode(x, y), bitwise);
    std::uint32_t dx, dy;
    morton_decode(morton_encode(x, y), dx, dy);
    ASSERT_EQ(dx, x);
    ASSERT_EQ(dy, y);
    if (x != y) ASSERT_NE(morton_encode(y, x), bitwise);  // power: the order of the coordinates matters
  }
}
