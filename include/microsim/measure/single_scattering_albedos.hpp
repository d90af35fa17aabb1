// The single-scattering albedo models of a bsdf measurement (height-correlated Smith and V-cavity G2, one
// quadrature for both, models/microfacet_bsdf.hpp single_scattering_albedos), run on TBB's threads and with
// the quadrature's resolution chosen for the accuracy the measurement needs.
#pragma once

#include "microsim/models/microfacet_bsdf.hpp"

namespace microsim {

// single_scattering_albedos with the rows on TBB's threads; bit-identical to the sequential function
// (the rows' terms are summed in a fixed order), whatever the number of threads.
models::SingleScatteringAlbedos parallel_single_scattering_albedos(const models::Ndf& ndf, const models::Material& material,
                                                                   const models::Vec3& i, int n);

// The albedos at the smallest resolution n (doubling from 4 min_n) whose estimated quadrature error is at most
// target_error, or at max_n. The smoothed midpoint rule's error (microfacet_bsdf.hpp albedo_node) decreases at
// least like 1/n, so the error at n is at most about the change from n / 2, and half the change from n / 4 to
// n / 2; the larger of the two (over Smith, V-cavity x reflected, transmitted), doubled because the
// convergence is irregular:
//   estimated_error = 2 max(|A(n) - A(n/2)|, |A(n/2) - A(n/4)| / 2).
// Not a guarantee: on the plain (unsmoothed) square, where the error decreased much more slowly than 1/n
// (Beckmann alpha = 0.2, mirror, theta_i <= 20 deg) it underestimated up to 10x; the tests bound the smoothed
// rule's estimate against n = 4096 in their cases.
// target_error <= 0 (or not finite) asks for max_n.
struct AlbedoQuadrature {
  models::SingleScatteringAlbedos albedos;
  int n = 0;                     // the resolution of the result (n x n samples)
  double estimated_error = 0.0;  // see above
  double target_error = 0.0;
};
AlbedoQuadrature single_scattering_albedos_to_error(const models::Ndf& ndf, const models::Material& material,
                                                    const models::Vec3& i, double target_error, int min_n = 32,
                                                    int max_n = 1024);

}  // namespace microsim
