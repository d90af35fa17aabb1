// Evaluation of an RGL tensor file (.bsdf) at any pair of directions, the way Mitsuba 3's
// `measured` plugin evaluates it (format and writer: io/rgl_bsdf.hpp, docs/theory/exports.md):
//   theta_i = elevation(wi), phi_i = atan2(wi.y, wi.x); wm = normalize(wi + wo);
//   u_m = (u(theta_m), u(phi_m - phi_i) [isotropic: phi_i has at most 2 values] or u(phi_m));
//   s = inverse of the `vndf` warp at u_m, the warp interpolated linearly in (phi_i, theta_i)
//       between the tabulated incidences (each table normalized first; weights clamped to
//       [0, 1], so the outermost incidence holds beyond the grid; a parameter with one value is
//       not interpolated);
//   f cos(theta_o) = spectra(s; phi_i, theta_i) [* ndf(u_m) / (4 sigma(u_wi)) when `jacobian`].
// A renderer passes the direction toward the viewer as wi and the light's as wo (reciprocity),
// and the value is f times the cosine of wo. Files whose phi_i do not span the full circle
// (the symmetry reductions of acquired tables) are refused. Wavelength-dependent spectra are
// averaged over the file's wavelengths (grey preview).
#pragma once
#include <map>
#include <string>
#include <vector>

#include "microsim/io/rgl_bsdf.hpp"

namespace microsim {

// Every field of a tensor file; UsageError naming the file when it is not one.
std::map<std::string, TensorField> read_tensor_file(const std::string& path);

class RglMaterial {
 public:
  explicit RglMaterial(const std::string& path);
  // f(wi, wo) cos(theta_o), 0 unless both are above the surface.
  double eval(const Vec3& wi, const Vec3& wo) const;
  bool isotropic() const { return isotropic_; }
  const std::string& description() const { return description_; }
  const std::vector<float>& theta_i() const { return theta_i_; }
  const std::vector<float>& phi_i() const { return phi_i_; }
  // Multiplies every spectra value (tests: a deliberately wrong table).
  void scale(double c) { scale_ *= c; }

 private:
  struct Grid {  // bilinear [rows][cols] on [0, 1]^2
    std::vector<float> v;
    int nx = 0, ny = 0;
    double operator()(double x, double y, std::size_t offset = 0) const;
  };
  // Interpolation weights over the incidence grid: up to 4 (slice, weight) pairs.
  struct Blend {
    std::size_t slice[4];
    double weight[4];
    int n = 0;
  };
  Blend blend(double phi_i, double theta_i) const;
  Vec2 invert_vndf(const Vec2& um, const Blend& b) const;

  bool isotropic_ = true, jacobian_ = true;
  std::string description_;
  std::vector<float> theta_i_, phi_i_;
  int res_ = 0, n_wavelengths_ = 0;
  Grid ndf_, sigma_;
  std::vector<BilinearWarp> vndf_;  // one per incidence (phi_i outer)
  Grid spectra_;  // [phi_i][theta_i][wavelength] slices of res x res
  double scale_ = 1.0;
};

}  // namespace microsim
