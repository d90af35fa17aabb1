#include "microsim/surface/microsurface.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace microsim {

Microsurface Microsurface::heightfield(int nx, int ny, double size_x, double size_y,
                                       std::vector<float> heights) {
  if (nx <= 0 || ny <= 0 || heights.size() != static_cast<std::size_t>(nx) * ny)
    throw RuntimeFailure("heightfield: size does not match its resolution");
  Microsurface s;
  s.kind_ = Kind::Heightfield;
  s.nx_ = nx;
  s.ny_ = ny;
  s.heights_ = std::move(heights);
  s.macro_.periodic = true;
  s.macro_.size_x = size_x;
  s.macro_.size_y = size_y;
  s.macro_.area = size_x * size_y;
  return s;
}

Microsurface Microsurface::mesh(std::vector<Eigen::Vector3f> vertices,
                                std::vector<std::array<std::uint32_t, 3>> triangles,
                                Macrosurface macro) {
  Microsurface s;
  s.kind_ = Kind::Mesh;
  s.vertices_ = std::move(vertices);
  s.triangles_ = std::move(triangles);
  s.macro_ = macro;
  for (const auto& t : s.triangles_)
    for (auto v : t)
      if (v >= s.vertices_.size()) throw UsageError("mesh: triangle index out of range");
  return s;
}

std::size_t Microsurface::num_facets() const {
  if (kind_ == Kind::Mesh) return triangles_.size();
  if (macro_.region) return 2 * static_cast<std::size_t>(ri1_ - ri0_) * (rj1_ - rj0_);
  return 2 * static_cast<std::size_t>(nx_) * ny_;
}

std::size_t Microsurface::facet_index(long i, long j, int half) const {
  if (macro_.region) {
    if (i >= ri0_ && i < ri1_ && j >= rj0_ && j < rj1_)
      return 2 * (static_cast<std::size_t>(j - rj0_) * (ri1_ - ri0_) + (i - ri0_)) + half;
    return num_facets() + 2 * (static_cast<std::size_t>(j) * nx_ + i) + half;
  }
  return 2 * (static_cast<std::size_t>(j) * nx_ + i) + half;
}

void Microsurface::set_sample_region(int i0, int i1, int j0, int j1, bool periodic) {
  if (kind_ != Kind::Heightfield) throw UsageError("a sample region needs a heightfield");
  macro_.periodic = periodic;
  const int cx = traced_cells_x(), cy = traced_cells_y();
  if (!(0 <= i0 && i0 < i1 && i1 <= cx && 0 <= j0 && j0 < j1 && j1 <= cy))
    throw UsageError("sample region [" + std::to_string(i0) + ", " + std::to_string(i1) + ") x [" +
                     std::to_string(j0) + ", " + std::to_string(j1) + ") is empty or outside the " +
                     std::to_string(cx) + " x " + std::to_string(cy) + " cells");
  ri0_ = i0;
  ri1_ = i1;
  rj0_ = j0;
  rj1_ = j1;
  macro_.region = true;
  macro_.region_x0 = -0.5 * macro_.size_x + i0 * dx();
  macro_.region_x1 = -0.5 * macro_.size_x + i1 * dx();
  macro_.region_y0 = -0.5 * macro_.size_y + j0 * dy();
  macro_.region_y1 = -0.5 * macro_.size_y + j1 * dy();
  macro_.guard_x = std::min(i0, cx - i1) * dx();
  macro_.guard_y = std::min(j0, cy - j1) * dy();
  macro_.area = (macro_.region_x1 - macro_.region_x0) * (macro_.region_y1 - macro_.region_y0);
}

float Microsurface::height(long i, long j) const {
  // Every corner of a facet but those on the far border lies inside the tile: two comparisons
  // then replace the two modulos per index (facet() reads three corners, the area-sampled
  // estimators and the facet sums call it per sample or per facet).
  const long ii = (i >= 0 && i < nx_) ? i : ((i % nx_) + nx_) % nx_;
  const long jj = (j >= 0 && j < ny_) ? j : ((j % ny_) + ny_) % ny_;
  return heights_[static_cast<std::size_t>(jj) * nx_ + ii];
}

Vec3 Microsurface::grid_point(long i, long j) const {
  return Vec3(-0.5 * macro_.size_x + i * dx(), -0.5 * macro_.size_y + j * dy(), height(i, j));
}

