// Polarized BRDF tables (.pbsdf) for Mitsuba 3's `measured_polarized` plugin, the format of the
// measured materials of [Baek20]; docs/theory/polarization.md describes the fields and the frames.
//
// An RGL tensor file (io/rgl_bsdf.hpp) with the fields
//   theta_h, theta_d, phi_d  float32 [1, n]: the grids of Rusinkiewicz's angles in radians,
//                            increasing; theta_h, theta_d in [0, pi/2], phi_d in [-pi, pi];
//   wvls                     uint16 [5]: wavelengths in nm (the plugin reads exactly five);
//   M                        float32 [n_phi_d][n_theta_d][n_theta_h][5][4][4]: the Mueller-matrix
//                            BRDF f (the plugin multiplies by the light's cosine), row-major 4 x 4;
//                            NaN where the light or the view direction is below the horizon.
// Isotropic materials only: a node stands for every rotation of its pair of directions about z.
//
// A node (theta_h, theta_d, phi_d) is the pair (light l, view v) with the half vector
// h = (sin theta_h, 0, cos theta_h), t = (cos theta_h, 0, -sin theta_h), b = (0, 1, 0),
// p = cos phi_d t + sin phi_d b, l = cos theta_d h + sin theta_d p, v = cos theta_d h - sin theta_d p.
// The matrix maps the Stokes vector of the light arriving along -l to that of the light leaving
// along v, both with the reference axis p x h (= normalize(l x v): the s axis of the facet h).
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "microsim/io/pbsdf_grid.hpp"
#include "microsim/io/rgl_bsdf.hpp"
#include "microsim/measure/bsdf_table.hpp"
#include "microsim/models/mueller.hpp"

namespace microsim {

struct PolarizedTable {
  std::vector<float> theta_h, theta_d, phi_d;  // radians
  std::vector<std::uint16_t> wavelengths;      // nm
  std::vector<float> M;  // [phi_d][theta_d][theta_h][wavelength][4][4]

  std::size_t size() const { return phi_d.size() * theta_d.size() * theta_h.size() * wavelengths.size() * 16; }
  // Offset in M of the 4 x 4 block at (phi_d index, theta_d index, theta_h index, wavelength index).
  std::size_t offset(std::size_t p, std::size_t d, std::size_t h, std::size_t l) const {
    return (((p * theta_d.size() + d) * theta_h.size() + h) * wavelengths.size() + l) * 16;
  }
  models::Mueller block(std::size_t p, std::size_t d, std::size_t h, std::size_t l) const;
  std::vector<TensorField> fields() const;
};

// The plugin reads exactly five wavelengths: UsageError unless the table has five, and unless
// the grids are increasing and in range and M has the size of the grids.
void write_pbsdf(const std::string& path, const PolarizedTable& table);
// UsageError naming the file when a field is missing or of the wrong type or shape.
PolarizedTable read_pbsdf(const std::string& path);

// The light and view directions of a node (see above), with the half vector h and the unit
// vector p (the light's offset from h) that fix the reference axis p x h.
struct RusinkiewiczPair {
  Vec3 light, view, h, p;
};
RusinkiewiczPair directions_of_rusinkiewicz(double theta_h, double theta_d, double phi_d);
// The inverse, as the plugin computes it: h = normalize(l + v), b = normalize(z x h),
// t = normalize(b x h), theta_d = angle(h, l), phi_d = atan2(b . p, t . p), p = l's part
// perpendicular to h (undefined at theta_h = 0 or theta_d = 0, where the plugin has no frame either).
void rusinkiewicz_of_directions(const Vec3& light, const Vec3& view, double* theta_h, double* theta_d, double* phi_d);
// The plugin's Stokes reference axis of both beams of a node: p x h.
inline Vec3 pbsdf_reference_axis(const RusinkiewiczPair& d) { return d.p.cross(d.h).normalized(); }

// A Mueller-matrix BRDF in microsim's frames: the matrix from the Stokes frame of the light
// arriving from `light` (axis stokes_frame(light)) to that of the light leaving toward `view`
// (axis stokes_frame(view)). Called from several threads at once.
using PolarizedBrdf = std::function<models::Mueller(const Vec3& light, const Vec3& view, double wavelength_nm)>;
// M of a microsim-frame matrix at a node, re-expressed in the plugin's frames.
models::Mueller to_pbsdf_frames(const models::Mueller& M, const RusinkiewiczPair& d);
// The table of f on the grids: every node with both directions above the horizon holds f in the
// plugin's frames, the others NaN. Grazing nodes (z >= -1e-6, the rounding of the float32 angles)
// are evaluated.
PolarizedTable fill_pbsdf(std::vector<float> theta_h, std::vector<float> theta_d, std::vector<float> phi_d,
                          std::vector<std::uint16_t> wavelengths, const PolarizedBrdf& f);
// n values evenly spaced from lo to hi (both included).
std::vector<float> evenly_spaced(double lo, double hi, int n);

// ---------------------------------------------------------------------------------------------
// A table from a polarized measurement (measure bsdf --polarized -o X.pbsdf)

// The wavelength count, the single-index wavelengths and the node counts of pbsdf_grid(n): io/pbsdf_grid.hpp.

// The measured Mueller BRDF of an isotropic polarized table (one phi_i, every run with per-bin
// tallies) for light from `light` seen from `view` at wavelength index l, in microsim's frames
// (axes stokes_frame(light) in, stokes_frame(view) out): the pair turned about z so that the light
// has the table's azimuth (the frames turn with it, so the matrix does not change); then, as the
// unpolarized tables (table_f): bilinear between the pixel centres of the bin map (all orders),
// linear in theta_i between measured incidences and held constant outside them, the mean over the
// table's incidence azimuths weighted by walks. Zero when either direction is below the horizon.
models::Mueller measured_mueller(const BsdfTable& t, const Vec3& light, const Vec3& view, int l);
// The .pbsdf of a measured table: the grid of pbsdf_grid(table_resolution), each valid node
// measured_mueller re-expressed in the plugin's frames (fill_pbsdf), the run's wavelengths (a
// single index: pbsdf_single_index_wavelengths with the same matrix at each). UsageError unless
// the runs are polarized with per-bin tallies, one azimuth and five whole-nanometre wavelengths.
PolarizedTable measured_pbsdf(const BsdfTable& t, int table_resolution);

}  // namespace microsim
