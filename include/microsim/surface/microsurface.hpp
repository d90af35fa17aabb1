// The explicit microgeometry and its macrosurface (000 "microsurface/macrosurface").
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "microsim/common.hpp"
#include "microsim/models/ndf.hpp"

namespace microsim {

// The macrosurface: normal n, area A, and how rays cover it (DESIGN.md "Macrosurface").
struct Macrosurface {
  Vec3 normal{0, 0, 1};
  double area = 1.0;      // A
  bool periodic = true;   // periodic tile: rays leaving through a side re-enter opposite
  double size_x = 1.0;    // tile (or window) extent along x, centered on the origin
  double size_y = 1.0;    // tile (or window) extent along y
};

struct Triangle {
  Vec3 p0, p1, p2;
  Vec3 cross() const { return (p1 - p0).cross(p2 - p0); }  // length = 2 * area
  Vec3 normal() const { return cross().normalized(); }
  double area() const { return 0.5 * cross().norm(); }
  Vec3 point(double b1, double b2) const { return p0 + b1 * (p1 - p0) + b2 * (p2 - p0); }
};

// A microsurface is either a periodic heightfield on a regular grid (traced as an Embree grid)
// or a triangle mesh (traced as Embree triangles).
class Microsurface {
 public:
  enum class Kind { Heightfield, Mesh };

  static Microsurface heightfield(int nx, int ny, double size_x, double size_y,
                                  std::vector<float> heights);
  static Microsurface mesh(std::vector<Eigen::Vector3f> vertices,
                           std::vector<std::array<std::uint32_t, 3>> triangles, Macrosurface macro);

  Kind kind() const { return kind_; }
  const Macrosurface& macro() const { return macro_; }

  // Generator name and parameters, carried into every output so a file explains itself.
  Json description = Json::object();
  // The generator's nominal NDF, when it has one (e.g. gaussian: Beckmann with the requested alpha).
  std::optional<models::Ndf> nominal;

  std::size_t num_facets() const;
  Triangle facet(std::size_t k) const;

  // Heightfield access (periodic indices).
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double dx() const { return macro_.size_x / nx_; }
  double dy() const { return macro_.size_y / ny_; }
  float height(long i, long j) const;
  const std::vector<float>& heights() const { return heights_; }
  // Grid vertex position (i, j may run past the tile: the periodic copy is returned).
  Vec3 grid_point(long i, long j) const;

  // Mesh access.
  const std::vector<Eigen::Vector3f>& vertices() const { return vertices_; }
  const std::vector<std::array<std::uint32_t, 3>>& triangles() const { return triangles_; }

  // Axis-aligned bounds of the geometry inside the tile/window.
  Eigen::AlignedBox3d bounds() const;

 private:
  Kind kind_ = Kind::Heightfield;
  Macrosurface macro_;
  int nx_ = 0, ny_ = 0;
  std::vector<float> heights_;  // nx * ny, row-major in j
  std::vector<Eigen::Vector3f> vertices_;
  std::vector<std::array<std::uint32_t, 3>> triangles_;
};

// Area-weighted facet statistics that every check and model needs (000 eq. 1b/1c, DESIGN.md).
struct FacetSums {
  Vec3 sum_area_normal = Vec3::Zero();  // sum_f A_f m_f        (000 eq. 1b: equals n A)
  double sum_area_cos = 0.0;            // sum_f A_f (n.m_f)    (000 eq. 1c: equals A)
  double total_area = 0.0;              // sum_f A_f
  double slope_var_x = 0.0;             // projected-area-weighted variance of slopes -m_x/m_z
  double slope_var_y = 0.0;
  double slope_cov_xy = 0.0;
  double slope_mean_x = 0.0, slope_mean_y = 0.0;
};
FacetSums facet_sums(const Microsurface& s);

// sum_f A_f max(0, v.m_f): front-facing projected area (DESIGN.md G1 denominator).
double front_projected_area(const Microsurface& s, const Vec3& v);
// Smith Lambda from the surface's own facets (DESIGN.md, 000 eq. 3Xd, 001 App. A).
double lambda_from_facets(const Microsurface& s, const Vec3& v);

}  // namespace microsim