// Heightfield cell (i, j) is split along its (i+1, j)-(i, j+1) diagonal, exactly as Embree
// triangulates grid geometry (checked by tests/test_trace.cpp):
//   facet 2k   = (v00, v10, v01),   facet 2k+1 = (v10, v11, v01).
Triangle Microsurface::facet(std::size_t k) const {
  if (kind_ == Kind::Mesh) {
    const auto& t = triangles_[k];
    return {vertices_[t[0]].cast<double>(), vertices_[t[1]].cast<double>(),
            vertices_[t[2]].cast<double>()};
  }
  long i, j;
  const std::size_t nr = macro_.region ? num_facets() : 0;
  if (k < nr) {  // region facets first
    const std::size_t cell = k / 2, w = static_cast<std::size_t>(ri1_ - ri0_);
    i = ri0_ + static_cast<long>(cell % w);
    j = rj0_ + static_cast<long>(cell / w);
  } else {
    const std::size_t cell = (k - nr) / 2;
    j = static_cast<long>(cell / static_cast<std::size_t>(nx_));
    i = static_cast<long>(cell - static_cast<std::size_t>(j) * nx_);
  }
  if (k % 2 == 0) return {grid_point(i, j), grid_point(i + 1, j), grid_point(i, j + 1)};
  return {grid_point(i + 1, j), grid_point(i + 1, j + 1), grid_point(i, j + 1)};
}

Eigen::AlignedBox3d Microsurface::bounds() const {
  Eigen::AlignedBox3d box;
  if (kind_ == Kind::Heightfield) {
    float lo = heights_[0], hi = heights_[0];
    for (float h : heights_) {
      lo = std::min(lo, h);
      hi = std::max(hi, h);
    }
    box.extend(Vec3(-0.5 * macro_.size_x, -0.5 * macro_.size_y, lo));
    box.extend(Vec3(0.5 * macro_.size_x, 0.5 * macro_.size_y, hi));
  } else {
    for (const auto& v : vertices_) box.extend(v.cast<double>());
  }
  return box;
}

namespace {
// Deterministic parallel sum over facets (same result for any thread count).
template <class T, class F>
T reduce_facets(const Microsurface& s, T zero, F&& per_facet) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, s.num_facets(), 1 << 14), zero,
      [&](const tbb::blocked_range<std::size_t>& r, T acc) {
        for (std::size_t k = r.begin(); k != r.end(); ++k) per_facet(s.facet(k), acc);
        return acc;
      },
      [](T a, const T& b) { return a += b; });
}

struct Sums {
  Eigen::Matrix<double, 10, 1> v = Eigen::Matrix<double, 10, 1>::Zero();
  Sums& operator+=(const Sums& o) {
    v += o.v;
    return *this;
  }
};
}  // namespace

FacetSums facet_sums(const Microsurface& s) {
  Sums acc = reduce_facets(s, Sums{}, [&](const Triangle& t, Sums& a) {
    Vec3 c = t.cross();
    double area = 0.5 * c.norm();
    if (area == 0.0) return;
    Vec3 m = c / c.norm();
    a.v.head<3>() += area * m;
    a.v[3] += area * m.z();
    a.v[4] += area;
    // Slopes are weighted by projected area A_f (n.m_f): the slope distribution P22 is a
    // density over the macrosurface [Heitz14, App. A].
    if (m.z() > 0) {
      double w = area * m.z();
      double sx = -m.x() / m.z(), sy = -m.y() / m.z();
      a.v[5] += w;
      a.v[6] += w * sx;
      a.v[7] += w * sy;
      a.v[8] += w * sx * sx;
      a.v[9] += w * sy * sy;
    }
  });
  // Cross moment computed separately to keep the accumulator small and readable.
  double sxy = reduce_facets(s, 0.0, [&](const Triangle& t, double& a) {
    Vec3 c = t.cross();
    if (c.z() <= 0) return;
    Vec3 m = c.normalized();
    a += 0.5 * c.norm() * m.z() * (m.x() / m.z()) * (m.y() / m.z());
  });
  FacetSums f;
  f.sum_area_normal = acc.v.head<3>();
  f.sum_area_cos = acc.v[3];
  f.total_area = acc.v[4];
  double w = acc.v[5];
  if (w > 0) {
    f.slope_mean_x = acc.v[6] / w;
    f.slope_mean_y = acc.v[7] / w;
    f.slope_var_x = acc.v[8] / w - f.slope_mean_x * f.slope_mean_x;
    f.slope_var_y = acc.v[9] / w - f.slope_mean_y * f.slope_mean_y;
    f.slope_cov_xy = sxy / w - f.slope_mean_x * f.slope_mean_y;
  }
  return f;
}

double front_projected_area(const Microsurface& s, const Vec3& v) {
  return reduce_facets(s, 0.0, [&](const Triangle& t, double& a) {
    a += std::max(0.0, 0.5 * t.cross().dot(v));
  });
}

double lambda_from_facets(const Microsurface& s, const Vec3& v) {
  // Lambda(v) = sum_f A_f max(0, -v.m_f) / ((v.n) A)   [Heitz14, App. A]
  double back = reduce_facets(s, 0.0, [&](const Triangle& t, double& a) {
    a += std::max(0.0, -0.5 * t.cross().dot(v));
  });
  return back / (v.dot(s.macro().normal) * s.macro().area);
}

bool is_window(const Microsurface& s) {
  return s.kind() == Microsurface::Kind::Heightfield && s.description.is_object() &&
         s.description.value("boundary", std::string()) == "window";
}

}  // namespace microsim
