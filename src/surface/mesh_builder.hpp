// Internal helper of the generators: accumulates float vertices and outward-oriented triangles.
#pragma once
#include <array>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "microsim/common.hpp"

namespace microsim::detail {

// A parameter as the generators write it into descriptions (a stream's default format).
inline std::string num(double x) {
  std::ostringstream os;
  os << x;
  return os.str();
}

class MeshBuilder {
 public:
  std::uint32_t vertex(const Vec3& p) {
    vertices.push_back(p.cast<float>());
    return static_cast<std::uint32_t>(vertices.size() - 1);
  }
  Vec3 point(std::uint32_t i) const { return vertices[i].cast<double>(); }
  // Triangle (a, b, c), reversed if needed so that its normal points along `outward`.
  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, const Vec3& outward) {
    Vec3 n = (point(b) - point(a)).cross(point(c) - point(a));
    if (n.dot(outward) < 0) std::swap(b, c);
    triangles.push_back({a, b, c});
  }
  // Planar quad a-b-c-d (in cyclic order), as two triangles facing `outward`.
  void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d, const Vec3& outward) {
    triangle(a, b, c, outward);
    triangle(a, c, d, outward);
  }
  std::vector<Eigen::Vector3f> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// Area of a polygon in the plane z = 0 from its (float-rounded) vertices, by the shoelace
// formula in double: the exact macro area of the faceted object, so that [GeomBSDF24, eq. 1b] holds to
// rounding.
inline double polygon_area_xy(const std::vector<Eigen::Vector3f>& v,
                              const std::vector<std::uint32_t>& loop) {
  double a = 0;
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const Eigen::Vector3f& p = v[loop[k]];
    const Eigen::Vector3f& q = v[loop[(k + 1) % loop.size()]];
    a += static_cast<double>(p.x()) * q.y() - static_cast<double>(q.x()) * p.y();
  }
  return 0.5 * std::abs(a);
}

}  // namespace microsim::detail
