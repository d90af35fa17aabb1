#include "microsim/measure/compensation_maps.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "microsim/models/smith_random_walk.hpp"

namespace microsim {

std::vector<double> lobe_map(const HemisphereMap& map, const LobeFunction& f, int sub) {
  const int R = map.resolution();
  std::vector<double> out(map.size(), 0.0);
  tbb::parallel_for(0, map.size(), [&](int px) {
    const int i = px % R, j = px / R;
    double sf = 0.0, sc = 0.0;
    for (int u = 0; u < sub; ++u)
      for (int v = 0; v < sub; ++v) {
        const double a = -1.0 + 2.0 * (i + (u + 0.5) / sub) / R;
        const double b = -1.0 + 2.0 * (j + (v + 0.5) / sub) / R;
        const Vec3 o = map.from_square(a, b);
        sf += f(o) * o.z();
        sc += o.z();
      }
    out[px] = sc > 0.0 ? sf / sc : 0.0;
  });
  return out;
}

double map_albedo(const HemisphereMap& map, const std::vector<double>& f) {
  if (static_cast<int>(f.size()) != map.size()) throw std::invalid_argument("map_albedo: map size differs");
  double s = 0.0;
  for (int px = 0; px < map.size(); ++px) s += f[px] * map.pixel_cos_integral(px);
  return s;
}

WalkMap smith_walk_map(const models::Ndf& ndf, const models::Material& material, const Vec3& i,
                       const HemisphereMap& map, int min_order, std::uint64_t walks, std::uint64_t seed) {
  const models::SmithRandomWalk walk(ndf, material);
  // Per-chunk power tallies, summed in chunk order (independent of the number of threads).
  constexpr std::uint64_t kChunk = 1 << 14;
  const std::uint64_t chunks = (walks + kChunk - 1) / kChunk;
  std::vector<std::vector<double>> parts(chunks, std::vector<double>(map.size(), 0.0));
  tbb::parallel_for(std::uint64_t{0}, chunks, [&](std::uint64_t c) {
    for (std::uint64_t k = c * kChunk; k < std::min(walks, (c + 1) * kChunk); ++k) {
      CounterRng rng(seed, 0, k);
      const models::WalkExit e = walk.walk(i, rng);
      if (e.lost || !e.reflected || e.order < min_order) continue;
      parts[c][map.pixel_of(e.direction)] += e.weight;
    }
  });
  WalkMap out;
  out.f.assign(map.size(), 0.0);
  for (const auto& p : parts)
    for (int px = 0; px < map.size(); ++px) out.f[px] += p[px];
  for (int px = 0; px < map.size(); ++px) {
    out.albedo += out.f[px] / walks;
    out.f[px] /= walks * map.pixel_cos_integral(px);
  }
  return out;
}

double hellinger_distance(const std::vector<double>& c, const std::vector<double>& f, const std::vector<double>& g) {
  if (f.size() != c.size() || g.size() != c.size()) throw std::invalid_argument("hellinger_distance: map sizes differ");
  double pf = 0.0, pg = 0.0;
  for (std::size_t k = 0; k < c.size(); ++k) {
    pf += std::max(f[k], 0.0) * c[k];
    pg += std::max(g[k], 0.0) * c[k];
  }
  if (!(pf > 0.0) || !(pg > 0.0)) throw std::invalid_argument("hellinger_distance: a map without positive power");
  double bc = 0.0;  // Bhattacharyya coefficient
  for (std::size_t k = 0; k < c.size(); ++k) bc += std::sqrt(std::max(f[k], 0.0) * std::max(g[k], 0.0)) * c[k];
  bc /= std::sqrt(pf * pg);
  return std::sqrt(std::max(0.0, 1.0 - bc));
}

double hellinger_distance(const HemisphereMap& map, const std::vector<double>& f, const std::vector<double>& g) {
  std::vector<double> c(map.size());
  for (int px = 0; px < map.size(); ++px) c[px] = map.pixel_cos_integral(px);
  return hellinger_distance(c, f, g);
}

}  // namespace microsim
