#include "microsim/measure/vcavity_multiple_map.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "microsim/models/vgroove_multiple.hpp"

namespace microsim {

namespace {

// Weighted sums over grooves of each groove's power per (slot, pixel) cell, and of its square.
struct GrooveSums {
  std::vector<double> sum, sum2;  // [slot * pixels + px]
  double weight = 0.0;
  std::size_t grooves = 0;
  explicit GrooveSums(std::size_t cells = 0) : sum(cells, 0.0), sum2(cells, 0.0) {}
  void add(const GrooveSums& o) {
    for (std::size_t c = 0; c < sum.size(); ++c) {
      sum[c] += o.sum[c];
      sum2[c] += o.sum2[c];
    }
    weight += o.weight;
    grooves += o.grooves;
  }
};

// One groove of normal m, weight w: its beams [Xie18] in the world frame, binned; beams of the
// groove that land in the same cell add before squaring (the groove is one sample).
void add_groove(GrooveSums& s, double w, const Vec3& m, const models::Material& material, const Vec3& i,
                const HemisphereMap& map, int K) {
  const models::GrooveFrame frame(m);
  std::vector<std::pair<std::size_t, double>> cells;
  for (const models::GrooveBeam& b : models::vgroove_beams(frame.facet_angle, frame.to_local(i), material)) {
    const std::size_t px = static_cast<std::size_t>(map.pixel_of(frame.to_world(b.direction)));
    const double p = b.fraction * b.reflectance;
    cells.push_back({static_cast<std::size_t>(std::min(b.bounces, K) - 1) * map.size() + px, p});
    cells.push_back({static_cast<std::size_t>(K) * map.size() + px, p});
  }
  std::sort(cells.begin(), cells.end());
  for (std::size_t a = 0; a < cells.size();) {
    double p = 0.0;
    std::size_t b = a;
    for (; b < cells.size() && cells[b].first == cells[a].first; ++b) p += cells[b].second;
    s.sum[cells[a].first] += w * p;
    s.sum2[cells[a].first] += w * p * p;
    a = b;
  }
  s.weight += w;
  ++s.grooves;
}

// Means per cell (f: divided by the pixel's int cos d omega) and, when asked, the standard error
// of an equal-weight groove average.
GrooveLobeMaps maps_of(const GrooveSums& s, const HemisphereMap& map, int K, bool with_stderr) {
  GrooveLobeMaps out;
  out.orders = K;
  out.grooves = s.grooves;
  out.f.assign(K + 1, std::vector<double>(map.size(), 0.0));
  out.albedo.assign(K + 1, 0.0);
  if (with_stderr) out.f_stderr = out.f;
  if (!(s.weight > 0.0)) return out;
  const double G = static_cast<double>(s.grooves);
  for (int k = 0; k <= K; ++k)
    for (int px = 0; px < map.size(); ++px) {
      const std::size_t c = static_cast<std::size_t>(k) * map.size() + px;
      const double mean = s.sum[c] / s.weight, ci = map.pixel_cos_integral(px);
      out.albedo[k] += mean;
      out.f[k][px] = mean / ci;
      if (with_stderr && G > 1)  // equal weights w = 1 / G: sum2 / weight is the mean square
        out.f_stderr[k][px] = std::sqrt(std::max(0.0, s.sum2[c] / s.weight - mean * mean) / (G - 1)) / ci;
    }
  return out;
}

// Row r of a stratified (jittered) vcavity_quadrature: one normal drawn uniformly in (theta, phi) in each
// cell, weighted by (n.m) D(m) sin(theta) dtheta dphi there. The beams of a regular grid of normals leave
// on a regular pattern (at normal incidence every beam leaves at its groove's azimuth), which the pixel
// borders alias by several percent per pixel; the jitter turns that into noise that averages over the
// cells of a pixel.
template <class F>
void jittered_quadrature_row(const models::Ndf& ndf, int n_theta, int n_phi, int r, F&& f) {
  const double dt = 0.5 * kPi / n_theta, dp = 2.0 * kPi / n_phi;
  const std::uint64_t key = CounterRng::key(1, 0x7CA71B0ull + static_cast<std::uint64_t>(r));
  for (int j = 0; j < n_phi; ++j) {
    CounterRng rng(CounterRng::Keyed{}, key, static_cast<std::uint64_t>(j));
    const double th = (r + rng.uniform()) * dt, ph = (j + rng.uniform()) * dp;
    const double st = std::sin(th), ct = std::cos(th);
    const Vec3 m(st * std::cos(ph), st * std::sin(ph), ct);
    const double w = ct * ndf.D(m) * st * dt * dp;
    if (w > 0) f(w, m);
  }
}

void check_orders(int K) {
  if (K < 1) throw std::invalid_argument("V-cavity maps: orders must be >= 1");
}

}  // namespace

std::vector<double> GrooveLobeMaps::f_from_order(int min_order) const {
  if (min_order < 1 || min_order > orders) throw std::invalid_argument("f_from_order: min_order outside 1 .. K");
  std::vector<double> out(f.at(0).size(), 0.0);
  for (int k = min_order - 1; k < orders; ++k)
    for (std::size_t px = 0; px < out.size(); ++px) out[px] += f[k][px];
  return out;
}

double GrooveLobeMaps::albedo_from_order(int min_order) const {
  if (min_order < 1 || min_order > orders) throw std::invalid_argument("albedo_from_order: min_order outside 1 .. K");
  double a = 0.0;
  for (int k = min_order - 1; k < orders; ++k) a += albedo[k];
  return a;
}

GrooveLobeMaps vcavity_multiple_maps(const models::Ndf& ndf, const models::Material& material, const Vec3& i,
                                     const HemisphereMap& map, int orders, int n_theta, int n_phi) {
  check_orders(orders);
  if (n_theta < 1 || n_phi < 1) throw std::invalid_argument("V-cavity maps: quadrature sizes must be >= 1");
  const Vec3 l = i.normalized();
  const std::size_t cells = static_cast<std::size_t>(orders + 1) * map.size();
  // One partial sum per polar row, added in row order (independent of the number of threads).
  std::vector<GrooveSums> rows(n_theta, GrooveSums(cells));
  tbb::parallel_for(0, n_theta, [&](int r) {
    jittered_quadrature_row(ndf, n_theta, n_phi, r, [&](double w, const Vec3& m) {
      add_groove(rows[r], w, m, material, l, map, orders);
    });
  });
  GrooveSums total(cells);
  for (const GrooveSums& r : rows) total.add(r);
  return maps_of(total, map, orders, false);
}

GrooveLobeMaps groove_ensemble_maps(const std::vector<Vec3>& normals, const models::Material& material,
                                    const Vec3& i, const HemisphereMap& map, int orders) {
  check_orders(orders);
  const Vec3 l = i.normalized();
  GrooveSums s(static_cast<std::size_t>(orders + 1) * map.size());
  const double w = normals.empty() ? 0.0 : 1.0 / static_cast<double>(normals.size());
  for (const Vec3& m : normals) add_groove(s, w, m, material, l, map, orders);
  return maps_of(s, map, orders, true);
}

}  // namespace microsim
