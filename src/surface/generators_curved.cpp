// Generators with curved or sampled geometry: the GGX ellipsoid and the V-cavity ensemble.
#include <sstream>

#include "mesh_builder.hpp"
#include "microsim/surface/generators.hpp"

namespace microsim {

namespace {
using detail::num;
void require_alpha(double a, const char* option) {
  if (!(a >= 1e-3 && a <= 1e3))
    throw ParameterError(std::string(option) + " must be in [0.001, 1000] (got " + num(a) + ")");
}
}  // namespace

Microsurface generate_ellipsoid(const EllipsoidParams& p) {
  require_alpha(p.alpha_x, "{alpha_x}");
  require_alpha(p.alpha_y, "{alpha_y}");
  if (p.rings < 2 || p.rings > 4096)
    throw ParameterError("{rings} must be in [2, 4096] (got " + std::to_string(p.rings) + ")");
  if (p.segments < 8 || p.segments > 16384)
    throw ParameterError("{segments} must be in [8, 16384] (got " + std::to_string(p.segments) + ")");
  if (2.0 * p.rings * p.segments > 5e7)
    throw ParameterError("{rings} x {segments} must be at most 2.5e7 (about 5e7 triangles)");
  // p = A^-1 u for u on a latitude-longitude mesh of the unit upper hemisphere, A = diag(ax, ay,
  // 1): p lies on (ax x)^2 + (ay y)^2 + z^2 = 1 ([TSBlog24], C = 1); facet normals map to A n_u.
  const int R = p.rings, S = p.segments;
  detail::MeshBuilder mb;
  auto at = [&](int i, int j) {
    const double th = 0.5 * kPi * i / R, ph = 2 * kPi * j / S;
    const double z = i == R ? 0.0 : std::cos(th);  // the rim exactly on the base plane
    return Vec3(std::sin(th) * std::cos(ph) / p.alpha_x, std::sin(th) * std::sin(ph) / p.alpha_y, z);
  };
  // Outward direction for orientation: the gradient A^T A p of the ellipsoid.
  auto grad = [&](const Vec3& q) {
    return Vec3(p.alpha_x * p.alpha_x * q.x(), p.alpha_y * p.alpha_y * q.y(), q.z());
  };
  const std::uint32_t pole = mb.vertex(at(0, 0));
  std::vector<std::uint32_t> ring((static_cast<std::size_t>(R)) * S);
  for (int i = 1; i <= R; ++i)
    for (int j = 0; j < S; ++j) ring[static_cast<std::size_t>(i - 1) * S + j] = mb.vertex(at(i, j));
  auto id = [&](int i, int j) { return ring[static_cast<std::size_t>(i - 1) * S + (j % S)]; };
  for (int j = 0; j < S; ++j) mb.triangle(pole, id(1, j), id(1, j + 1), Vec3::UnitZ());
  for (int i = 1; i < R; ++i)
    for (int j = 0; j < S; ++j) {
      Vec3 c = 0.25 * (mb.point(id(i, j)) + mb.point(id(i, j + 1)) + mb.point(id(i + 1, j)) +
                       mb.point(id(i + 1, j + 1)));
      mb.quad(id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1), grad(c));
    }
  std::vector<std::uint32_t> rim(S);
  for (int j = 0; j < S; ++j) rim[j] = id(R, j);
  Macrosurface m;
  m.periodic = false;
  m.area = detail::polygon_area_xy(mb.vertices, rim);  // -> pi / (ax ay) as S grows
  m.size_x = 2.0 / p.alpha_x;
  m.size_y = 2.0 / p.alpha_y;
  Microsurface s = Microsurface::mesh(std::move(mb.vertices), std::move(mb.triangles), m);
  s.nominal = models::Ndf::ggx(p.alpha_x, p.alpha_y);
  s.description = {{"kind", "ellipsoid"},        {"alpha_x", p.alpha_x},
                   {"alpha_y", p.alpha_y},       {"rings", R},
                   {"segments", S},              {"nominal_ndf", "ggx"},
                   {"semi_axes", {1.0 / p.alpha_x, 1.0 / p.alpha_y, 1.0}}};
  return s;
}

bool is_vcavity(const Microsurface& s) {
  return s.description.is_object() && s.description.value("kind", std::string()) == "vcavity";
}

Vec3 vcavity_groove_normal(const Microsurface& s, std::size_t k) { return s.facet(4 * k).normal(); }

