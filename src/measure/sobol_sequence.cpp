#include "microsim/measure/sobol_sequence.hpp"

#include <stdexcept>

namespace microsim {

namespace {

// Direction numbers of dimensions 2 .. kSobolDims from [JoeKuo08] (their file new-joe-kuo-6.21201,
// lines d = 2 .. 9): degree s and coefficients a of the primitive polynomial, initial m_1 .. m_s.
struct Primitive {
  int s, a;
  std::uint32_t m[5];
};
constexpr Primitive kPrimitives[kSobolDims - 1] = {
    {1, 0, {1}},          {2, 1, {1, 3}},          {3, 1, {1, 3, 1}},       {3, 2, {1, 1, 1}},
    {4, 1, {1, 1, 3, 3}}, {4, 4, {1, 3, 5, 13}},   {5, 2, {1, 1, 5, 5, 17}}, {5, 4, {1, 1, 5, 5, 5}}};

struct DirectionNumbers {
  std::uint32_t v[kSobolDims][32];  // v[d][b] = m_{b+1} 2^(31 - b)
  // prefix[d][b] = v[d][0] ^ ... ^ v[d][b]: what changes from j - 1 to j when b = ctz(j)
  std::uint32_t prefix[kSobolDims][32];

  DirectionNumbers() {
    for (int b = 0; b < 32; ++b) v[0][b] = 1u << (31 - b);  // dimension 1: van der Corput
    for (int d = 1; d < kSobolDims; ++d) {
      const Primitive& p = kPrimitives[d - 1];
      std::uint32_t m[32];
      for (int i = 0; i < p.s; ++i) m[i] = p.m[i];
      // m_i = 2 a_1 m_{i-1} ^ 4 a_2 m_{i-2} ^ ... ^ 2^s m_{i-s} ^ m_{i-s}, the recurrence of [JoeKuo08]
      for (int i = p.s; i < 32; ++i) {
        std::uint32_t x = m[i - p.s] ^ (m[i - p.s] << p.s);
        for (int k = 1; k < p.s; ++k)
          if ((p.a >> (p.s - 1 - k)) & 1) x ^= m[i - k] << k;
        m[i] = x;
      }
      for (int b = 0; b < 32; ++b) v[d][b] = m[b] << (31 - b);
    }
    for (int d = 0; d < kSobolDims; ++d) {
      std::uint32_t x = 0;
      for (int b = 0; b < 32; ++b) prefix[d][b] = x ^= v[d][b];
    }
  }
};

const DirectionNumbers& direction_numbers() {
  static const DirectionNumbers numbers;
  return numbers;
}

void check_dimension(int d) {
  if (d < 0 || d >= kSobolDims) throw std::invalid_argument("sobol: dimension out of range");
}

int trailing_zeros(std::uint64_t j) {
  int b = 0;
  for (; !(j & 1); j >>= 1) ++b;
  return b;
}

}  // namespace

std::uint32_t sobol_component(std::uint64_t j, int d) {
  check_dimension(d);
  const DirectionNumbers& dn = direction_numbers();
  std::uint32_t x = 0;
  for (int b = 0; j != 0 && b < 32; j >>= 1, ++b)
    if (j & 1) x ^= dn.v[d][b];
  return x;
}

void shifted_sobol_components(std::uint64_t first, std::uint64_t n, int d, std::uint32_t shift, std::uint32_t* out) {
  if (n == 0) return;
  const DirectionNumbers& dn = direction_numbers();
  std::uint32_t x = sobol_component(first, d);
  out[0] = x ^ shift;
  for (std::uint64_t i = 1; i < n; ++i) {
    const int b = trailing_zeros(first + i);
    x ^= b < 32 ? dn.prefix[d][b] : dn.prefix[d][31];  // past 2^32 points the sequence repeats its bits
    out[i] = x ^ shift;
  }
}

}  // namespace microsim
