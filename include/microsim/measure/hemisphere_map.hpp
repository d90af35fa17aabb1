// The equal-area hemisphere map the BSDF tallies bin outgoing directions on (measure/bsdf_measure.hpp),
// and the atan2 it bins with. Defined in src/measure/bsdf_measure.cpp.
#pragma once
#include <vector>

#include "microsim/common.hpp"

namespace microsim {

// Equal-area map of a hemisphere onto the square [-1, 1]^2, pixelated R x R:
// square (a, b) -> unit disk by the concentric map of Shirley and Chiu (r = max(|a|, |b|),
// phi = pi/4 b/a on |a| >= |b|, pi/2 - pi/4 a/b otherwise; area ratio pi/4 everywhere), then
// disk -> hemisphere by Lambert's azimuthal equal-area map (|z| = 1 - r^2, the horizontal part
// r sqrt(2 - r^2) (cos phi, sin phi)). Every pixel subtends 2 pi / R^2 sr. Pixel (i, j): column i
// covers a in [-1 + 2i/R, -1 + 2(i+1)/R], row j covers b likewise; x = +a direction is azimuth
// 0 (+x), b the azimuth 90 degrees (+y). The lower hemisphere uses the same map on (x, y, -z).
class HemisphereMap {
 public:
  explicit HemisphereMap(int resolution = 64);
  int resolution() const { return res_; }
  int size() const { return res_ * res_; }
  // Pixel of a direction (its |z| is used): j * R + i. Exactly the pixel of to_square(d), whose
  // azimuth is std::atan2's; decided with azimuth_near (no atan2) where the square coordinate is
  // further than `edge_margin` pixels from a pixel border and the azimuth further than
  // kSectorMargin from a sector border of the concentric map, else by pixel_of_exact.
  int pixel_of(const Vec3& d) const { return pixel_of(d, edge_margin_); }
  int pixel_of(const Vec3& d, double edge_margin) const;
  int pixel_of_exact(const Vec3& d) const;
  // Bounds for pixel_of: |azimuth_near - std::atan2| (see azimuth_near), the azimuth's distance
  // to a sector border, and (edge_margin_) a pixel border's distance in pixels:
  // R/2 (4/pi (kAzimuthError + 2e-15) + 4e-15), R = resolution, times 16.
  static constexpr double kAzimuthError = 1e-13;
  static constexpr double kSectorMargin = 2 * kAzimuthError;
  // Square coordinates (a, b) of a direction and back (z >= 0 returned).
  Vec2 to_square(const Vec3& d) const;
  Vec3 from_square(double a, double b) const;
  double pixel_solid_angle() const { return 2.0 * kPi / (static_cast<double>(res_) * res_); }
  // Exact int_pixel |cos theta| d omega (the integrand is piecewise quadratic in (a, b)).
  double pixel_cos_integral(int pixel) const { return cos_integral_[pixel]; }

 private:
  int res_;
  double edge_margin_;
  std::vector<double> cos_integral_;
};

// atan2(y, x) for finite (x, y) != (0, 0), within HemisphereMap::kAzimuthError of std::atan2
// (which is within 1 ulp of the true angle), on the same branch ((-pi, pi], the sign of y's
// sign bit): atan(t) = atan(c) + atan(u), t = min / max of |x|, |y|, c = round(16 t) / 16,
// u = (t - c) / (1 + c t), |u| <= 1/32, atan(u) by its series to u^9 (remainder below
// |u|^11 / 11 < 3e-18), atan(c) from a table of std::atan; the rounding of about a dozen
// operations adds a few 1e-16. Two divisions, no libm call.
double azimuth_near(double y, double x);

}  // namespace microsim
