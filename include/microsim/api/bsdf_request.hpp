// measure bsdf as a request of the library: the BSDF per scattering order by random walks on one
// surface (mirror, conductor, dielectric, or a spectral conductor), at every incidence of
// theta_i x phi_i, its record (definitions included) and the renderer tables beside it.
//
// A request states a measurement as the command line and the Python module give it (material
// by name, angles in degrees, the output format); check() holds every limit, so that each front
// end refuses the same requests with the same words. The request is resolved into the table's
// options in api/bsdf_resolve.hpp, its record is built in api/bsdf_record.hpp and its table files
// are written by api/bsdf_files.hpp: the measure layer knows no request.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "microsim/api/run_context.hpp"
#include "microsim/models/metals.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/api/surface_input.hpp"

namespace microsim {

// Ranges of the request's counts: check() and the command line's help both use them.
constexpr int kMaxBsdfOrders = 16;
constexpr int kMaxBsdfResolution = 1024;
constexpr int kMinTableResolution = 2, kMaxTableResolution = 512;

// Incidence azimuths an isotropic renderer table averages by default.
constexpr int kDefaultTableAzimuths = 16;
constexpr int kMaxTableAzimuths = 360;

struct BsdfRequest {
  SurfaceInput surface;          // a periodic tile, a finite object or a vcavity ensemble
  std::string material;          // mirror, conductor or dielectric
  std::optional<double> eta, k;  // as given (conductor: both; dielectric: eta)
  // A spectral conductor (instead of eta and k): a shipped metal's table (models/metals.hpp) or
  // a CSV file of wavelength_nm, n, k; the wavelengths in nm (empty: default_wavelengths_nm).
  std::string metal, ior_file;
  std::vector<double> wavelengths_nm;
  // Incidences: every theta_i x phi_i, measured sorted, without repeats.
  std::vector<double> theta_i_deg;
  std::vector<double> phi_i_deg = {0.0};
  int orders = 4;
  long long rays = 1000000;
  std::uint64_t seed = 1;
  int replicates = 32;
  bool models = true;
  bool polarized = false;     // Mueller matrices along the paths (measure/polarized_walk.hpp)
  int resolution = 64;        // hemisphere map R; also the in-plane bins
  int table_resolution = 64;  // .bsdf tables; .pbsdf grids (io/pbsdf.hpp pbsdf_grid)
  // Isotropic .bsdf / .binary tables (one phi_i): incidence azimuths averaged (BsdfTableOptions).
  int table_azimuths = kDefaultTableAzimuths;
  std::string format = "json";  // json, exr, bsdf (RGL tensor file), binary (MERL) or pbsdf (polarized)
  int threads = 0;              // for the memory estimate (0: all processors; the run sets its own)
  // ParameterError naming what is out of range: counts, angles, the material and its indices,
  // the output format against the angles, and the memory the tallies need.
  void check() const;
};

// The output formats of measure bsdf: the table files and the record alone.
constexpr const char* kBsdfFormats[] = {"exr", "json", "bsdf", "binary", "pbsdf"};

// The request as it is measured: its incidence angles sorted, without repeats.
BsdfRequest normalized_bsdf_request(const BsdfRequest& r);

// The index table of a spectral request (metal or ior_file), or nullopt; ParameterError for a
// misplaced or unknown metal and an unreadable or malformed file.
std::optional<models::IndexTable> bsdf_index_table(const BsdfRequest& request);
// The wavelengths of a spectral request, checked against its table (empty when not spectral).
std::vector<double> bsdf_wavelengths(const BsdfRequest& request);
// The conductors of a spectral request's table at its wavelengths `nm`, one per wavelength.
std::vector<models::Material> spectral_conductors(const models::IndexTable& table, const std::vector<double>& nm);
// The material the request names (a spectral conductor: its index at the first wavelength);
// ParameterError for a wrong name or missing / misplaced indices.
models::Material bsdf_material(const BsdfRequest& request);

}  // namespace microsim
