// Tests of the Sobol sequence (measure/sobol_sequence.hpp): every dimension stratified at every power of two
// (with a power check), dimensions 0 and 1 a (0, k, 2)-net, dimension 0 the van der Corput sequence and
// dimension 1 the Pascal matrix mod 2 (independent routes to the direction numbers), and the incremental
// shifted components equal to the direct ones.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "microsim/measure/sobol_sequence.hpp"

using namespace microsim;

namespace {

// True when the n = 2^k values hit each interval [i / n, (i + 1) / n) exactly once.
bool stratified(const std::vector<std::uint32_t>& x, int k) {
  std::vector<int> hits(std::size_t(1) << k, 0);
  for (const std::uint32_t v : x) ++hits[k == 0 ? 0 : v >> (32 - k)];
  for (const int h : hits)
    if (h != 1) return false;
  return true;
}

std::vector<std::uint32_t> components(int d, std::uint64_t n, std::uint32_t shift = 0) {
  std::vector<std::uint32_t> x(n);
  shifted_sobol_components(0, n, d, shift, x.data());
  return x;
}

std::uint32_t bit_reverse(std::uint32_t j) {
  std::uint32_t r = 0;
  for (int b = 0; b < 32; ++b) r |= ((j >> b) & 1u) << (31 - b);
  return r;
}

}  // namespace

TEST(SobolSequence, EveryDimensionIsStratifiedAtEveryPowerOfTwo) {
  for (int d = 0; d < kSobolDims; ++d)
    for (int k = 0; k <= 14; ++k) {
      EXPECT_TRUE(stratified(components(d, std::uint64_t(1) << k), k)) << "dimension " << d << " 2^" << k;
      // a digital shift permutes the intervals: still stratified
      EXPECT_TRUE(stratified(components(d, std::uint64_t(1) << k, 0x9E3779B9u), k)) << "dimension " << d;
    }
  // Power: the first 2^k points with every odd point replaced by its even neighbour are not stratified.
  std::vector<std::uint32_t> x = components(3, 1024);
  for (std::size_t j = 1; j < x.size(); j += 2) x[j] = x[j - 1];
  EXPECT_FALSE(stratified(x, 10));
}

TEST(SobolSequence, FirstTwoDimensionsFormAZeroNet) {
  // Every box [i / 2^a, (i + 1) / 2^a) x [l / 2^(k - a), (l + 1) / 2^(k - a)) holds one of the first 2^k points.
  for (int k = 1; k <= 12; ++k) {
    const std::uint64_t n = std::uint64_t(1) << k;
    const std::vector<std::uint32_t> x = components(0, n), y = components(1, n);
    for (int a = 0; a <= k; ++a) {
      std::vector<int> hits(n, 0);
      for (std::uint64_t j = 0; j < n; ++j) {
        const std::uint64_t i = a == 0 ? 0 : x[j] >> (32 - a), l = a == k ? 0 : y[j] >> (32 - (k - a));
        ++hits[(i << (k - a)) | l];
      }
      for (const int h : hits) ASSERT_EQ(h, 1) << "2^" << k << " points, boxes 2^-" << a << " x 2^-" << k - a;
    }
  }
}

TEST(SobolSequence, DimensionZeroIsVanDerCorput) {
  for (std::uint64_t j : {0ull, 1ull, 2ull, 3ull, 1000ull, 65535ull, 123456789ull, 4294967295ull})
    EXPECT_EQ(sobol_component(j, 0), bit_reverse(static_cast<std::uint32_t>(j))) << j;
}

TEST(SobolSequence, DimensionOneIsThePascalMatrixModTwo) {
  // The polynomial x + 1 gives the generator matrix C(b, i) mod 2: bit i (from the top) of x_1(j) is the sum
  // over the bits b of j of C(b, i) mod 2, and C(b, i) is odd exactly when i's bits are among b's (Lucas).
  for (std::uint64_t j = 0; j < 5000; j += 7) {
    std::uint32_t x = 0;
    for (int i = 0; i < 32; ++i) {
      int bit = 0;
      for (int b = 0; b < 32; ++b)
        if (((j >> b) & 1) && (static_cast<unsigned>(i) & ~static_cast<unsigned>(b)) == 0) bit ^= 1;
      x |= static_cast<std::uint32_t>(bit) << (31 - i);
    }
    ASSERT_EQ(sobol_component(j, 1), x) << j;
  }
  // its first points in natural order: 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8
  const double expected[8] = {0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875};
  for (int j = 0; j < 8; ++j) EXPECT_EQ(sobol_component(j, 1) * 0x1p-32, expected[j]);
}

TEST(SobolSequence, IncrementalShiftedComponentsEqualTheDirectOnes) {
  for (int d = 0; d < kSobolDims; ++d)
    for (std::uint64_t first : {0ull, 1ull, 1000ull, 65530ull}) {
      const std::uint32_t shift = 0x12345678u * static_cast<std::uint32_t>(d + 1);
      std::vector<std::uint32_t> x(3000);
      shifted_sobol_components(first, x.size(), d, shift, x.data());
      for (std::size_t i = 0; i < x.size(); ++i)
        ASSERT_EQ(x[i], sobol_component(first + i, d) ^ shift) << "dimension " << d << " point " << first + i;
    }
  EXPECT_THROW(sobol_component(0, kSobolDims), std::invalid_argument);
}
