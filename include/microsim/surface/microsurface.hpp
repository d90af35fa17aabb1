// The explicit microgeometry and its macrosurface [GeomBSDF24, "microsurface/macrosurface"].
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

// The macrosurface: normal n, area A, and how rays cover it (docs/theory/microsurface.md).
struct Macrosurface {
  Vec3 normal{0, 0, 1};
  double area = 1.0;      // A
  bool periodic = true;   // periodic tile: rays leaving through a side re-enter opposite
  double size_x = 1.0;    // tile (or window) extent along x, centered on the origin
  double size_y = 1.0;    // tile (or window) extent along y
  // A heightfield measured in a region only (a measured patch inset by its guard band, or a
  // periodic tile restricted to the same cells for comparison): estimators take sample points
  // and ray footprints in x in [region_x0, region_x1], y in [region_y0, region_y1]; `area` is
  // the region's. The geometry around it is traced too (wrapped only when `periodic`).
  bool region = false;
  double region_x0 = 0, region_x1 = 0, region_y0 = 0, region_y1 = 0;
  double guard_x = 0, guard_y = 0;  // inset of the region from the patch border (surface units)
  // A finite object: rays cover a window around its projection and may miss it.
  bool finite_object() const { return !periodic && !region; }
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

  // The facets the estimators sum over and sample (a region's facets when one is set).
  std::size_t num_facets() const;
  // Any traced facet: k < num_facets() as above; with a region, the other traced cells follow
  // as num_facets() + 2 (j nx + i) + half (never summed over, only named by tracer hits).
  Triangle facet(std::size_t k) const;
  // Index of facet `half` of traced cell (i, j) (0 <= i < traced_cells_x(), likewise j).
  std::size_t facet_index(long i, long j, int half) const;
  // Cells the tracer builds: nx x ny for a periodic tile, (nx-1) x (ny-1) for a window.
  int traced_cells_x() const { return macro_.periodic ? nx_ : nx_ - 1; }
  int traced_cells_y() const { return macro_.periodic ? ny_ : ny_ - 1; }

  // Heightfields: restrict the estimators to the cells [i0, i1) x [j0, j1); `periodic` false
  // makes the grid a non-periodic window (no wrap-around; cells between vertices only). The
  // macro area becomes the region's area. UsageError when the region is empty or outside.
  void set_sample_region(int i0, int i1, int j0, int j1, bool periodic);
  bool has_region() const { return macro_.region; }
  int region_i0() const { return ri0_; }
  int region_i1() const { return ri1_; }
  int region_j0() const { return rj0_; }
  int region_j1() const { return rj1_; }

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
  int ri0_ = 0, ri1_ = 0, rj0_ = 0, rj1_ = 0;  // sample region (cells), when macro_.region
  std::vector<Eigen::Vector3f> vertices_;
  std::vector<std::array<std::uint32_t, 3>> triangles_;
};

// True for a heightfield imported as a non-periodic window (surface/heightmap_import.hpp): its
// description has "boundary": "window". Here, with the surface, so that metrology can tell a
// window without depending on the importer.
bool is_window(const Microsurface& s);

// Area-weighted facet statistics that every check and model needs ([GeomBSDF24, eq. 1b/1c], docs/theory/ndf.md).
struct FacetSums {
  Vec3 sum_area_normal = Vec3::Zero();  // sum_f A_f m_f        ([GeomBSDF24, eq. 1b]: equals n A)
  double sum_area_cos = 0.0;            // sum_f A_f (n.m_f)    ([GeomBSDF24, eq. 1c]: equals A)
  double total_area = 0.0;              // sum_f A_f
  double slope_var_x = 0.0;             // projected-area-weighted variance of slopes -m_x/m_z
  double slope_var_y = 0.0;
  double slope_cov_xy = 0.0;
  double slope_mean_x = 0.0, slope_mean_y = 0.0;
};
FacetSums facet_sums(const Microsurface& s);

// sum_f A_f max(0, v.m_f): front-facing projected area (the G1 denominator, docs/theory/masking.md).
double front_projected_area(const Microsurface& s, const Vec3& v);
// Smith Lambda from the surface's own facets ([GeomBSDF24, eq. 3Xd], [Heitz14, App. A]).
double lambda_from_facets(const Microsurface& s, const Vec3& v);

}  // namespace microsim
