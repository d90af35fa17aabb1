// Point evaluation of the Smith random-walk BSDF (models/smith_random_walk.hpp): an unbiased
// estimator of f(o, i) cos(theta_o) at a given pair of directions (the stochastic evaluation of
// [Heitz16]): walk from i; at every scattering event add the density that the event sends the path toward
// o times the probability that it then leaves the surface unoccluded. The walk's exit
// directions have the density f cos(theta_o) (the walk tallies flux), so
//   f(o, i) cos(theta_o) = E[ sum_events  weight * p_event(v -> o) * C1(h')^Lambda(o) ],
// with p_event the phase function of the event:
//   reflection (mirror, conductor, dielectric from its own side):
//     F(v.m) D_v(m) / (4 v.m),                 m = normalize(v + o)      [GeomBSDF24, eq. 13b, 19b]
//   refraction from the medium below out to o (dielectrics):
//     (1 - F(v.m)) D_v(m) eta_o^2 |t.m| / (eta_i v.m + eta_o t.m)^2,  t = o seen from the lower
//     frame, m the refraction half vector ([GeomBSDF24, eq. 15b, 20b]; [Walter07, eq. 17]),
// where D_v(m) = max(0, v.m) D(m) / proj(v) is the density of the facet normals that the
// arriving ray meets [Heitz14, eq. 13], proj(v) = v.z (1 + Lambda(v)) for v.z > 0 and |v.z| Lambda(-v)
// below the horizon, and h' the height in the frame of the medium o lies in. For the mirror this
// counts every order; the first event alone gives D G2 / (4 i.z) with the height-correlated G2
// [Heitz14, eq. 21], the single-scattering BRDF (tests check both).
#pragma once

#include <cmath>

#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/models/smith_random_walk.hpp"

namespace microsim::models {

// Density of the normals met by a ray arriving from -v (any v with v.z != 0), per solid angle.
inline double met_normal_density(const Ndf& ndf, const Vec3& v, const Vec3& m) {
  const double vm = v.dot(m);
  if (!(vm > 0.0) || !(m.z() > 0.0) || v.z() == 0.0) return 0.0;
  const double proj = v.z() > 0.0 ? v.z() * (1.0 + ndf.Lambda(v)) : -v.z() * ndf.Lambda(-v);
  if (!(proj > 0.0)) return 0.0;
  return vm * ndf.D(m) / proj;
}

// The contribution toward o (real frame, o.z > 0) of one event of a walk (see the header).
inline double walk_event_toward(const SmithRandomWalk& model, const WalkVertex& e, const Vec3& o) {
  const Ndf& ndf = model.ndf();
  const Material& mat = model.material();
  const SmithHeights heights{model.heights()};
  if (e.above) {
    const Vec3 m = (e.v + o).normalized();
    const double d = met_normal_density(ndf, e.v, m);
    if (!(d > 0.0)) return 0.0;
    const double vm = e.v.dot(m);
    const double F = mat.reflectance(vm, true);
    const double escape = std::pow(heights.C1(e.h), ndf.Lambda(o));
    return e.weight * F * d / (4.0 * vm) * escape;
  }
  // Lower frame: leave by refraction into the medium above along o, i.e. along t = o mirrored.
  const Vec3 t = mirror_z(o);
  const double eta_i = mat.eta, eta_o = 1.0;  // near (material) and far (above) indices
  Vec3 m = -(eta_i * e.v + eta_o * t);
  const double len = m.norm();
  if (!(len > 0.0)) return 0.0;
  m /= len;
  if (m.z() < 0.0) m = -m;
  const double vm = e.v.dot(m), tm = t.dot(m);
  if (!(vm > 0.0) || !(tm < 0.0)) return 0.0;
  const double d = met_normal_density(ndf, e.v, m);
  if (!(d > 0.0)) return 0.0;
  const double F = mat.reflectance(vm, false);
  if (F >= 1.0) return 0.0;
  const double den = eta_i * vm + eta_o * tm;
  const double jac = eta_o * eta_o * std::abs(tm) / (den * den);  // d omega_m / d omega_t
  const double escape = std::pow(heights.C1(-e.h), ndf.Lambda(o));  // height seen from above
  return e.weight * (1.0 - F) * d * jac * escape;
}

// One sample of the estimator of f(o, i) cos(theta_o) (reflection: i.z > 0, o.z > 0); `orders`
// > 0 keeps the first `orders` events only (1: the single-scattering BRDF).
template <class Rng>
double smith_walk_eval_cos(const SmithRandomWalk& model, const Vec3& i, const Vec3& o, Rng& rng, int orders = 0) {
  if (!(i.z() > 0.0) || !(o.z() > 0.0)) return 0.0;
  double sum = 0.0;
  int k = 0;
  model.walk(i, rng, [&](const WalkVertex& e) {
    if (orders > 0 && ++k > orders) return;
    sum += walk_event_toward(model, e, o);
  });
  return sum;
}

}  // namespace microsim::models
