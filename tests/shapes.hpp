// Exact structured surfaces built directly in the tests of G2 and the VNDF (to be merged with
// the structured-surface generators): a periodic square wave and a tessellated upper
// half-ellipsoid (whose normal distribution is GGX, 002).
#pragma once
#include <cmath>
#include <vector>

#include "microsim/surface/microsurface.hpp"

namespace microsim::testing {

// Square wave: ridges along y, `periods` periods of length `period` in x; each period holds a
// box top of width `top` at height `h` and a trench bottom of width period - top at z = 0,
// joined by vertical walls. The tile starts in the middle of a trench, so its borders cut
// bottoms only. Extruded along y over `size_y` in `ny` strips.
struct SquareWave {
  double period = 1.0, top = 0.5, h = 0.25;
  int periods = 4;
  double size_y = 1.0;
  int ny = 4;
  double bottom() const { return period - top; }
  double size_x() const { return periods * period; }
};

inline Microsurface square_wave_mesh(const SquareWave& w) {
  std::vector<Vec2> profile;  // (x, z) from -size_x/2 to +size_x/2
  const double x0 = -0.5 * w.size_x(), b = w.bottom();
  for (int k = 0; k < w.periods; ++k) {
    const double s = x0 + k * w.period;
    profile.emplace_back(s, 0.0);
    profile.emplace_back(s + 0.5 * b, 0.0);
    profile.emplace_back(s + 0.5 * b, w.h);
    profile.emplace_back(s + 0.5 * b + w.top, w.h);
    profile.emplace_back(s + 0.5 * b + w.top, 0.0);
  }
  profile.emplace_back(-x0, 0.0);
  std::vector<Eigen::Vector3f> verts;
  std::vector<std::array<std::uint32_t, 3>> tris;
  const std::size_t np = profile.size();
  for (int j = 0; j <= w.ny; ++j) {
    const double y = -0.5 * w.size_y + w.size_y * j / w.ny;
    for (const Vec2& p : profile)
      verts.emplace_back(static_cast<float>(p.x()), static_cast<float>(y), static_cast<float>(p.y()));
  }
  auto id = [&](std::size_t k, int j) { return static_cast<std::uint32_t>(j * np + k); };
  for (int j = 0; j < w.ny; ++j)
    for (std::size_t k = 0; k + 1 < np; ++k) {
      // A = (k, j), B = (k+1, j), C = (k+1, j+1), D = (k, j+1): (B-A) x (C-A) points out of
      // the solid (+z on tops and bottoms, -x on a rising wall, +x on a falling one).
      tris.push_back({id(k, j), id(k + 1, j), id(k + 1, j + 1)});
      tris.push_back({id(k, j), id(k + 1, j + 1), id(k, j + 1)});
    }
  Macrosurface m;
  m.periodic = true;
  m.size_x = w.size_x();
  m.size_y = w.size_y;
  m.area = m.size_x * m.size_y;
  Microsurface s = Microsurface::mesh(std::move(verts), std::move(tris), m);
  s.description = {{"kind", "square_wave"}, {"period", w.period}, {"top", w.top}, {"height", w.h}};
  return s;
}

// Exact visibility on the square wave (000 after eq. 16c), for directions o, i (z > 0); only
// their x components matter. For direction d the shift s_d = h d_x / d_z is the horizontal run
// of a ray rising over the wall height.
struct SquareWaveExact {
  double g2 = 0, g1_o = 0, g1_i = 0;
};
// Normal-n area (tops and bottoms): tops are always visible; a bottom point at x in the trench
// [a, a + b] is seen along d iff a + max(0, -s_d) <= x <= a + b - max(0, s_d).
inline SquareWaveExact square_wave_exact_n(const SquareWave& w, const Vec3& o, const Vec3& i) {
  const double so = w.h * o.x() / o.z(), si = w.h * i.x() / i.z(), b = w.bottom();
  auto seen = [&](double lo, double hi) { return std::max(0.0, b - lo - hi); };
  SquareWaveExact e;
  const double total = w.top + b;
  e.g1_o = (w.top + seen(std::max(0.0, -so), std::max(0.0, so))) / total;
  e.g1_i = (w.top + seen(std::max(0.0, -si), std::max(0.0, si))) / total;
  e.g2 = (w.top + seen(std::max({0.0, -so, -si}), std::max({0.0, so, si}))) / total;
  return e;
}
// A wall with normal (sign, 0, 0): faces d iff sign d_x > 0; a point at height z is seen along
// d iff z >= h - b d_z / |d_x| (the ray clears the opposite wall of the trench).
inline SquareWaveExact square_wave_exact_wall(const SquareWave& w, double sign, const Vec3& o,
                                              const Vec3& i) {
  auto seen = [&](const Vec3& d) {
    if (!(sign * d.x() > 0)) return 0.0;
    return std::min(w.h, w.bottom() * d.z() / std::abs(d.x())) / w.h;
  };
  SquareWaveExact e;
  e.g1_o = seen(o);
  e.g1_i = seen(i);
  e.g2 = std::min(e.g1_o, e.g1_i);  // both visible iff above the higher of the two limits
  return e;
}

// Upper half of the ellipsoid with semi-axes (1/alpha_x, 1/alpha_y, 1): its normal
// distribution is GGX(alpha_x, alpha_y) (002). Tessellated on a grid in normal space: the
// vertex with normal m(theta_k, phi_j) is the ellipsoid point with that normal,
// p = (a^2 m_x, b^2 m_y, c^2 m_z) / |(a m_x, b m_y, c m_z)|, theta_k = k 90/n_theta degrees,
// phi_j = j 360/n_phi degrees, so that facets fall inside normal bins whose edges are on the
// grid. A finite object (periodic = false) whose macro area is the projected area of the
// tessellation (000 eq. 1c; it tends to pi a b), so that eq. 1b holds to rounding.
inline Microsurface ellipsoid_mesh(double alpha_x, double alpha_y, int n_theta = 90,
                                   int n_phi = 144) {
  const double a = 1 / alpha_x, b = 1 / alpha_y, c = 1;
  auto point = [&](double th, double ph) {
    const Vec3 m(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    const double d = Vec3(a * m.x(), b * m.y(), c * m.z()).norm();
    return Eigen::Vector3f(static_cast<float>(a * a * m.x() / d), static_cast<float>(b * b * m.y() / d),
                           static_cast<float>(c * c * m.z() / d));
  };
  std::vector<Eigen::Vector3f> verts;
  std::vector<std::array<std::uint32_t, 3>> tris;
  verts.push_back(point(0, 0));  // pole
  for (int k = 1; k <= n_theta; ++k)
    for (int j = 0; j < n_phi; ++j)
      verts.push_back(point(0.5 * kPi * k / n_theta, 2 * kPi * j / n_phi));
  auto id = [&](int k, int j) {  // k >= 1
    return static_cast<std::uint32_t>(1 + (k - 1) * n_phi + ((j % n_phi) + n_phi) % n_phi);
  };
  for (int j = 0; j < n_phi; ++j) tris.push_back({0, id(1, j), id(1, j + 1)});
  for (int k = 1; k < n_theta; ++k)
    for (int j = 0; j < n_phi; ++j) {
      tris.push_back({id(k, j), id(k + 1, j), id(k + 1, j + 1)});
      tris.push_back({id(k, j), id(k + 1, j + 1), id(k, j + 1)});
    }
  Macrosurface m;
  m.periodic = false;
  m.size_x = 2 * a;
  m.size_y = 2 * b;
  m.area = 0;
  for (const auto& t : tris)
    m.area += 0.5 * (verts[t[1]] - verts[t[0]]).cast<double>().cross((verts[t[2]] - verts[t[0]]).cast<double>()).z();
  Microsurface s = Microsurface::mesh(std::move(verts), std::move(tris), m);
  s.description = {{"kind", "ellipsoid"}, {"nominal_ndf", "ggx"}, {"alpha_x", alpha_x},
                   {"alpha_y", alpha_y}};
  s.nominal = models::Ndf::ggx(alpha_x, alpha_y);
  return s;
}

}  // namespace microsim::testing
