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

// Complex Fresnel amplitudes of one interface (models/mueller.hpp builds Mueller matrices from
// them). Frames: s = the unit vector normal to the plane of incidence, the same vector for the
// incident, reflected and transmitted waves; p = (propagation direction) x s for each wave
// ((s, p, propagation) right-handed). In these bases the reflected field is (r_s E_s, r_p E_p),
// the transmitted one (t_s E_s, t_p E_p). This is the convention in which r_p = -r_s at normal
// incidence (Verdet's sign of r_p). Time dependence exp(-i omega t): an absorbing medium has
// n = eta + i k, k >= 0.
struct FresnelAmplitudes {
  std::complex<double> rs{-1.0, 0.0}, rp{1.0, 0.0};  // reflection (a perfect mirror by default)
  std::complex<double> ts{0.0, 0.0}, tp{0.0, 0.0};   // transmission (dielectrics, no total reflection)
  double cos_t = -1.0;  // cosine of the refraction angle; -1 under total internal reflection or for conductors
};

// Dielectric interface, real relative index n > 0: the amplitudes behind fresnel_dielectric and
// fresnel_dielectric_transmittance (|r_s|^2 and |r_p|^2 are their R_s and R_p to rounding). Under
// total internal reflection n cos_t = i sqrt(sin_i^2 - n^2) (the root of an evanescent wave that
// decays away from the interface for exp(-i omega t)), so |r_s| = |r_p| = 1 with phases.
inline FresnelAmplitudes fresnel_dielectric_amplitudes(double cos_i, double n) {
  using C = std::complex<double>;
  cos_i = std::clamp(std::abs(cos_i), 0.0, 1.0);
  FresnelAmplitudes a;
  const double cos_t = fresnel_cos_transmitted(cos_i, n);
  if (cos_t < 0.0) {
    const double sin2_i = 1.0 - cos_i * cos_i;
    const C w(0.0, std::sqrt(std::max(0.0, sin2_i - n * n)));  // n cos_t
    const C n2cos(n * n * cos_i, 0.0);
    a.rs = (C(cos_i, 0.0) - w) / (C(cos_i, 0.0) + w);
    a.rp = (n2cos - w) / (n2cos + w);
    a.ts = a.tp = 0.0;
    a.cos_t = -1.0;
    return a;
  }
  a.rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
  a.rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
  a.ts = 2.0 * cos_i / (cos_i + n * cos_t);
  a.tp = 2.0 * cos_i / (n * cos_i + cos_t);
  a.cos_t = cos_t;
  return a;
}

// Conductor (or any absorbing medium) with complex relative index n = eta + i k, k >= 0:
// with w = n cos_t = sqrt(n^2 - sin_i^2) (principal branch, Re w >= 0, Im w >= 0),
// r_s = (cos_i - w) / (cos_i + w), r_p = (n^2 cos_i - w) / (n^2 cos_i + w). k = 0 reduces to the
// dielectric formulas (total internal reflection included: w is then imaginary and |r| = 1).
inline FresnelAmplitudes fresnel_conductor_amplitudes(double cos_i, double eta, double k) {
  using C = std::complex<double>;
  cos_i = std::clamp(std::abs(cos_i), 0.0, 1.0);
  const C n(eta, k);
  const C n2 = n * n;
  const C w = std::sqrt(n2 - C(1.0 - cos_i * cos_i, 0.0));
  FresnelAmplitudes a;
  a.rs = (C(cos_i, 0.0) - w) / (C(cos_i, 0.0) + w);
  a.rp = (n2 * cos_i - w) / (n2 * cos_i + w);
  return a;
}

// Power reflectances of the conductor: |r_s|^2 and |r_p|^2 of fresnel_conductor_amplitudes.
inline FresnelReflectance fresnel_conductor(double cos_i, double eta, double k) {
  const FresnelAmplitudes a = fresnel_conductor_amplitudes(cos_i, eta, k);
  return {std::norm(a.rs), std::norm(a.rp)};
}

}  // namespace microsim::models
