// measure albedo as a request of the library: the directional albedo E(mu) per scattering order
// and in total at the nodes of a quadrature in mu, and E_avg = 2 int E(mu) mu dmu with its
// errors, per surface (measure/albedo_measure.hpp); its record and the lookup table E(mu, alpha)
// (api/albedo_record.hpp). The request is resolved into the measurement's options in
// api/albedo_resolve.hpp: the measure layer knows no request.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "microsim/api/run_context.hpp"
#include "microsim/api/surface_input.hpp"
#include "microsim/measure/mu_quadrature.hpp"
#include "microsim/models/microfacet_bsdf.hpp"

namespace microsim {

// Ranges of the request (the command line's help uses them; mu_nodes: kMinMuNodes, kMaxMuNodes
// of measure/mu_quadrature.hpp).
constexpr int kMaxAlbedoAzimuths = 360;

struct AlbedoRequest {
  // Each surface is measured on its own (a row of the lookup table, in the order given).
  std::vector<SurfaceInput> surfaces;
  std::string material;           // mirror, conductor or dielectric
  std::optional<double> eta, k;   // as in BsdfRequest
  // A conductor from a shipped metal's table (models/metals.hpp) at one wavelength.
  std::string metal;
  double wavelength_nm = 550.0;
  int mu_nodes = 8;                 // Gauss-Legendre nodes in mu (when theta_i_deg is empty)
  std::vector<double> theta_i_deg;  // given incidences instead: the trapezoid rule in mu
  double phi_i_deg = 0.0;
  // Incidence azimuths averaged; 0: 1 (isotropic), kAnisotropicAlbedoAzimuths (anisotropic;
  // measure/albedo_measure.hpp).
  int azimuths = 0;
  int orders = 4;
  long long rays = 200000;  // per mu node and surface
  std::uint64_t seed = 1;
  int replicates = 32;
  int max_events = 10000;
  std::string format = "json";  // json, csv or exr (the lookup table)
  // ParameterError naming what is out of range (the incidences, the material and its index, the
  // quadrature and the counts).
  void check() const;
};

// The output formats of measure albedo.
constexpr const char* kAlbedoFormats[] = {"json", "csv", "exr"};

// The material the request names (a conductor from a metal's table: its index at wavelength_nm);
// ParameterError for a wrong name or missing / misplaced indices.
models::Material albedo_material(const AlbedoRequest& request);

// The request as it is measured: its incidences sorted, without repeats.
AlbedoRequest normalized_albedo_request(const AlbedoRequest& r);

}  // namespace microsim
