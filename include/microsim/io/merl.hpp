// MERL isotropic BRDF files (.binary; docs/theory/exports.md): three int32 (90, 90, 180), then the
// R, G and B blocks of 90 * 90 * 180 doubles, cell (theta_h, theta_d, phi_d) at index
// phi_d + 180 (theta_d + 90 theta_h); theta_h cell i covers u in [i/90, (i+1)/90) with theta_h =
// u^2 pi/2, theta_d cell j covers [j, j+1) pi/180, phi_d cell k covers [k, k+1) pi/180. A reader
// multiplies the three blocks by 1/1500, 1.15/1500 and 1.66/1500; we store f times the inverse,
// so the decoded channels are equal for our wavelength-independent materials. A spectral
// conductor's channels are the white-balanced linear sRGB of its per-wavelength f
// (models/spectral_rgb.hpp; a mirror's would be equal).
//
// Filling: each cell's value is the measured f (reflected side, all orders) at the cell centre.
// The centre's (theta_h, theta_d, phi_d) give the pair (wi, wo) with the half vector at azimuth 0
// (wi = R_y(theta_h) d(theta_d, phi_d), wo its mirror about the half vector); by reciprocity
// [GeomBSDF24, eq. 4c] the direction nearer the normal is taken as the light's; the pair is turned
// about the normal so that wi has the measured azimuth, then f is read from the measured
// hemisphere maps (interpolate_f) of the two measured incidences that bracket theta(wi) at the
// same outgoing direction and interpolated linearly in theta_i (held constant outside the
// measured range). Cells with wi or wo below the horizon hold 0.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "microsim/measure/bsdf_table.hpp"

namespace microsim {

constexpr int kMerlThetaH = 90, kMerlThetaD = 90, kMerlPhiD = 180;
constexpr std::size_t kMerlCells = static_cast<std::size_t>(kMerlThetaH) * kMerlThetaD * kMerlPhiD;
constexpr double kMerlScale[3] = {1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0};

// The f of every cell (one block, not yet divided by the reader's scales). UsageError when the
// table has more than one azimuth (anisotropic).
std::vector<double> merl_cells(const BsdfTable& t);
// The measured f at (wi, wo), interpolated in theta_i as described above.
// `lambda`: a spectral run's wavelength index, -1 the measured tallies.
double table_f(const BsdfTable& t, const Vec3& wi, const Vec3& wo, int lambda = -1);
// The R, G and B cells (not yet divided by the reader's scales): three copies of merl_cells, or a
// spectral conductor's colour per cell.
std::array<std::vector<double>, 3> merl_rgb_cells(const BsdfTable& t);
void write_merl(const std::string& path, const BsdfTable& t);

}  // namespace microsim
