// Fresnel reflectance of a smooth interface [GeomBSDF24, eq. 8]: dielectric (real relative index, total
// internal reflection included) and conductor (complex index eta + i k), for s- and p-polarized
// and unpolarized light.
//
// Header-only, depends on nothing but the standard library.
//
// Conventions:
//   cos_i  = |cos| of the angle between the propagation direction and the interface normal, on
//            the side the light comes from ([GeomBSDF24]: theta_v; Fresnel is symmetric in the two sides,
//            [GeomBSDF24, after eq. 8c]).
//   n      = relative index of the far side over the near side (eta_t / eta_v in the notation of
//            [GeomBSDF24, eq. 8]; [GeomBSDF24] writes F(theta_v, eta_v / eta_t), i.e. the argument is 1 / n).
//            Conductors: n = eta + i k relative to the medium the light comes from.
//   s / p  = polarization perpendicular / parallel to the plane of incidence (the physics
//            convention: R_p vanishes at Brewster's angle tan(theta_B) = n, R_s never does).
//            Note: [GeomBSDF24, eq. 8b] prints the two closed forms under swapped labels; its "R_p"
//            |sin(tv - tt) / sin(tv + tt)|^2 is the s-reflectance here, and its "R_s"
//            |(sin 2tv - sin 2tt) / (sin 2tv + sin 2tt)|^2 = |tan(tv - tt) / tan(tv + tt)|^2 is the
//            p-reflectance (the one with a Brewster zero). The unpolarized average is unaffected.
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>

namespace microsim::models {

struct FresnelReflectance {
  double Rs = 1.0;  // s-polarized (perpendicular) power reflectance
  double Rp = 1.0;  // p-polarized (parallel) power reflectance
  // [GeomBSDF24, eq. 8a]: F = (1 - a) R_s + a R_p, a = 0 s-polarized, 1 p-polarized, 1/2 unpolarized.
  double polarized(double a) const { return (1.0 - a) * Rs + a * Rp; }
  double unpolarized() const { return 0.5 * (Rs + Rp); }
};

// Cosine of the refraction angle ([GeomBSDF24, eq. 8c]: sin_t = sin_i / n), or -1 under total internal
// reflection (sin_t > 1).
inline double fresnel_cos_transmitted(double cos_i, double n) {
  cos_i = std::clamp(std::abs(cos_i), 0.0, 1.0);
  const double sin2_t = (1.0 - cos_i * cos_i) / (n * n);
  if (sin2_t >= 1.0) return -1.0;
  return std::sqrt(1.0 - sin2_t);
}

// Dielectric interface, real n > 0 ([GeomBSDF24, eq. 8b] in the amplitude form
// r_s = (cos_i - n cos_t) / (cos_i + n cos_t), r_p = (n cos_i - cos_t) / (n cos_i + cos_t),
// algebraically identical to 8b by Snell's law 8c and finite at normal incidence, where 8b's
// ratios of sines are 0/0). Total internal reflection: R_s = R_p = 1.
inline FresnelReflectance fresnel_dielectric(double cos_i, double n) {
  cos_i = std::clamp(std::abs(cos_i), 0.0, 1.0);
  const double cos_t = fresnel_cos_transmitted(cos_i, n);
  if (cos_t < 0.0) return {1.0, 1.0};
  const double rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
  const double rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
  return {rs * rs, rp * rp};
}

// Unpolarized dielectric reflectance (the walk's Fresnel: light is unpolarized, [GeomBSDF24, eq. 8a], a = 1/2).
inline double fresnel_dielectric_unpolarized(double cos_i, double n) {
  return fresnel_dielectric(cos_i, n).unpolarized();
}

// Power transmittance of a dielectric interface computed from the transmitted amplitudes
// t_s = 2 cos_i / (cos_i + n cos_t), t_p = 2 cos_i / (n cos_i + cos_t), T = (n cos_t / cos_i) |t|^2.
// Independent of the reflectance formulas: R + T = 1 is then a check of both (energy).
inline FresnelReflectance fresnel_dielectric_transmittance(double cos_i, double n) {
  cos_i = std::clamp(std::abs(cos_i), 0.0, 1.0);
  const double cos_t = fresnel_cos_transmitted(cos_i, n);
  if (cos_t < 0.0 || cos_i == 0.0) return {0.0, 0.0};
  const double ts = 2.0 * cos_i / (cos_i + n * cos_t);
  const double tp = 2.0 * cos_i / (n * cos_i + cos_t);
  const double k = n * cos_t / cos_i;
  return {k * ts * ts, k * tp * tp};
}

// Conductor (or any absorbing medium) with complex relative index n = eta + i k, k >= 0:
// with w = n cos_t = sqrt(n^2 - sin_i^2) (principal branch, Re w >= 0, Im w >= 0),
// r_s = (cos_i - w) / (cos_i + w), r_p = (n^2 cos_i - w) / (n^2 cos_i + w). k = 0 reduces to the
// dielectric formulas (total internal reflection included: w is then imaginary and |r| = 1).
inline FresnelReflectance fresnel_conductor(double cos_i, double eta, double k) {
  using C = std::complex<double>;
  cos_i = std::clamp(std::abs(cos_i), 0.0, 1.0);
  const C n(eta, k);
  const C n2 = n * n;
  const C w = std::sqrt(n2 - C(1.0 - cos_i * cos_i, 0.0));
  const C rs = (C(cos_i, 0.0) - w) / (C(cos_i, 0.0) + w);
  const C rp = (n2 * cos_i - w) / (n2 * cos_i + w);
  return {std::norm(rs), std::norm(rp)};
}

}  // namespace microsim::models