Microsurface generate_vcavity(const VCavityParams& p) {
  if (p.ndf != "beckmann" && p.ndf != "ggx")
    throw ParameterError("{ndf} must be beckmann or ggx (got '" + literal_text(p.ndf) + "')");
  require_alpha(p.alpha_x, "{alpha_x}");
  require_alpha(p.alpha_y, "{alpha_y}");
  if (p.grooves < 1 || p.grooves > 1000000)
    throw ParameterError("{grooves} must be in [1, 1000000] (got " + std::to_string(p.grooves) + ")");
  const int K = p.grooves;
  const int grid = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(K))));
  const double spacing = 2.0;  // strips of 1 x 1 (diagonal 1.42) never touch
  detail::MeshBuilder mb;
  double area = 0;  // the strips' footprints, from their float vertices (eq. 1b to rounding)
  for (int k = 0; k < K; ++k) {
    // Slope drawn from P22 (density (n.m) D(m) over normals: every groove covers the same
    // macro area, [Heitz14, Sec. 6.1]); the radius is stratified over the ensemble.
    CounterRng rng(p.seed, 0x7CA7, static_cast<std::uint64_t>(k));
    const double u1 = (k + rng.uniform()) / K, u2 = rng.uniform();
    const double r = p.ndf == "beckmann" ? std::sqrt(-std::log1p(-u1))  // P(r) = 2 r e^{-r^2}
                                         : std::sqrt(u1 / (1 - u1));    // P(r) = 2 r / (1+r^2)^2
    const double sx = p.alpha_x * r * std::cos(2 * kPi * u2), sy = p.alpha_y * r * std::sin(2 * kPi * u2);
    const Vec3 m = Vec3(-sx, -sy, 1).normalized();
    // Groove frame: d = horizontal direction of m, t = ridge direction. Valley at xi = 0,
    // z = tan(theta_m) |xi| for xi in [-1/2, 1/2]: the half xi < 0 has normal m, the other m'.
    const double mh = std::hypot(m.x(), m.y());
    const Vec3 d = mh > 0 ? Vec3(m.x() / mh, m.y() / mh, 0) : Vec3::UnitX();
    const Vec3 t = Vec3::UnitZ().cross(d);
    const double top = 0.5 * mh / m.z();  // tan(theta_m) / 2
    const Vec3 c(spacing * (k % grid - 0.5 * (grid - 1)), spacing * (k / grid - 0.5 * (grid - 1)), 0);
    std::uint32_t v[6];
    const double xi[3] = {-0.5, 0.0, 0.5}, zz[3] = {top, 0.0, top};
    for (int a = 0; a < 3; ++a) {
      v[2 * a] = mb.vertex(c + xi[a] * d - 0.5 * t + zz[a] * Vec3::UnitZ());
      v[2 * a + 1] = mb.vertex(c + xi[a] * d + 0.5 * t + zz[a] * Vec3::UnitZ());
    }
    const Vec3 m2(-m.x(), -m.y(), m.z());
    mb.quad(v[0], v[2], v[3], v[1], m);   // facets 4k, 4k+1: normal m
    mb.quad(v[2], v[4], v[5], v[3], m2);  // facets 4k+2, 4k+3: normal m'
    area += detail::polygon_area_xy(mb.vertices, {v[0], v[2], v[4], v[5], v[3], v[1]});
  }
  Macrosurface macro;
  macro.periodic = false;
  macro.area = area;  // K grooves of unit period and unit length: K up to float rounding
  macro.size_x = macro.size_y = spacing * grid;
  Microsurface s = Microsurface::mesh(std::move(mb.vertices), std::move(mb.triangles), macro);
  s.nominal = p.ndf == "beckmann" ? models::Ndf::beckmann(p.alpha_x, p.alpha_y)
                                  : models::Ndf::ggx(p.alpha_x, p.alpha_y);
  s.description = {{"kind", "vcavity"},   {"ndf", p.ndf},   {"alpha_x", p.alpha_x},
                   {"alpha_y", p.alpha_y}, {"grooves", K},  {"seed", p.seed},
                   {"nominal_ndf", p.ndf},
                   {"layout", "groove k = facets 4k..4k+3 (normal m: 4k, 4k+1; m': 4k+2, 4k+3), "
                              "one unit period x unit length of an infinite V-groove; measure "
                              "g1 traces each groove on its own"}};
  return s;
}

}  // namespace microsim
