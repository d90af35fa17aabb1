#include "microsim/measure/bsdf_table.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "microsim/measure/table_run_sums.hpp"

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
  const int N = o.phi_i.size() == 1 ? o.table_azimuths : 1;
  if (N < 1) throw ParameterError("{table_azimuths} must be at least 1");
  if (N > 1) {
    if (o.base.rays < static_cast<std::uint64_t>(N))
      throw ParameterError("{table_azimuths}: " + std::to_string(N) + " azimuths need at least as many {rays}");
    for (int a = 0; a < N; ++a) table.turns.push_back(2.0 * kPi * a / N);
    table.turned.resize(o.theta_i.size());
  }
  const int n = static_cast<int>(o.theta_i.size() * o.phi_i.size()) * N;
  table.results.reserve(o.theta_i.size() * o.phi_i.size());
  int k = 0;
  for (double phi : o.phi_i)
    for (std::size_t t = 0; t < o.theta_i.size(); ++t)
      for (int a = 0; a < N; ++a) {
        BsdfOptions b = o.base;
        b.theta_i = o.theta_i[t];
        b.phi_i = N > 1 ? phi + table.turns[a] : phi;
        // rays / N walks per azimuth, the remainder to the first ones: the cost is unchanged.
        b.rays = o.base.rays / N + (static_cast<std::uint64_t>(a) < o.base.rays % N ? 1 : 0);
        // The models go beside the nominal run only (the record's rows), as without averaging.
        if (a > 0) b.models = false, b.model_walks = 0;
        const bool table_only = a > 0 && o.turned_runs != BsdfTableOptions::TurnedRuns::Everything;
        if (table_only) {
          b.table_sums_only = true;
          if (o.turned_runs == BsdfTableOptions::TurnedRuns::TableF) b.polarized = false;
        }
        if (o.progress) b.progress = [&, k](double f) { o.progress((k + f) / n); };
        else b.progress = nullptr;
        if (a == 0) table.results.push_back(measure_bsdf(tracer, b));
        else {
          table.turned[t].push_back(measure_bsdf(tracer, b));
          // The turned runs enter the table's averages, not the record: only the table's sums stay.
          BsdfResult& turned = table.turned[t].back();
          if (table_only) keep_table_sums_only(turned, o.turned_runs == BsdfTableOptions::TurnedRuns::TableF);
          else if (turned.polarization) turned.polarization->keep_table_sums_only();
        }
        ++k;
      }
  table.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return table;
}

double interpolate_f(const BsdfResult& r, int side, int slot, const Vec3& wo, int lambda) {
  const int R = r.map.resolution();
  auto pixel = [&](int i, int j) { return f_pixel_mean(r, side, slot, j * R + i, lambda); };
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

std::uint64_t BsdfTable::paths(int p, int t) const {
  std::uint64_t n = at(p, t).measured.paths;
  if (!turned.empty())
    for (const BsdfResult& r : turned[static_cast<std::size_t>(t)]) n += r.measured.paths;
  return n;
}

Vec3 turn_about_normal(const Vec3& v, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return Vec3(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z());
}

double table_f(const BsdfTable& table, int p, int t, int side, int slot, const Vec3& wo, int lambda) {
  const BsdfResult& r0 = table.at(p, t);
  if (table.turned.empty()) return interpolate_f(r0, side, slot, wo, lambda);
  // Each run's f weighted by its walks: the mean over all walks of the table entry.
  double sum = static_cast<double>(r0.measured.paths) * interpolate_f(r0, side, slot, wo, lambda);
  double walks = static_cast<double>(r0.measured.paths);
  const auto& runs = table.turned[static_cast<std::size_t>(t)];
  for (std::size_t a = 0; a < runs.size(); ++a) {
    const double w = static_cast<double>(runs[a].measured.paths);
    sum += w * interpolate_f(runs[a], side, slot, turn_about_normal(wo, table.turns[a + 1]), lambda);
    walks += w;
  }
  return sum / walks;
}

}  // namespace microsim
