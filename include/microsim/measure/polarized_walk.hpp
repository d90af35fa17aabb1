// Mueller matrices carried along the BSDF walk (`measure bsdf --polarized`, docs/guide/polarization.md):
// every path of the explicit surface keeps its facets as it is walked for the unpolarized
// tallies (one trace per path), and the path's Mueller
// matrix is built from them (models/mueller.hpp: the s/p frame of each facet, the Fresnel
// matrix, the rotations between frames), from the Stokes frame of the light's direction to the
// frame of the exit direction, once per wavelength (the geometry is shared, only r_s and r_p
// change). A dielectric's path matrix is divided by the probabilities of the branches the walk
// chose, so its M00 estimates the same albedo as the unpolarized weight of 1.
//
// Tallied: the reflected paths' matrices per order slot (orders 1 .. K-1, K+ and the total, as
// the albedo tallies) and wavelength, summed per replicate in the unpolarized tallies' order,
// so for a mirror, and for a conductor's single scattering, M00 equals the unpolarized albedo
// bit for bit. Errors: the spread of the replicate means, as the albedo's.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "microsim/io/output.hpp"
#include "microsim/models/mueller.hpp"

namespace microsim {

struct WalkFacet;
struct WalkEnd;

// The equal-area map (HemisphereMap) of the direction-resolved sums: coarse, so that each pixel
// gathers paths of every order.
constexpr int kPolarizationMapResolution = 8;
// The per-bin Mueller BSDF's hemisphere map: the record's resolution R up to this one
// (min(R, 32)), so that its replicate sums (R^2 x 16 per wavelength and replicate) stay small.
constexpr int kMaxPolarizedBinResolution = 32;
inline int polarized_bin_resolution(int resolution) { return resolution < kMaxPolarizedBinResolution ? resolution : kMaxPolarizedBinResolution; }

// The reflected Mueller sums of a run: per replicate, order slot and wavelength, 16 elements
// (row-major); and the same per pixel of a coarse hemisphere map of the exit directions (each
// path's matrix in the frame of its own direction).
//
// The Mueller BSDF per outgoing bin: the same sums per pixel of an equal-area hemisphere map of
// resolution polarized_bin_resolution(R) (all orders together) and per in-plane bin of the
// record (InPlaneBins of R bins, every order slot). A bin's matrix maps the Stokes vector of the
// incident light (travelling along -l, reference axis stokes_frame(l)) to that of the light
// leaving through the bin, each path in the frame of its own exit direction o (reference axis
// stokes_frame(o) = normalize(z x o)); f = sum / (paths * int_bin |cos theta_o| d omega), the
// unpolarized f_pixel / f_plane's normalisation, so M00 is the BSDF of unpolarized light.
struct PolarizationTally {
  int orders = 0, wavelengths = 1, replicates = 0, pixels = 0;
  std::uint64_t paths = 0;          // all replicates
  std::vector<double> total;        // [k][l][16]: sum of w0 * M over reflected paths
  std::vector<double> replicate;    // [q][k][l][16]: the same per replicate
  std::vector<double> map_total;      // [k][l][pixel][16]
  std::vector<double> map_replicate;  // [q][k][l][pixel][16]
  int bin_resolution = 0, bin_pixels = 0, plane_bins = 0;
  std::vector<double> bin_cos, plane_cos;            // int_bin |cos theta_o| d omega per pixel / in-plane bin
  // Sums over the paths (all replicates), and the standard errors of f element by element (the
  // spread of the replicate means, computed once at the end of the run: the replicates' sums of
  // every bin are not kept).
  std::vector<double> bins_total, bins_stderr;    // [l][pixel][16] (all orders)
  std::vector<double> plane_total, plane_stderr;  // [k][l][b][16]

