// The first dimensions of Sobol's sequence [Sobol67] with the direction numbers of [JoeKuo08], as 32-bit
// binary fractions: component d of point j is x_d(j) = XOR over the set bits b of j of v_d[b] (natural
// order, not Gray-code order). Every dimension's first 2^k points hit each of the 2^k intervals
// [i / 2^k, (i + 1) / 2^k) exactly once, and dimensions 0 and 1 form a (0, k, 2)-net.
//
// A digital shift (x_d(j) XOR s_d, s_d uniform on 32 bits) plus a uniform below 2^-32 makes every point
// uniform on [0, 1)^D while keeping the net's structure: a randomized quasi-Monte Carlo point set whose
// replicates, independently shifted, are independent estimates.
#pragma once

#include <cstdint>

namespace microsim {

constexpr int kSobolDims = 9;

// x_d(j) * 2^32, d in [0, kSobolDims).
std::uint32_t sobol_component(std::uint64_t j, int d);

// x_d(first), ..., x_d(first + n - 1) XOR shift into out[0 .. n): one XOR per point after the first
// (x_d(j) = x_d(j - 1) XOR the direction numbers of the bits that change from j - 1 to j).
void shifted_sobol_components(std::uint64_t first, std::uint64_t n, int d, std::uint32_t shift, std::uint32_t* out);

}  // namespace microsim
