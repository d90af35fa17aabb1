// Hemisphere maps of the V-cavity multiple-scattering model (models/vgroove_multiple.hpp) in the
// equal-area convention of measure bsdf, so that they compare pixel by pixel with measured maps:
// every groove's beams (closed form with every interreflection, [Xie18]) binned by exit direction
// and averaged over grooves, either with weight (n.m) D(m) (the nominal model, [Heitz14, Sec. 6]) or
// with equal weights over given groove normals (a V-cavity ensemble's own grooves: the exact
// expectation of `measure bsdf` on that ensemble for a mirror or conductor).
// (docs/theory/energy-compensation.md, "V-cavity multiple scattering")
#pragma once

#include <vector>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/models/ndf.hpp"

namespace microsim {

// Slots as vgroove_albedo: k = 0 .. K-2 order k+1, K-1 orders K and above, K the total.
// f[k][px]: the cosine-weighted pixel average of the lobe (HemisphereMap index px), the quantity of
// the measured maps; albedo[k] = sum_px f[k][px] int_px cos d omega. f_stderr[k][px]: for a groove
// list, the standard error of the groove average as an estimate of the nominal model (between-groove
// spread / sqrt(grooves)); empty for the quadrature.
struct GrooveLobeMaps {
  int orders = 0;
  std::size_t grooves = 0;  // normals averaged (quadrature: the cells with positive weight)
  std::vector<std::vector<double>> f, f_stderr;
  std::vector<double> albedo;
  // The map and albedo of orders >= min_order (1 <= min_order <= K): the sum of their slots.
  std::vector<double> f_from_order(int min_order) const;
  double albedo_from_order(int min_order) const;
};

// The nominal model for light from i (mirror or conductor; a dielectric's refracted light is not
// followed): n_theta x n_phi groove normals, one drawn uniformly in (theta_m, phi_m) in each cell of the
// grid of vcavity_quadrature (a fixed stratified sample: a regular grid aliases with the pixels),
// weights (n.m) D(m) sin(theta_m) dtheta dphi normalised to their sum. With a mirror the total albedo
// is 1 to rounding.
GrooveLobeMaps vcavity_multiple_maps(const models::Ndf& ndf, const models::Material& material, const Vec3& i,
                                     const HemisphereMap& map, int orders, int n_theta = 1024, int n_phi = 1024);

// The same over the grooves of the given normals (m.z > 0), each with weight 1 / grooves.
GrooveLobeMaps groove_ensemble_maps(const std::vector<Vec3>& normals, const models::Material& material,
                                    const Vec3& i, const HemisphereMap& map, int orders);

}  // namespace microsim