  int slots() const { return orders + 1; }
  std::size_t index(int k, int l) const { return (static_cast<std::size_t>(k) * wavelengths + l) * 16; }
  // Per-path mean of slot k at wavelength l, and its standard error per element.
  models::Mueller mean(int k, int l) const;
  models::Mueller stderr_(int k, int l) const;
  // Replicate q's per-path mean.
  models::Mueller replicate_mean(int q, int k, int l) const;
  // A scalar linear-or-not function g of the mean matrix, with the standard error of g over the
  // replicate means (sd / sqrt(R)).
  Estimate statistic(int k, int l, const std::function<double(const models::Mueller&)>& g) const;
  // The Mueller BSDF of pixel px (all orders) / of in-plane bin b (slot k) at wavelength l, and
  // the standard errors of its elements (the spread of the replicate means).
  models::Mueller pixel_f(int l, int px) const;
  models::Mueller pixel_f_stderr(int l, int px) const;
  models::Mueller plane_f(int k, int l, int b) const;
  models::Mueller plane_f_stderr(int k, int l, int b) const;
  std::size_t pixel_index(int l, int px) const { return (static_cast<std::size_t>(l) * bin_pixels + px) * 16; }
  std::size_t plane_index(int k, int l, int b) const {
    return ((static_cast<std::size_t>(k) * wavelengths + l) * plane_bins + b) * 16;
  }
  // Keeps only what a table reads (bins_total, paths and the bin geometry): for the runs an
  // azimuth-averaged table adds without reporting them; frees the replicate sums, the errors,
  // the albedo and map sums and the in-plane sums.
  void keep_table_sums_only();
  // The degree of polarization of the reflected light direction by direction for the input s:
  // sum over pixels of |(s1, s2, s3)| of M_pixel s over the sum of its s0 (the flux-weighted mean
  // of the pixels' degrees of polarization), with its error over the replicates.
  Estimate resolved_degree_of_polarization(int k, int l, const models::Stokes& s) const;
};

// What the polarized sums of a run take from it (measure_bsdf).
struct PolarizedSumsSetup {
  Vec3 wi;                       // light direction
  double ray_weight = 1.0;
  int replicates = 32;           // the run's (ReplicatePlan::replicates)
  int orders = 4;
  models::Material material;     // single index (spectral empty)
  std::vector<models::Material> spectral;
  double phi_i = 0.0;            // the in-plane bins' plane of incidence
  int resolution = 0;            // the record's R: in-plane bins, and the bin map's resolution
                                 // polarized_bin_resolution(R); 0: no per-bin tallies
  // A run that enters only a table's averages (BsdfOptions::table_sums_only): bins_total alone,
  // summed replicate by replicate as finish() sums it, without the other sums and the errors.
  bool bins_only = false;
};

// One work unit's Mueller sums (measure/replicates.hpp): its paths, and its reflected paths'
// matrices as PolarizationTally lays them out.
struct MuellerUnit {
  std::vector<double> sums;   // [k][l][16]
  std::vector<double> map;    // [k][l][pixel][16]
  std::vector<double> bins;   // [l][bin pixel][16]
  std::vector<double> plane;  // [k][l][b][16]
  std::uint64_t paths = 0;
  // Every sum, declared once (tally_fields.hpp): added (operator+=) and exchanged between
  // processes (a replicate's row, measure/shards.hpp) from this list alone.
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f("sums", &MuellerUnit::sums);
    f("map", &MuellerUnit::map);
    f("bins", &MuellerUnit::bins);
    f("plane", &MuellerUnit::plane);
    f("paths", &MuellerUnit::paths);
  }
  MuellerUnit& operator+=(const MuellerUnit& o);
};

// The polarized sums of a run, filled from the BSDF walk's own paths (measure_bsdf walks each
// path once and hands it here with its facets): per unit, then per replicate in unit order
// (the order of the unpolarized tallies), then the run's PolarizationTally.
class PolarizedSums {
 public:
  explicit PolarizedSums(const PolarizedSumsSetup& setup);
  ~PolarizedSums();
  MuellerUnit make_unit() const;
  // A walked path into its unit's sums (every path counts; a reflected one adds its matrices).
  void add_path(const WalkEnd& end, const std::vector<WalkFacet>& facets, MuellerUnit& unit) const;
  // Unit sums of replicate q, in unit order.
  void add_unit(int q, const MuellerUnit& unit);
  // The totals and the errors of the bins.
  PolarizationTally finish();

 private:
  struct Layout;
  std::unique_ptr<Layout> layout_;
  // bins_only: the replicate summed so far into bins_total, its sum back to zero.
  void add_summed_replicate();
};

// The Mueller matrix of a walked path for each of `count` materials (the geometry shared): from
// the Stokes frame of wi to that of `exit` (models::stokes_frame), divided by the product of the
// branch probabilities. out[l] for l < count.
void walk_path_muellers(const Vec3& wi, const std::vector<WalkFacet>& facets, const Vec3& exit,
                        const models::Material* materials, int count, models::Mueller* out);

// Fully polarized inputs of the record, in the incident frame (x = the azimuthal axis of the
// light's direction, the s axis of the specular plane): unpolarized, s, p, 45 degrees, circular
// (s3 > 0, docs/theory/polarization.md).
struct NamedStokes {
  const char* name;
  models::Stokes s;
};
std::vector<NamedStokes> polarization_inputs();

// The lowest eigenvalue of the coherency matrix of the mean of slot k, wavelength l, with its
// standard error: the spread over the replicate means of v^H H(M_q) v for the eigenvector v
// of the mean's lowest eigenvalue (linear in M, so the error of a fixed quadratic form).
Estimate coherency_min_eigenvalue(const PolarizationTally& t, int k, int l);

// The record's `polarization` block of one incidence (docs/reference: the record fields):
// per order key, one entry per wavelength with the mean Mueller matrix, its errors, the degree of
// polarization of the reflected light for each of polarization_inputs() with its error, and the
// coherency matrix's lowest eigenvalue with its error. `wavelengths_nm` empty: a single index.
// With the per-bin tallies, `bins` (the hemisphere map, all orders) and `in_plane` (per slot):
// per wavelength the matrices f and their errors of every bin (docs/guide/polarization.md).
Json polarization_json(const PolarizationTally& t, const std::vector<double>& wavelengths_nm);

}  // namespace microsim
