#include "microsim/surface/transform.hpp"

#include "microsim/surface/surface_io.hpp"

namespace microsim {

Microsurface stretch_surface(const Microsurface& s, double sx, double sy) {
  if (!(sx > 0 && sy > 0 && std::isfinite(sx) && std::isfinite(sy)))
    throw UsageError("stretch factors must be finite and > 0");
  Microsurface out;
  if (s.kind() == Microsurface::Kind::Heightfield) {
    out = Microsurface::heightfield(s.nx(), s.ny(), s.macro().size_x * sx, s.macro().size_y * sy,
                                    s.heights());
  } else {
    std::vector<Eigen::Vector3f> verts = s.vertices();
    for (auto& v : verts) {
      v.x() = static_cast<float>(sx * v.x());
      v.y() = static_cast<float>(sy * v.y());
    }
    Macrosurface m = s.macro();
    m.size_x *= sx;
    m.size_y *= sy;
    m.area *= sx * sy;
    out = Microsurface::mesh(std::move(verts), s.triangles(), m);
  }
  out.description = s.description;
  out.description["transform_stretch"] = {sx, sy};
  if (s.nominal) {
    models::Ndf n = *s.nominal;
    n.alpha_x /= sx;
    n.alpha_y /= sy;
    out.nominal = n;
    if (out.description.contains("alpha_x")) out.description["alpha_x"] = n.alpha_x;
    if (out.description.contains("alpha_y")) out.description["alpha_y"] = n.alpha_y;
  }
  return out;
}

ShearedPatch shear_surface(const Microsurface& s, double kx, double ky, int copies) {
  if (!s.macro().periodic) throw UsageError("shear_surface: the surface must be a periodic tile");
  if (copies < 0 || copies > 4) throw UsageError("shear_surface: copies must be in [0, 4]");
  const Microsurface m = heightfield_to_mesh(s);
  const double lx = s.macro().size_x, ly = s.macro().size_y;
  std::vector<Eigen::Vector3f> verts;
  std::vector<std::array<std::uint32_t, 3>> tris;
  const auto& v0 = m.vertices();
  const auto& t0 = m.triangles();
  const int side = 2 * copies + 1;
  verts.reserve(v0.size() * side * side);
  tris.reserve(t0.size() * side * side);
  // Central copy first, then the others.
  std::vector<std::pair<int, int>> order = {{0, 0}};
  for (int cy = -copies; cy <= copies; ++cy)
    for (int cx = -copies; cx <= copies; ++cx)
      if (cx != 0 || cy != 0) order.emplace_back(cx, cy);
  for (auto [cx, cy] : order) {
    const auto base = static_cast<std::uint32_t>(verts.size());
    for (const auto& v : v0) {
      const double x = v.x() + cx * lx, y = v.y() + cy * ly;
      verts.emplace_back(static_cast<float>(x), static_cast<float>(y),
                         static_cast<float>(v.z() + kx * x + ky * y));
    }
    for (const auto& t : t0) tris.push_back({base + t[0], base + t[1], base + t[2]});
  }
  ShearedPatch p;
  p.tile_area = lx * ly;
  p.mesonormal = Vec3(-kx, -ky, 1).normalized();
  Macrosurface macro;
  macro.periodic = false;
  macro.normal = p.mesonormal;
  macro.size_x = side * lx;
  macro.size_y = side * ly;
  macro.area = side * side * p.tile_area * Vec3(-kx, -ky, 1).norm();  // mesosurface area
  p.surface = Microsurface::mesh(std::move(verts), std::move(tris), macro);
  p.surface.description = s.description;
  p.surface.description["transform_shear"] = {kx, ky};
  p.surface.description["transform_shear_copies"] = copies;
  p.central_facets = t0.size();
  return p;
}

}  // namespace microsim
