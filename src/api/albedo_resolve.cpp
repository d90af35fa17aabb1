#include "microsim/api/albedo_resolve.hpp"

#include <cmath>
#include <vector>

namespace microsim {

MuQuadrature albedo_quadrature(const AlbedoRequest& o) {
  if (o.theta_i_deg.empty()) return gauss_legendre_mu(o.mu_nodes);
  std::vector<double> mu;
  for (double t : o.theta_i_deg) mu.push_back(std::cos(rad(t)));
  return trapezoid_mu(mu);
}

AlbedoOptions albedo_options(const AlbedoRequest& o) {
  AlbedoOptions out;
  out.quadrature = albedo_quadrature(o);
  out.material = albedo_material(o);
  out.phi_i_deg = o.phi_i_deg;
  out.azimuths = o.azimuths;
  out.orders = o.orders;
  out.rays = o.rays;
  out.seed = o.seed;
  out.replicates = o.replicates;
  out.max_events = o.max_events;
  return out;
}

AlbedoSurface measure_albedo(const Microsurface& s, const std::string& file, const AlbedoRequest& request,
                             const std::function<void(double)>& progress) {
  return measure_albedo(s, file, albedo_options(request), progress);
}

}  // namespace microsim
