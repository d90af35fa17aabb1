#include "microsim/surface/rounding_bound.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <tuple>
#include <utility>
#include <vector>

namespace microsim {

namespace {

using Key = std::uint64_t;
Key key(std::uint32_t a, std::uint32_t b) { return (static_cast<Key>(a) << 32) | b; }

// Largest possible rounding of one stored coordinate: half its float ulp, plus the double
// rounding of the value that was rounded (a few eps of it).
double coordinate_rounding(float x) {
  const float ax = std::abs(x);
  if (ax == 0.0f) return 0.0;
  const double ulp = static_cast<double>(std::nextafter(ax, std::numeric_limits<float>::infinity())) - ax;
  return 0.5 * ulp + 4.0 * std::numeric_limits<double>::epsilon() * ax;
}

using HalfEdge = std::pair<std::uint32_t, std::uint32_t>;

// The boundary half-edges of a mesh, each as often as it is unmatched: half-edges sorted, an
// edge's boundary multiplicity is its count minus its reverse's.
std::vector<HalfEdge> boundary_half_edges(const std::vector<std::array<std::uint32_t, 3>>& T) {
  std::vector<Key> half;
  half.reserve(3 * T.size());
  for (const auto& t : T)
    for (int e = 0; e < 3; ++e) half.push_back(key(t[e], t[(e + 1) % 3]));
  std::sort(half.begin(), half.end());
  std::vector<HalfEdge> boundary;
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j] == half[i]) ++j;
    const std::uint32_t a = static_cast<std::uint32_t>(half[i] >> 32), b = static_cast<std::uint32_t>(half[i]);
    const auto rev = std::equal_range(half.begin(), half.end(), key(b, a));
    const std::size_t n = j - i, m = static_cast<std::size_t>(rev.second - rev.first);
    for (std::size_t c = m; c < n; ++c) boundary.emplace_back(a, b);
    i = j;
  }
  return boundary;
}

// A periodic tile: a boundary half-edge a->b and one b'->a' with a' = a + L, b' = b + L
// exactly (L a tile translation) are the two sides of one seam; matched pairs close exactly
// (their sum telescopes to the tile's lattice vectors). Clears `open` of the matched ones and
// returns how many there are.
std::size_t match_seams(const Microsurface& s, const std::vector<HalfEdge>& boundary, std::vector<char>& open) {
  const auto& V = s.vertices();
  using Pos = std::tuple<float, float, float>;
  auto pos = [&](std::uint32_t v) { return Pos(V[v].x(), V[v].y(), V[v].z()); };
  std::multimap<Pos, std::size_t> by_start;
  for (std::size_t e = 0; e < boundary.size(); ++e) by_start.emplace(pos(boundary[e].first), e);
  const double Lx = s.macro().size_x, Ly = s.macro().size_y;
  std::size_t matched = 0;
  for (std::size_t e = 0; e < boundary.size(); ++e) {
    if (!open[e]) continue;
    const Eigen::Vector3d a = V[boundary[e].first].cast<double>(), b = V[boundary[e].second].cast<double>();
    bool found = false;
    for (int i = -1; i <= 1 && !found; ++i)
      for (int j = -1; j <= 1 && !found; ++j) {
        if (i == 0 && j == 0) continue;
        const Eigen::Vector3d L(i * Lx, j * Ly, 0.0);
        const Eigen::Vector3d b2 = b + L, a2 = a + L;
        // Only a bit-exact translate counts (the float must equal the shifted double).
        const Pos start(static_cast<float>(b2.x()), static_cast<float>(b2.y()), static_cast<float>(b2.z()));
        if (Eigen::Vector3d(std::get<0>(start), std::get<1>(start), std::get<2>(start)) != b2) continue;
        auto range = by_start.equal_range(start);
        for (auto it = range.first; it != range.second; ++it) {
          const std::size_t p = it->second;
          if (!open[p] || p == e || V[boundary[p].second].cast<double>() != a2) continue;
          open[e] = open[p] = 0;
          matched += 2;
          found = true;
          break;
        }
      }
  }
  return matched;
}

// |d x t| <= |d| x |t| component by component (both in absolute values).
Vec3 abs_cross(const Vec3& d, const Vec3& t) {
  const Vec3 ad = d.cwiseAbs(), at = t.cwiseAbs();
  return Vec3(ad.y() * at.z() + ad.z() * at.y(), ad.z() * at.x() + ad.x() * at.z(), ad.x() * at.y() + ad.y() * at.x());
}

// T_v over all boundary half-edges (translation invariant: boundary half-edges form closed
// loops); the bound over the vertices of the open ones, to second order. Adds to r.
void bound_open_boundary(const Microsurface& s, const std::vector<HalfEdge>& boundary,
                         const std::vector<char>& open, FacetSumRounding& r) {
  const auto& V = s.vertices();
  std::map<std::uint32_t, Vec3> tangent;
  std::vector<char> on_open(V.size(), 0);
  for (std::size_t e = 0; e < boundary.size(); ++e) {
    const auto [a, b] = boundary[e];
    tangent.try_emplace(a, Vec3::Zero()).first->second += V[b].cast<double>();
    tangent.try_emplace(b, Vec3::Zero()).first->second -= V[a].cast<double>();
    if (open[e]) on_open[a] = on_open[b] = 1;
  }
  auto delta = [&](std::uint32_t v) {
    return Vec3(coordinate_rounding(V[v].x()), coordinate_rounding(V[v].y()), coordinate_rounding(V[v].z()));
  };
  for (const auto& [v, t] : tangent) {
    if (!on_open[v]) continue;
    ++r.open_vertices;
    r.bound += 0.5 * abs_cross(delta(v), t);
  }
  for (std::size_t e = 0; e < boundary.size(); ++e)  // second order: 1/2 delta_a x delta_b
    if (open[e]) r.bound += 0.5 * abs_cross(delta(boundary[e].first), delta(boundary[e].second));
}

}  // namespace

FacetSumRounding facet_sum_rounding_bound(const Microsurface& s) {
  FacetSumRounding r;
  if (s.kind() != Microsurface::Kind::Mesh) return r;
  const std::vector<HalfEdge> boundary = boundary_half_edges(s.triangles());
  r.boundary_half_edges = boundary.size();
  if (boundary.empty()) return r;
  std::vector<char> open(boundary.size(), 1);
  if (s.macro().periodic) r.seam_matched += match_seams(s, boundary, open);
  bound_open_boundary(s, boundary, open, r);
  return r;
}

}  // namespace microsim
