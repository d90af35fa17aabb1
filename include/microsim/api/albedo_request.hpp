// measure albedo as a request of the library: the directional albedo E(mu) per scattering order
// and in total at the nodes of a quadrature in mu, and E_avg = 2 int E(mu) mu dmu with its
// errors, per surface (measure/albedo_measure.hpp); its record and the lookup table E(mu, alpha).
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "microsim/api/run_context.hpp"
#include "microsim/api/surface_input.hpp"

namespace microsim {

// Ranges of the request (the command line's help uses them).
constexpr int kMinMuNodes = 2, kMaxMuNodes = 64;
constexpr int kMaxAlbedoAzimuths = 360;
// Azimuths averaged on an anisotropic surface when the request leaves it open (azimuths = 0).
constexpr int kAnisotropicAlbedoAzimuths = 8;

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
  int azimuths = 0;  // incidence azimuths averaged; 0: 1 (isotropic), kAnisotropicAlbedoAzimuths (anisotropic)
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

struct AlbedoSurface;  // measure/albedo_measure.hpp

// A run of the request: the record and each surface's measurement (the lookup table's rows;
// shared, so that a run is whole without measure/albedo_measure.hpp).
struct AlbedoRun {
  Json record;
  std::shared_ptr<const std::vector<AlbedoSurface>> surfaces;
};

// Checks the request, measures each surface in turn (each loaded when its turn comes) and
// returns the record (command "measure albedo") with the measurements.
AlbedoRun run_albedo_request(const AlbedoRequest& r, const RunContext& ctx);
// The record of run_albedo_request.
Json measure_albedo_record(const AlbedoRequest& r, const RunContext& ctx);
// Writes a run to `output` by its format: .json the record; .csv the rows and the record beside
// (.json); .exr the lookup table, the rows beside (.csv) and the record (.json). Returns the
// paths written, in words ("lut.exr, lut.csv and lut.json").
std::string write_albedo_outputs(const std::string& output, const AlbedoRequest& r, const AlbedoRun& run);

}  // namespace microsim
