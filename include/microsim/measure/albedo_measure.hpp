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
// Quadrature. E_avg = sum_j W_j E(mu_j):
//  * gauss-legendre (default): the N-point Gauss-Legendre rule in mu on [0, 1], W_j = w_j mu_j
//    (w_j the rule's weights on [-1, 1]); exact when E is a polynomial of degree <= 2N - 2;
//  * trapezoid (given incidence angles): E linear in mu between the nodes and constant from the
//    outermost nodes to mu = 0 and mu = 1, integrated exactly against 2 mu.
// Statistical error: sqrt(sum_j W_j^2 se_j^2) (independent nodes). Quadrature error: the
// difference |Q - Q_low| from a lower-order rule on a subset of the same measured values
// (every other node; gauss-legendre: the interpolating polynomial of those nodes integrated
// exactly; trapezoid: the piecewise-linear rule on them, the outermost nodes kept). It is the
// error of the lower rule, so an overestimate of the higher rule's; its own noise,
// sqrt(sum_j (W_j - W'_j)^2 se_j^2), is reported beside it.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "microsim/api/albedo_request.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/bsdf_table.hpp"
#include "microsim/measure/table.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// A quadrature of 2 int_0^1 E(mu) mu dmu on measured nodes, with a lower-order rule on a subset
// of them for the error estimate. Nodes increase in mu.
struct MuQuadrature {
  std::string rule;                 // "gauss-legendre" or "trapezoid"
  std::vector<double> mu;           // nodes
  std::vector<double> weight;       // W_j: E_avg = sum_j W_j E(mu_j)
  std::vector<double> low_weight;   // W'_j of the lower-order rule (0 on nodes it does not use)
  bool has_low_rule = false;        // false when the subset is every node (too few nodes)
  std::string description() const;  // the rule and its lower-order partner, in words
};
// The N-point Gauss-Legendre rule in mu on [0, 1] (N >= 2).
MuQuadrature gauss_legendre_mu(int nodes);
// The piecewise-linear rule on the given nodes (sorted here; at least one, each in (0, 1]).
MuQuadrature trapezoid_mu(std::vector<double> mu);

// E_avg of values at the nodes, with its statistical and quadrature errors.
struct AlbedoAverage {
  double value = 0.0;
  double stderr_ = 0.0;            // sqrt(sum W_j^2 se_j^2)
  double quadrature_error = 0.0;   // |Q - Q_low|; NaN without a lower-order rule
  double quadrature_error_noise = 0.0;  // sqrt(sum (W_j - W'_j)^2 se_j^2); NaN likewise
  double low_rule_value = 0.0;
};
AlbedoAverage average_albedo(const MuQuadrature& q, const std::vector<Estimate>& e);
// The quadrature the request asks for.
MuQuadrature albedo_quadrature(const AlbedoRequest& request);

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

// Measures E at every node of the request's quadrature on one surface (the BSDF walk with
// hemisphere maps of one pixel and no models). `progress`: fraction done.
AlbedoSurface measure_albedo(const Microsurface& s, const std::string& file, const AlbedoRequest& request,
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

// The record of `measure albedo` after its run header: parameters, definitions, quadrature,
// surfaces, rows (per node) and averages (E_avg per series).
void put_albedo_record(Json& record, const AlbedoRequest& request, const std::vector<AlbedoSurface>& surfaces);

// The lookup table: rows are the surfaces (in the order given; attribute alpha lists their
// nominal alpha), columns the mu nodes (increasing). Channels: E (all orders, both sides),
// E_stderr (the error map), E_avg, E_avg_stderr and E_avg_quadrature_error (the row's value in
// every column), and per series <series> and <series>_stderr.
ExrTable albedo_lut_exr(const AlbedoRequest& request, const std::vector<AlbedoSurface>& surfaces);

}  // namespace microsim
