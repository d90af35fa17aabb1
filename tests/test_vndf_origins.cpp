// A VNDF ray origin held in 16 bytes (VndfOrigin): the two uniforms come back exactly, and the
// origins sort in Morton order of their 21 leading bits with the coordinates as tie-breaks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <tuple>
#include <vector>

#include "../src/measure/vndf_estimator.hpp"
#include "microsim/common.hpp"

namespace {
using namespace microsim;

// The Morton key of the 21 leading bits of a and b, bit by bit (b's bit above a's at every level).
std::uint64_t morton_key(double a, double b) {
  const auto ca = static_cast<std::uint64_t>(a * (1 << 21)), cb = static_cast<std::uint64_t>(b * (1 << 21));
  std::uint64_t key = 0;
  for (int bit = 0; bit < 21; ++bit) key |= ((ca >> bit) & 1) << (2 * bit) | ((cb >> bit) & 1) << (2 * bit + 1);
  return key;
}

// Uniforms as CounterRng draws them (k 2^-53), some sharing their 21 leading bits (equal keys:
// the coordinates decide).
std::vector<Vec2> draws() {
  constexpr double kUnit = 1.0 / 9007199254740992.0;
  constexpr std::uint64_t kLead = ~std::uint64_t(0xFFFFFFFF);  // the 21 leading of 53 bits
  std::vector<Vec2> v;
  for (std::uint64_t j = 0; j < 4000; ++j) {
    CounterRng rng(7, 11, j);
    const std::uint64_t ka = rng.next_u64() >> 11, kb = rng.next_u64() >> 11;
    const std::uint64_t ta = rng.next_u64() >> 32, tb = rng.next_u64() >> 32;
    v.emplace_back(ka * kUnit, kb * kUnit);
    v.emplace_back(((ka & kLead) | ta) * kUnit, ((kb & kLead) | tb) * kUnit);
    v.emplace_back(ka * kUnit, ((kb & kLead) | tb) * kUnit);
  }
  v.emplace_back(0.0, 0.0);
  v.emplace_back(1.0 - kUnit, 1.0 - kUnit);
  return v;
}

TEST(VndfOrigins, TheCoordinatesComeBackExactly) {
  for (const Vec2& p : draws()) {
    const Vec2 q = VndfOrigin::of(p.x(), p.y()).ab();
    EXPECT_EQ(q.x(), p.x());
    EXPECT_EQ(q.y(), p.y());
  }
}

TEST(VndfOrigins, TheySortByMortonKeyThenCoordinates) {
  std::vector<Vec2> expected = draws();
  std::vector<VndfOrigin> sorted;
  for (const Vec2& p : expected) sorted.push_back(VndfOrigin::of(p.x(), p.y()));
  std::sort(expected.begin(), expected.end(), [](const Vec2& p, const Vec2& q) {
    return std::make_tuple(morton_key(p.x(), p.y()), p.x(), p.y()) < std::make_tuple(morton_key(q.x(), q.y()), q.x(), q.y());
  });
  std::sort(sorted.begin(), sorted.end());
  ASSERT_EQ(sorted.size(), expected.size());
  for (std::size_t j = 0; j < sorted.size(); ++j) {
    EXPECT_EQ(sorted[j].ab().x(), expected[j].x()) << j;
    EXPECT_EQ(sorted[j].ab().y(), expected[j].y()) << j;
  }
}

}  // namespace
