#include "microsim/measure/bsdf_table.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace microsim {

BsdfTable measure_bsdf_table(const Tracer& tracer, const BsdfTableOptions& o) {
  if (o.theta_i.empty()) throw ParameterError("{theta_i}: no incidence angle given");
  if (o.phi_i.empty()) throw ParameterError("{phi_i}: no azimuth given");
  for (double t : o.theta_i)
    if (!(t >= 0.0 && t < 0.5 * kPi))
      throw ParameterError("{theta_i} must be in [0, 90) degrees (got " + std::to_string(deg(t)) + ")");
  for (double p : o.phi_i)
    if (!std::isfinite(p)) throw ParameterError("{phi_i} must be finite");
  const auto t0 = std::chrono::steady_clock::now();
  BsdfTable table;
  table.theta_i = o.theta_i;
  table.phi_i = o.phi_i;
  const int n = static_cast<int>(o.theta_i.size() * o.phi_i.size());
  table.results.reserve(static_cast<std::size_t>(n));
  int k = 0;
  for (double phi : o.phi_i)
    for (double theta : o.theta_i) {
      BsdfOptions b = o.base;
      b.theta_i = theta;
      b.phi_i = phi;
      if (o.progress) b.progress = [&, k](double f) { o.progress((k + f) / n); };
      else b.progress = nullptr;
      table.results.push_back(measure_bsdf(tracer, b));
      ++k;
    }
  table.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return table;
}

double interpolate_f(const BsdfResult& r, int side, int slot, const Vec3& wo, int lambda) {
  const int R = r.map.resolution();
  auto pixel = [&](int i, int j) { return r.f_pixel(side, slot, j * R + i, lambda).mean; };
  if (R == 1) return pixel(0, 0);
  const Vec2 sq = r.map.to_square(wo);
  // Pixel centres sit at a = -1 + (i + 1/2) 2/R: continuous index x = (a + 1) R/2 - 1/2.
  const double x = std::clamp((sq.x() + 1.0) * 0.5 * R - 0.5, 0.0, R - 1.0);
  const double y = std::clamp((sq.y() + 1.0) * 0.5 * R - 0.5, 0.0, R - 1.0);
  const int i = std::min(static_cast<int>(x), R - 2), j = std::min(static_cast<int>(y), R - 2);
  const double fx = x - i, fy = y - j;
  return (1 - fy) * ((1 - fx) * pixel(i, j) + fx * pixel(i + 1, j)) +
         fy * ((1 - fx) * pixel(i, j + 1) + fx * pixel(i + 1, j + 1));
}

}  // namespace microsim
