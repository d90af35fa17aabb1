#include "microsim/measure/sampling.hpp"

namespace microsim {

RayWindow make_ray_window(const Tracer& tracer, const Vec3& v) {
  const Macrosurface& m = tracer.surface().macro();
  RayWindow w;
  if (m.periodic) {
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
