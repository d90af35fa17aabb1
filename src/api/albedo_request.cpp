#include "microsim/api/albedo_request.hpp"

#include <algorithm>
#include <cmath>

#include "microsim/api/angle_list.hpp"
#include "microsim/api/bsdf_request.hpp"
#include "microsim/api/estimator_record.hpp"
#include "microsim/api/request_checks.hpp"
#include "microsim/models/metals.hpp"

namespace microsim {

namespace {

// The request as it is measured: its incidence angles sorted, without repeats.
AlbedoRequest normalized(const AlbedoRequest& r) {
  AlbedoRequest n = r;
  std::sort(n.theta_i_deg.begin(), n.theta_i_deg.end());
  n.theta_i_deg.erase(std::unique(n.theta_i_deg.begin(), n.theta_i_deg.end()), n.theta_i_deg.end());
  return n;
}


}  // namespace

void AlbedoRequest::check() const {
  require_above_horizon(theta_i_deg, "theta_i");  // in the order given
  if (format != "json" && format != "csv" && format != "exr")
    throw UsageError("the output must be .json, .csv or .exr (got ." + format + ")");
  albedo_material(*this);
  if (theta_i_deg.empty()) require_integer_in(mu_nodes, kMinMuNodes, kMaxMuNodes, "mu_nodes");
  if (!std::isfinite(phi_i_deg) || std::abs(phi_i_deg) > 3600)
    throw ParameterError("{phi_i} must be a finite angle in degrees, |phi| <= 3600");
  require_integer_in(azimuths, 0, kMaxAlbedoAzimuths, "azimuths");
  require_integer_in(orders, 1, kMaxBsdfOrders, "orders");
  require_rays_and_replicates(rays, replicates);
  const long long runs = azimuths > 0 ? azimuths : 1;
  if (rays < runs * replicates)
    throw ParameterError("{rays} must be at least {replicates} per azimuth (" + std::to_string(runs * replicates) +
                         " here; got " + std::to_string(rays) + ")");
}

AlbedoRequest normalized_albedo_request(const AlbedoRequest& r) { return normalized(r); }

models::Material albedo_material(const AlbedoRequest& o) {
  if (!o.metal.empty()) {
    if (o.material != "conductor") throw ParameterError("{metal} applies to {material} conductor only");
    if (o.eta || o.k) throw ParameterError("{eta} and {k} do not go with {metal} (the table gives the index)");
    const models::IndexTable& table = models::metal_table(o.metal);
    models::check_wavelengths({o.wavelength_nm}, table, "{wavelength_nm}");
    const models::OpticalConstant c = table.at(o.wavelength_nm);
    return models::Material::conductor(c.n, c.k);
  }
  BsdfRequest b;
  b.material = o.material;
  b.eta = o.eta;
  b.k = o.k;
  return bsdf_material(b);
}

}  // namespace microsim
