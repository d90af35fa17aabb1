// Structured generators: flat, box, tiled boxes, parallelepipeds, square waves, V-grooves.
#include "microsim/surface/generators.hpp"

#include <sstream>

#include "mesh_builder.hpp"

namespace microsim {

namespace {
using detail::num;

// `option`: the parameter as a ParameterError names it ("{width}").
void require_positive(double x, const char* option, double max = 1e6) {
  if (!(x > 0) || !std::isfinite(x) || x > max)
    throw ParameterError(std::string(option) + " must be in (0, " + num(max) + "] (got " + num(x) + ")");
}

void require_tiles(int n) {
  if (n < 1 || n > 256)
    throw ParameterError("{tiles} must be in [1, 256] (got " + std::to_string(n) + ")");
}

// Box [x0, x1] x [y0, y1] x [0, h]: top and four walls with outward normals, no bottom.
// Returns the base loop (counter-clockwise seen from above).
std::vector<std::uint32_t> add_box(detail::MeshBuilder& mb, double x0, double x1, double y0,
                                   double y1, double h) {
  std::uint32_t b00 = mb.vertex({x0, y0, 0}), b10 = mb.vertex({x1, y0, 0}),
                b11 = mb.vertex({x1, y1, 0}), b01 = mb.vertex({x0, y1, 0});
  std::uint32_t t00 = mb.vertex({x0, y0, h}), t10 = mb.vertex({x1, y0, h}),
                t11 = mb.vertex({x1, y1, h}), t01 = mb.vertex({x0, y1, h});
  mb.quad(t00, t10, t11, t01, Vec3::UnitZ());
  mb.quad(b10, b11, t11, t10, Vec3::UnitX());
  mb.quad(b00, t00, t01, b01, -Vec3::UnitX());
  mb.quad(b01, t01, t11, b11, Vec3::UnitY());
  mb.quad(b00, b10, t10, t00, -Vec3::UnitY());
  return {b00, b10, b11, b01};
}

// N x N boxes of size W/N x D/N x H/N covering [-W/2, W/2] x [-D/2, D/2]; each box a separate
// component. Returns the base loops.
std::vector<std::vector<std::uint32_t>> add_tiled_boxes(detail::MeshBuilder& mb, double w,
                                                        double d, double h, int n) {
  std::vector<std::vector<std::uint32_t>> bases;
  // Box edges at x0 + k w/n: neighbours share exactly the same float coordinate.
  auto xs = [&](int k) { return -0.5 * w + w * k / n; };
  auto ys = [&](int k) { return -0.5 * d + d * k / n; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) bases.push_back(add_box(mb, xs(i), xs(i + 1), ys(j), ys(j + 1), h / n));
  return bases;
}

Macrosurface finite_macro(const detail::MeshBuilder& mb,
                          const std::vector<std::vector<std::uint32_t>>& bases) {
  Macrosurface m;
  m.periodic = false;
  m.area = 0;
  Eigen::AlignedBox3f box;
  for (const auto& b : bases) {
    m.area += detail::polygon_area_xy(mb.vertices, b);
    for (auto id : b) box.extend(mb.vertices[id]);
  }
  // The window of a finite object: its base's extent (symmetric about the origin).
  m.size_x = 2 * std::max(std::abs(box.min().x()), std::abs(box.max().x()));
  m.size_y = 2 * std::max(std::abs(box.min().y()), std::abs(box.max().y()));
  return m;
}

void validate_box(const BoxParams& p) {
  require_positive(p.width, "{width}");
  require_positive(p.depth, "{depth}");
  require_positive(p.height, "{height}");
  require_tiles(p.tiles);
}

}  // namespace

Microsurface generate_flat(const FlatParams& p) {
  if (p.resolution < 1 || p.resolution > 4096)
    throw ParameterError("{resolution} must be in [1, 4096] for flat (got " +
                         std::to_string(p.resolution) + ")");
  if (!(p.size > 0)) throw ParameterError("{size} must be > 0");
  Microsurface s = Microsurface::heightfield(
      p.resolution, p.resolution, p.size, p.size,
      std::vector<float>(static_cast<std::size_t>(p.resolution) * p.resolution, 0.0f));
  s.description = {{"kind", "flat"}, {"resolution", p.resolution}, {"size", p.size}};
  return s;
}

Microsurface generate_box(const BoxParams& p_in) {
  BoxParams p = p_in;
  p.tiles = 1;
  validate_box(p);
  detail::MeshBuilder mb;
  auto bases = add_tiled_boxes(mb, p.width, p.depth, p.height, 1);
  Macrosurface m = finite_macro(mb, bases);
  Microsurface s = Microsurface::mesh(std::move(mb.vertices), std::move(mb.triangles), m);
  s.description = {{"kind", "box"}, {"width", p.width}, {"depth", p.depth}, {"height", p.height}};
  return s;
}

Microsurface generate_tiled_boxes(const BoxParams& p) {
  validate_box(p);
  detail::MeshBuilder mb;
  auto bases = add_tiled_boxes(mb, p.width, p.depth, p.height, p.tiles);
  Macrosurface m = finite_macro(mb, bases);
  Microsurface s = Microsurface::mesh(std::move(mb.vertices), std::move(mb.triangles), m);
  s.description = {{"kind", "tiled-boxes"}, {"tiles", p.tiles},    {"width", p.width},
                   {"depth", p.depth},      {"height", p.height}, {"box_height", p.height / p.tiles}};
  return s;
}

Microsurface generate_parallelepiped(const ParallelepipedParams& p) {
  validate_box({p.width, p.depth, p.height, p.tiles});
  const double* L = p.matrix;
  for (int k = 0; k < 9; ++k)
    if (!std::isfinite(L[k]) || std::abs(L[k]) > 1e6)
      throw ParameterError("{matrix} entries must be finite numbers of magnitude <= 1e6");
  if (L[6] != 0 || L[7] != 0 || !(L[8] > 0))
    throw ParameterError("{matrix} third row must be (0, 0, k) with k > 0 (the base must stay the "
                         "macrosurface z = 0); got (" + num(L[6]) + ", " + num(L[7]) + ", " + num(L[8]) + ")");
  const double det2 = L[0] * L[4] - L[1] * L[3];
  if (!(std::abs(det2) > 1e-9 * (std::abs(L[0] * L[4]) + std::abs(L[1] * L[3]) + 1e-300)))
    throw ParameterError("{matrix} is singular in x, y (l11 l22 - l12 l21 = 0): the base would be flat");
  detail::MeshBuilder box;
  auto bases = add_tiled_boxes(box, p.width, p.depth, p.height, p.tiles);
  // Map the float vertices (so that coincident walls of neighbours stay coincident).
  Eigen::Matrix3d M;
  M << L[0], L[1], L[2], L[3], L[4], L[5], L[6], L[7], L[8];
  for (auto& v : box.vertices) v = (M * v.cast<double>()).cast<float>();
  if (M.determinant() < 0)
    for (auto& t : box.triangles) std::swap(t[1], t[2]);  // a mirror map flips orientation
  Macrosurface m = finite_macro(box, bases);
  Microsurface s = Microsurface::mesh(std::move(box.vertices), std::move(box.triangles), m);
  s.description = {{"kind", "parallelepiped"},
                   {"width", p.width},
                   {"depth", p.depth},
                   {"height", p.height},
                   {"tiles", p.tiles},
                   {"matrix", {L[0], L[1], L[2], L[3], L[4], L[5], L[6], L[7], L[8]}}};
  return s;
}

Microsurface generate_square_wave(const SquareWaveParams& p) {
  require_positive(p.period, "{period}");
  require_positive(p.height, "{height}");
  if (!(p.duty > 0 && p.duty < 1))
    throw ParameterError("{duty} must be in (0, 1) (got " + num(p.duty) + ")");
  const double P = p.period, a = 0.5 * p.duty * P, h = p.height, e = 0.5 * P;
  detail::MeshBuilder mb;
  if (!p.two_d) {
    // Profile in x (z = 0 | wall | z = H | wall | z = 0), extruded along y over the tile.
    const double xs[6] = {-e, -a, -a, a, a, e};
    const double zs[6] = {0, 0, h, h, 0, 0};
    std::uint32_t lo[6], hi[6];
    for (int k = 0; k < 6; ++k) {
      lo[k] = mb.vertex({xs[k], -e, zs[k]});
      hi[k] = mb.vertex({xs[k], e, zs[k]});
    }
    const Vec3 out[5] = {Vec3::UnitZ(), -Vec3::UnitX(), Vec3::UnitZ(), Vec3::UnitX(), Vec3::UnitZ()};
    for (int k = 0; k < 5; ++k) mb.quad(lo[k], lo[k + 1], hi[k + 1], hi[k], out[k]);
  } else {
    // Raised block [-a, a]^2 x [0, H] on the floor of the tile [-e, e]^2.
    std::uint32_t o[4] = {mb.vertex({-e, -e, 0}), mb.vertex({e, -e, 0}), mb.vertex({e, e, 0}),
                          mb.vertex({-e, e, 0})};
    std::uint32_t b[4] = {mb.vertex({-a, -a, 0}), mb.vertex({a, -a, 0}), mb.vertex({a, a, 0}),
                          mb.vertex({-a, a, 0})};
    std::uint32_t t[4] = {mb.vertex({-a, -a, h}), mb.vertex({a, -a, h}), mb.vertex({a, a, h}),
                          mb.vertex({-a, a, h})};
    const Vec3 wall[4] = {-Vec3::UnitY(), Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitX()};
    mb.quad(t[0], t[1], t[2], t[3], Vec3::UnitZ());
    for (int k = 0; k < 4; ++k) {
      int k1 = (k + 1) % 4;
      mb.quad(b[k], b[k1], t[k1], t[k], wall[k]);
      mb.quad(o[k], o[k1], b[k1], b[k], Vec3::UnitZ());  // floor trapezoid
    }
  }
  Macrosurface m;
  m.periodic = true;
  m.size_x = m.size_y = P;
  m.area = P * P;
  Microsurface s = Microsurface::mesh(std::move(mb.vertices), std::move(mb.triangles), m);
  s.description = {{"kind", "square-wave"}, {"period", P}, {"duty", p.duty},
                   {"height", h},           {"two_d", p.two_d}};
  return s;
}

Microsurface generate_vgroove(const VGrooveParams& p) {
  if (!(p.facet_angle_deg > 0 && p.facet_angle_deg < 90))
    throw ParameterError("{facet_angle} must be in (0, 90) degrees (got " + num(p.facet_angle_deg) + ")");
  require_positive(p.period, "{period}");
  const double P = p.period, top = 0.5 * P * std::tan(rad(p.facet_angle_deg));
  Microsurface s;
  if (!p.two_d) {
    // One period per tile: vertices at x = -P/2 (valley), 0 (ridge); 2 x 2 cells, every
    // cell planar, so both triangles of a cell have the exact facet normal.
    std::vector<float> h = {0.0f, static_cast<float>(top), 0.0f, static_cast<float>(top)};
    s = Microsurface::heightfield(2, 2, P, P, std::move(h));
  } else {
    // Square pyramid: apex above the center, base = the tile.
    const double e = 0.5 * P;
    detail::MeshBuilder mb;
    std::uint32_t apex = mb.vertex({0, 0, top});
    std::uint32_t c[4] = {mb.vertex({-e, -e, 0}), mb.vertex({e, -e, 0}), mb.vertex({e, e, 0}),
                          mb.vertex({-e, e, 0})};
    const Vec3 out[4] = {-Vec3::UnitY(), Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitX()};
    for (int k = 0; k < 4; ++k) mb.triangle(c[k], c[(k + 1) % 4], apex, out[k] + Vec3::UnitZ());
    Macrosurface m;
    m.periodic = true;
    m.size_x = m.size_y = P;
    m.area = P * P;
    s = Microsurface::mesh(std::move(mb.vertices), std::move(mb.triangles), m);
  }
  s.description = {{"kind", "vgroove"},
                   {"facet_angle_deg", p.facet_angle_deg},
                   {"period", P},
                   {"two_d", p.two_d}};
  return s;
}

}  // namespace microsim
