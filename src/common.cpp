#include "microsim/common.hpp"

namespace microsim {

Estimate binomial_estimate(std::uint64_t k, std::uint64_t n) {
  Estimate e;
  e.n = n;
  if (n == 0) return e;
  e.mean = static_cast<double>(k) / static_cast<double>(n);
  e.stderr_ = std::sqrt(std::max(0.0, e.mean * (1.0 - e.mean)) / static_cast<double>(n));
  return e;
}

}  // namespace microsim
