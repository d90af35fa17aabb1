#include "microsim/api/albedo_record.hpp"

#include "microsim/api/albedo_resolve.hpp"

namespace microsim {

void put_albedo_record(Json& j, const AlbedoRequest& o, const std::vector<AlbedoSurface>& surfaces) {
  const MuQuadrature q = albedo_quadrature(o);
  const models::Material m = albedo_material(o);
  j["file"] = Json::array();
  for (const AlbedoSurface& s : surfaces) j["file"].push_back(s.file);
  j["parameters"] = {{"material", o.material},
                     {"eta", o.metal.empty() ? (o.eta ? Json(*o.eta) : Json(nullptr)) : Json(m.eta)},
                     {"k", o.metal.empty() ? (o.k ? Json(*o.k) : Json(nullptr)) : Json(m.k)},
                     {"metal", o.metal.empty() ? Json(nullptr) : Json(o.metal)},
                     {"wavelength_nm", o.metal.empty() ? Json(nullptr) : Json(o.wavelength_nm)},
                     {"phi_i_deg", o.phi_i_deg},
                     {"orders", o.orders},
                     {"rays_per_node", o.rays},
                     {"seed", o.seed},
                     {"replicates", o.replicates},
                     {"max_events", o.max_events}};
  put_albedo_results(j, q, surfaces);
}

ExrTable albedo_lut_exr(const AlbedoRequest& o, const std::vector<AlbedoSurface>& surfaces) {
  return albedo_lut_exr(albedo_quadrature(o), surfaces, o.material, o.rays, o.orders);
}

}  // namespace microsim
