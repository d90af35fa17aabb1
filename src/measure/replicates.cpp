#include "microsim/measure/replicates.hpp"

namespace microsim {

ReplicatePlan::ReplicatePlan(std::uint64_t rays, int requested) {
  if (requested < 2)
    throw ParameterError("{replicates} must be at least 2 (the error is the spread between replicates)");
  replicates = static_cast<int>(std::max<std::uint64_t>(1, std::min<std::uint64_t>(requested, rays)));
  strata = Strata((rays + replicates - 1) / replicates);
}

Estimate replicate_mean(const std::vector<double>& x) {
  Estimate e;
  const std::size_t R = x.size();
  e.n = R;
  if (R == 0) return e;
  double sum = 0;
  for (double v : x) sum += v;
  e.mean = sum / R;
  if (R < 2) return e;
  double ss = 0;
  for (double v : x) ss += (v - e.mean) * (v - e.mean);
  e.stderr_ = std::sqrt(ss / (R - 1) / R);
  return e;
}

Estimate replicate_mean(const std::vector<std::uint64_t>& counts, double scale) {
  std::vector<double> x(counts.size());
  for (std::size_t r = 0; r < counts.size(); ++r) x[r] = scale * static_cast<double>(counts[r]);
  return replicate_mean(x);
}

Estimate replicate_ratio(const std::vector<std::uint64_t>& y, const std::vector<std::uint64_t>& x) {
  Estimate e;
  const std::size_t R = x.size();
  double sy = 0, sx = 0;
  for (std::size_t r = 0; r < R; ++r) {
    sy += static_cast<double>(y[r]);
    sx += static_cast<double>(x[r]);
  }
  e.n = static_cast<std::uint64_t>(sx);
  if (!(sx > 0)) return e;
  e.mean = sy / sx;
  if (R < 2) return e;
  double ss = 0;
  for (std::size_t r = 0; r < R; ++r) {
    const double d = static_cast<double>(y[r]) - e.mean * static_cast<double>(x[r]);
    ss += d * d;
  }
  e.stderr_ = std::sqrt(ss / (R * (R - 1.0))) / (sx / R);
  return e;
}

Estimate jackknife(double theta_all, const std::vector<double>& t) {
  Estimate e;
  e.mean = theta_all;
  const std::size_t R = t.size();
  e.n = R;
  if (R < 2) return e;
  double m = 0;
  for (double v : t) m += v / R;
  double ss = 0;
  for (double v : t) ss += (v - m) * (v - m);
  e.stderr_ = std::sqrt((R - 1.0) / R * ss);
  return e;
}

}  // namespace microsim
