#include "microsim/trace/ray_window.hpp"

#include <algorithm>
#include <cmath>

#include "microsim/trace/tracer.hpp"

namespace microsim {

RayWindow make_ray_window(const Tracer& tracer, const Vec3& v) {
  const Macrosurface& m = tracer.surface().macro();
  RayWindow w;
  if (m.region && !m.periodic) {
    // A measured region: a horizontal rectangle at the top of the slab holding every ray along
    // -v that can meet a facet of the region (the region stretched toward v_xy by the slab's
    // height H: (H / v.z) v_xy). Only hits on the region's facets count (hit.facet <
    // num_facets()); the rest are misses, as for a finite object. (A periodic tile measured in a
    // region keeps the tile's window below: a longer one would wrap onto the region twice.)
    const double H = tracer.z_top() - tracer.z_bottom();
    const double sx = H * v.x() / v.z(), sy = H * v.y() / v.z();
    const double x0 = m.region_x0 + std::min(0.0, sx), x1 = m.region_x1 + std::max(0.0, sx);
    const double y0 = m.region_y0 + std::min(0.0, sy), y1 = m.region_y1 + std::max(0.0, sy);
    w.origin0 = Vec3(x0, y0, tracer.z_top());
    w.e1 = Vec3(x1 - x0, 0, 0);
    w.e2 = Vec3(0, y1 - y0, 0);
  } else if (m.periodic) {
    w.origin0 = Vec3(-0.5 * m.size_x, -0.5 * m.size_y, tracer.z_top());
    w.e1 = Vec3(m.size_x, 0, 0);
    w.e2 = Vec3(0, m.size_y, 0);
  } else {
    Eigen::AlignedBox3d box = tracer.surface().bounds();
    Vec3 t1 = std::abs(v.z()) < 0.9 ? v.cross(Vec3::UnitZ()).normalized()
                                     : v.cross(Vec3::UnitX()).normalized();
    Vec3 t2 = v.cross(t1);
    Vec3 c = box.center();
    double lo1 = 1e300, hi1 = -1e300, lo2 = 1e300, hi2 = -1e300;
    // The projection of the vertices (tighter than the bounding box's corners: fewer missed
    // rays, a smaller binomial error for the same ray count).
    for (const auto& vf : tracer.surface().vertices()) {
      Vec3 q = vf.cast<double>() - c;
      lo1 = std::min(lo1, q.dot(t1));
      hi1 = std::max(hi1, q.dot(t1));
      lo2 = std::min(lo2, q.dot(t2));
      hi2 = std::max(hi2, q.dot(t2));
    }
    double pad = 1e-3 * box.sizes().norm();
    double far = box.sizes().norm() + 1.0;
    w.origin0 = c + (lo1 - pad) * t1 + (lo2 - pad) * t2 + far * v;
    w.e1 = (hi1 - lo1 + 2 * pad) * t1;
    w.e2 = (hi2 - lo2 + 2 * pad) * t2;
  }
  w.area_perp = std::abs(w.e1.cross(w.e2).dot(v));
  return w;
}

}  // namespace microsim
