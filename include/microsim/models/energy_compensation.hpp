// Energy-compensation models of the single-scattering microfacet BRDF (docs/theory/energy-compensation.md):
// the directional albedo E_ss(mu) of the height-correlated Smith BRDF with F = 1 and its cosine-weighted
// average E_avg, the Fresnel average F_avg of a conductor, the multiple-scattering lobe of Kulla and Conty
// [KullaConty17] and the albedo-scaled single-scattering lobe of Turquin [Turquin19].
//
// Conventions as in models/ndf.hpp (n = +z, directions away from the surface). Opaque reflection only.
#pragma once

#include <vector>

#include "microsim/models/microfacet_bsdf.hpp"

namespace microsim::models {

// E_ss(mu) = int f_ss(o, i) o.z d omega_o for light from i with i.z = mu, mirror facets (F = 1),
// height-correlated Smith G2 ([Heitz14, eq. 21]): the quintic-smoothed midpoint rule of
// single_scattering_albedos at n x n points (deterministic). mu is clamped to [kEssMuMin, 1].
constexpr double kEssMuMin = 1e-4;
double directional_albedo_ss(const Ndf& ndf, double mu, int n = 256);

// 2 int_0^1 g(mu) mu d mu by Gauss-Legendre on `segments` equal pieces of [0, 1], 8 nodes each.
template <class G>
double cosine_weighted_average(const G& g, int segments = 8);
// The same integral in s = sqrt(mu) (4 int_0^1 g(s^2) s^3 ds), 8 Gauss nodes on each of `segments` equal
// pieces of s: exact for g a cubic in s on every piece (the table below), and accurate for the sqrt(mu)
// behaviour of E_ss near grazing.
template <class G>
double cosine_weighted_average_sqrt(const G& g, int segments = 8);

// F_avg = 2 int_0^1 F(mu) mu d mu ([KullaConty17], "Fresnel" part of the multiple-scattering section):
// the unpolarized reflectance of the material's facets averaged over the cosine-weighted hemisphere.
// Mirror: 1.
double fresnel_average(const Material& material);

// E_ss tabulated on s_k = sqrt(mu_k) = k / (N - 1), k = 0 .. N - 1 (mu_0 evaluated at kEssMuMin), each node
// by directional_albedo_ss at quadrature resolution n; between nodes cubic Hermite in s (Catmull-Rom slopes,
// one-sided at the ends). Nodes uniform in sqrt(mu) because E_ss - 1 behaves like sqrt(mu) near grazing
// (GGX alpha = 1: E = 0.9991, 0.9931, 0.954 at mu = 1e-4, 1e-3, 1e-2), which a grid uniform in mu
// interpolates to only 1e-2. E_avg is the exact integral of the interpolant (cosine_weighted_average_sqrt on
// the table's intervals), so that the Kulla-Conty lobe built on this table integrates to 1 - E(mu_o) to
// rounding (its white furnace identity).
class EssTable {
 public:
  EssTable(const Ndf& ndf, int nodes = 65, int quadrature_n = 256);
  const Ndf& ndf() const { return ndf_; }
  int nodes() const { return static_cast<int>(e_.size()); }
  int quadrature_n() const { return n_; }
  double E(double mu) const;    // the interpolant, mu clamped to [0, 1]
  // Integral 2 int g(mu) mu dmu on the table's intervals in s (exact for g a cubic in s between nodes).
  template <class G>
  double average(const G& g) const { return cosine_weighted_average_sqrt(g, nodes() - 1); }
  double E_avg() const { return e_avg_; }
  // Largest |E_table - directional_albedo_ss| over the midpoints (in s) of the intervals (the interpolation
  // error at the points furthest from the nodes; both at the table's quadrature resolution), over the
  // intervals first .. N - 2. The first interval (mu < 1 / (N - 1)^2, within 0.9 degrees of grazing at N = 65)
  // holds the steepest part of E_ss and interpolates worst (GGX alpha = 1, N = 65: 3.3e-4 there).
  double interpolation_error(int first = 0) const;
  const std::vector<double>& values() const { return e_; }

 private:
  Ndf ndf_;
  int n_;
  std::vector<double> e_;
  double e_avg_ = 0.0;
};

// The Kulla-Conty multiple-scattering BRDF [KullaConty17]:
//   f_ms(o, i) = (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)),
// times, with Fresnel, F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)) (the series of the light that
// survives k >= 2 bounces of average albedo E_avg and average reflectance F_avg, over that of F = 1).
struct KullaContyLobe {
  const EssTable* table;
  double fresnel_factor = 1.0;  // F_ms (1 for a mirror)
  KullaContyLobe(const EssTable& t, const Material& material);
  static double fresnel_factor_of(double f_avg, double e_avg);
  double eval(const Vec3& o, const Vec3& i) const;
  // int f_ms(o, i) o.z d omega_o = F_ms (1 - E(mu_i)) (closed form of the lobe's energy).
  double albedo(double mu_i) const;
};

// Turquin's compensation [Turquin19]: f = f_ss (1 + F0 (1 - E(mu)) / E(mu)) with E the F = 1 albedo of the
// direction held fixed in the albedo integral (here the incidence i, the measured light direction; f_ss is
// reciprocal, so int f_ss(o, i) o.z d omega_o = E(mu_i)). Its multiple-scattering lobe is
// f_ss F0 (1 - E) / E. F0 = the facets' reflectance at normal incidence (1 for a mirror).
struct TurquinLobe {
  const EssTable* table;
  MicrofacetBsdf single;  // f_ss with the material's Fresnel, height-correlated Smith G2
  double F0 = 1.0;
  TurquinLobe(const EssTable& t, const Material& material);
  double scale(double mu_i) const;                 // F0 (1 - E(mu_i)) / E(mu_i)
  double eval(const Vec3& o, const Vec3& i) const;  // the multiple-scattering lobe only
};

// --- template definitions

namespace detail {
// 8-point Gauss-Legendre nodes and weights on [-1, 1].
inline constexpr double kGl8x[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                                    -0.1834346424956498, 0.1834346424956498,  0.5255324099163290,
                                    0.7966664774136267,  0.9602898564975363};
inline constexpr double kGl8w[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                                    0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                                    0.2223810344533745, 0.1012285362903763};
}  // namespace detail

template <class G>
double cosine_weighted_average(const G& g, int segments) {
  double s = 0.0;
  const double h = 1.0 / segments;
  for (int k = 0; k < segments; ++k)
    for (int q = 0; q < 8; ++q) {
      const double mu = h * (k + 0.5 * (detail::kGl8x[q] + 1.0));
      s += 0.5 * h * detail::kGl8w[q] * g(mu) * mu;
    }
  return 2.0 * s;
}

template <class G>
double cosine_weighted_average_sqrt(const G& g, int segments) {
  double sum = 0.0;
  const double h = 1.0 / segments;
  for (int k = 0; k < segments; ++k)
    for (int q = 0; q < 8; ++q) {
      const double s = h * (k + 0.5 * (detail::kGl8x[q] + 1.0));
      sum += 0.5 * h * detail::kGl8w[q] * g(s * s) * s * s * s;
    }
  return 4.0 * sum;
}

}  // namespace microsim::models
