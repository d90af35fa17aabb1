// RGL tensor files (.bsdf) of [Dupuy18], read by Mitsuba 3 `measured`, pbrt-v4
// `MeasuredBxDF` and the authors' reader (docs/theory/exports.md gives the byte layout).
//
// How a reader evaluates the file, which fixes what we store (u-coordinates: theta = u^2 pi/2,
// phi = (2u - 1) pi; every 2D table is bilinear between its vertices on [0, 1]^2, the last
// array dimension along x):
//   wm = normalize(wi + wo), u_m = (u(theta_m), u(phi_m - phi_i) [isotropic] or u(phi_m)),
//   s  = inverse of the `vndf` warp at (phi_i, theta_i) applied to u_m,
//   f cos(theta_o) = spectra(s) * ndf(u_m) / (4 sigma(u_wi))          (jacobian flag = 1).
// The `vndf` warp is the exact inversion of its bilinear density (row marginal over phi first,
// then the conditional over theta). Sampling: s ~ `luminance` (bilinear density over the sample
// square), u_m = vndf warp(s), wo = reflect(wi, wm); pdf = p_lum(s) p_vndf(u_m) / (2 pi^2 u_theta
// sin(theta_m) 4 (wi.wm)).
//
// What we store:
//   ndf    the facets' D(m) by a kernel estimate at every vertex: sum_f (A_f / A) K(m_f) /
//          int K d omega, K a tent in theta of half-width max(vertex spacing, 1.5 degrees) (the
//          u-grid's first steps near the pole are far too small to hold facets) times, when
//          anisotropic, a tent of one vertex spacing in phi (at most 17 phi vertices, 22.5
//          degrees apart: finer tents hold too few facets of one tile); floored at `ndf_floor` times its
//          maximum so that every half vector has a finite spectra value. Isotropic: the
//          azimuthal average.
//   sigma  sum_f A_f max(0, w.m_f) / A at each vertex direction: exact from the facets
//          (isotropic: averaged over 16 azimuths).
//   vndf   a density in u-space: 50% the visible-normal distribution D_wi = D <wi.m> /
//          sigma(wi) (from the stored ndf) times the u-to-solid-angle Jacobian, 30% the density
//          of the half vectors of the measured reflected light, f cos(theta_o) 4 (wi.m) times
//          the same Jacobian, 20% that of outgoing directions uniform over the hemisphere,
//          4 (wi.m) times the Jacobian. The reader uses it only as the warp that places the
//          sample grid (and samples); the mixture gives multiply scattered light far from the
//          visible normals, and every outgoing direction, grid points of their own.
//   spectra at every sample-square vertex s: wm = warp(s), wo = reflect(wi, wm); the measured
//          f cos(theta_o) (all orders, reflected side; bilinear on the measured hemisphere map)
//          times 4 sigma(u_wi) / ndf(u_m), both as the reader interpolates them, so that the
//          reader returns the measured f cos(theta_o) exactly at those directions. 0 where wo is
//          below the horizon. A wavelength-independent material: two wavelengths (360 and
//          830 nm) with equal values, and `rgb` with three equal channels. A spectral conductor
//          (measure/bsdf_measure.hpp, BsdfOptions::spectral): the run's wavelengths, each from
//          its own tallies, and `rgb` their white-balanced linear sRGB (models/spectral_rgb.hpp:
//          CIE 1931 2-degree observer, equal-energy illuminant, a mirror is (1, 1, 1)).
//   luminance = spectra (the sampling density over the sample square); a spectral conductor: the
//          spectrum's luminance Y (relative to the white's), which also weighs the measured
//          half vectors of the vndf.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "microsim/measure/bsdf_table.hpp"

namespace microsim {

// One field of a tensor file: dtype 1 = uint8, 3 = uint16, 10 = float32; data is raw little-endian bytes.
struct TensorField {
  std::string name;
  std::uint8_t dtype = 10;
  std::vector<std::uint64_t> shape;
  std::vector<std::uint8_t> data;
  static TensorField f32(const std::string& name, std::vector<std::uint64_t> shape, const std::vector<float>& v);
  static TensorField u8(const std::string& name, std::vector<std::uint64_t> shape, const std::vector<std::uint8_t>& v);
  static TensorField u16(const std::string& name, std::vector<std::uint64_t> shape, const std::vector<std::uint16_t>& v);
};
// Bytes per value of a tensor field's dtype (0 for the types not used here).
inline std::size_t tensor_element_size(std::uint8_t dtype) {
  return dtype == 1 ? 1 : dtype == 3 ? 2 : dtype == 10 ? 4 : 0;
}
// Header `tensor_file\0`, version 1.0, field count, field headers, data (8-byte aligned);
// written atomically.
void write_tensor_file(const std::string& path, const std::vector<TensorField>& fields);

// Bilinear density on [0, 1]^2 (ny rows along y, nx columns along x, values at vertices) and
// its exact inversion-method warp: y from the marginal, then x from the conditional at that y.
class BilinearWarp {
 public:
  BilinearWarp(std::vector<double> values, int nx, int ny);
  // The point of [0, 1]^2 that the uniform sample s maps to.
  Vec2 sample(const Vec2& s) const;
  // Density (integrates to 1) at a point.
  double pdf(const Vec2& p) const;
  // The integrals behind the warp, unnormalized (divide by total()): of the whole density, of
  // the rows below y (the marginal CDF), of row y itself and of row y left of x (the
  // conditional CDF). Readers blend these between tables to invert an interpolated warp.
  double total() const { return marg_[ny_ - 1]; }
  double marginal(double y) const;
  double row(double y) const;
  double conditional(double x, double y) const;

 private:
  std::vector<double> v_, cond_, marg_;  // vertex values, per-row cumulative, row marginal
  int nx_, ny_;
};

struct RglOptions {
  int resolution = 64;      // vndf / luminance / spectra: resolution x resolution vertices
  int ndf_resolution = 64;  // ndf: theta (and phi when anisotropic) vertices
  int sigma_resolution = 32;
  double ndf_floor = 1e-3;  // relative to the table's maximum
  double measured_share = 0.3;  // share of the measured half-vector density in the vndf warp
  double uniform_share = 0.2;   // share of the half vectors of uniformly spread outgoing light
  std::string description;
};

struct RglTable {
  bool isotropic = true;
  int resolution = 0;
  std::vector<float> theta_i, phi_i, wavelengths;
  int ndf_phi = 0, ndf_theta = 0, sigma_phi = 0, sigma_theta = 0;
  std::vector<float> ndf, sigma, vndf, luminance, spectra;  // row-major as in the file
  std::vector<float> rgb;  // [np][nt][3][R][R]; empty: three copies of the first spectrum
  std::string description;
  std::vector<TensorField> fields() const;
};

// Isotropic when the table has one phi_i (phi_m - phi_i stored); anisotropic when its phi_i run
// over the full circle from -180 to 180 degrees. UsageError otherwise.
RglTable build_rgl_table(const BsdfTable& t, const Microsurface& s, const RglOptions& o);
void write_rgl_bsdf(const std::string& path, const RglTable& table);

}  // namespace microsim
