#include "microsim/surface/undersurface.hpp"

namespace microsim {

Microsurface undersurface(const Microsurface& s) {
  if (s.kind() != Microsurface::Kind::Mesh)
    throw UsageError("the undersurface (view below the horizon, theta in (90, 180]) is measured on "
                     "meshes only; heightfields are measured from above, theta in [0, 90)");
  std::vector<Eigen::Vector3f> v = s.vertices();
  for (auto& p : v) p.z() = -p.z();
  Microsurface u = Microsurface::mesh(std::move(v), s.triangles(), s.macro());
  u.description = s.description;
  u.description["undersurface"] = true;
  // Beckmann and GGX are symmetric under (mx, my) -> (-mx, -my): reversing n and m keeps D
  // [GeomBSDF24, "Inherent Assumptions"], so the nominal NDF carries over.
  u.nominal = s.nominal;
  return u;
}

}  // namespace microsim
