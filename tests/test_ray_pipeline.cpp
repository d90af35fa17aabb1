// The look-ahead loop of the primary rays (trace/ray_pipeline.hpp): every state is used once,
// in the order it was made, after exactly the intended number of set-ups ahead of it.
#include <gtest/gtest.h>

#include <vector>

#include "microsim/trace/ray_pipeline.hpp"

using namespace microsim;

TEST(RayPipeline, UsesEveryStateInOrderAfterItsLookAhead) {
  for (std::uint64_t m : {0ull, 1ull, 5ull, 8ull, 9ull, 17ull, 1000ull}) {
    std::uint64_t made = 0;
    std::vector<std::uint64_t> used, made_when_used;
    run_ahead<std::uint64_t, 8>(
        m, [&] { return made++; },
        [&](std::uint64_t k) {
          used.push_back(k);
          made_when_used.push_back(made);
        });
    ASSERT_EQ(made, m);
    ASSERT_EQ(used.size(), m);
    for (std::uint64_t k = 0; k < m; ++k) {
      EXPECT_EQ(used[k], k) << "m " << m;
      EXPECT_EQ(made_when_used[k], std::min(k + 9, m)) << "m " << m;
    }
  }
  // A look-ahead as long as the ring allows (ring of 64 states).
  std::uint64_t made = 0, next_used = 0;
  bool in_order = true;
  run_ahead<std::uint64_t, 63>(
      500, [&] { return made++; }, [&](std::uint64_t k) { in_order = in_order && k == next_used++; });
  EXPECT_TRUE(in_order);
  EXPECT_EQ(next_used, 500u);
}
