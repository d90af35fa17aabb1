// The directional albedo of an explicit microsurface, per scattering order and in total, its
// cosine-weighted hemispherical average, and the lookup table E(mu, alpha) that renderers use
// for energy compensation (docs/guide/albedo.md).
//
// Definitions. Light arrives from l with mu = cos theta_i. The directional albedo
//   E(mu) = fraction of the incident power that leaves the surface (reflected, plus transmitted
//           for a dielectric), all scattering orders,
// and E_k(mu) the same for the paths that leave after exactly k events (the slots of the BSDF
// walk: orders 1 .. K-1, K and above). For a mirror (F = 1) every path keeps its power, so
// E(mu) = 1 - (lost + unterminated paths) / paths: the white furnace test of an explicit
// heightfield. The hemispherical average is
//   E_avg = 2 int_0^1 E(mu) mu dmu
// (the albedo under uniform illumination, the E_avg of Kulla-Conty energy compensation).
//
// Measurement. Each mu node is one incidence of the BSDF random walk (measure/bsdf_measure.hpp,
// measure_bsdf_table): the same walk, tallies per order, replicate standard errors. Incidences
// draw from their own counter streams (keyed by their angles), so the nodes are independent and
// the errors of E at different nodes are uncorrelated. An anisotropic surface's E depends on the
// incidence azimuth: E is then the mean over `azimuths` azimuths phi_i + 2 pi a / N (rays split
// evenly), its error combined from the runs' independent errors.
//
// Quadrature: E_avg = sum_j W_j E(mu_j) by a rule in mu with its statistical and quadrature
// errors (measure/mu_quadrature.hpp).
//
// The measurement takes plain values (AlbedoOptions); a request of the library
// (api/albedo_request.hpp) is resolved into them in api/albedo_resolve.hpp, and its record is
// put together in api/albedo_record.hpp.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "microsim/io/output.hpp"
#include "microsim/measure/bsdf_table.hpp"
#include "microsim/measure/mu_quadrature.hpp"
#include "microsim/measure/table.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// The nominal roughness a surface stands for in the lookup table: alpha for an isotropic
// nominal NDF, sqrt(alpha_x alpha_y) for an anisotropic one; NaN without a nominal NDF.
double nominal_alpha(const Microsurface& s);

// E at one mu node, per side (0 reflected, 1 transmitted) and slot (orders 1 .. K+, total).
struct AlbedoNode {
  double mu = 0.0, theta_i_deg = 0.0;
  std::vector<Estimate> side[2];  // [slot], orders + 1 entries
  Estimate total;                 // reflected + transmitted, all orders (its own error)
  std::uint64_t paths = 0, lost = 0, unterminated = 0;
};

struct AlbedoSurface {
  std::string file;
  Json description;  // the surface's own (Microsurface::description)
  std::optional<models::Ndf> nominal;
  double alpha = 0.0;  // nominal_alpha
  int azimuths = 1;
  bool transmits = false;
  int orders = 4;
  std::vector<AlbedoNode> nodes;  // increasing mu
  double seconds = 0.0;
};

// Azimuths averaged on an anisotropic surface when the options leave it open (azimuths = 0).
constexpr int kAnisotropicAlbedoAzimuths = 8;

// What the measurement of E needs: the material, the nodes and the walks' counts.
struct AlbedoOptions {
  models::Material material;
  MuQuadrature quadrature;  // its nodes are the incidences measured
  double phi_i_deg = 0.0;
  int azimuths = 0;  // incidence azimuths averaged; 0: 1 (isotropic), kAnisotropicAlbedoAzimuths (anisotropic)
  int orders = 4;
  long long rays = 200000;  // per mu node
  std::uint64_t seed = 1;
  int replicates = 32;
  int max_events = 10000;
};

// Measures E at every node of the options' quadrature on one surface (the BSDF walk with
// hemisphere maps of one pixel and no models). `progress`: fraction done. ParameterError when
// the rays are fewer than the replicates of every azimuth.
AlbedoSurface measure_albedo(const Microsurface& s, const std::string& file, const AlbedoOptions& options,
                             const std::function<void(double)>& progress = {});

// The slot names of E: "reflected_order_1", ..., "reflected_total", "transmitted_..." (a
// dielectric) and "albedo" (both sides, all orders).
std::vector<std::string> albedo_series(int orders, bool transmits);
// The estimates of series `name` at every node of `s`.
std::vector<Estimate> albedo_series_values(const AlbedoSurface& s, const std::string& name);

// Record tables: one row per surface and mu node; one row per surface and series for E_avg.
Table albedo_nodes_spec(int orders, bool transmits);
Table albedo_average_spec();
Table albedo_nodes_table(const std::vector<AlbedoSurface>& surfaces, const MuQuadrature& q);
Table albedo_average_table(const std::vector<AlbedoSurface>& surfaces, const MuQuadrature& q);

// The measured part of `measure albedo`'s record (after its parameters): quadrature,
// definitions, surfaces, rows (per node) and averages (E_avg per series).
void put_albedo_results(Json& record, const MuQuadrature& q, const std::vector<AlbedoSurface>& surfaces);

// The lookup table: rows are the surfaces (in the order given; attribute alpha lists their
// nominal alpha), columns the mu nodes (increasing). Channels: E (all orders, both sides),
// E_stderr (the error map), E_avg, E_avg_stderr and E_avg_quadrature_error (the row's value in
// every column), and per series <series> and <series>_stderr. The header names `material`, `rays` (per
// node) and `orders` (also K when there are no surfaces).
ExrTable albedo_lut_exr(const MuQuadrature& q, const std::vector<AlbedoSurface>& surfaces, const std::string& material,
                        long long rays, int orders);

}  // namespace microsim
