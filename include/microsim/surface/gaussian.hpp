// Periodic Gaussian random heightfield with Beckmann slope statistics.
#pragma once
#include <cstdint>

#include "microsim/surface/microsurface.hpp"

namespace microsim {

struct GaussianParams {
  int resolution = 1024;            // grid cells per side (square tile)
  double size = 1.0;                // tile side length L (heights in the same unit)
  double correlation_length = 0.0;  // of the Gaussian autocorrelation exp(-r^2/l^2); 0 = 4 cells
  double alpha_x = 0.5;             // Beckmann roughness: slope variance per axis alpha^2/2
  double alpha_y = 0.5;
  std::uint64_t seed = 1;
};

// Validates the parameters (UsageError naming the option and its accepted range), including a
// memory estimate made before anything is allocated.
void validate(const GaussianParams& p);
// Bytes needed to generate and trace a tile of this resolution (for the refusal above).
double gaussian_memory_estimate(int resolution);

// Heights h = F^-1[ sqrt(S(k)) F[w] ], w white Gaussian noise, S the spectrum of the Gaussian
// autocorrelation. The tile is exactly periodic. Heights are scaled so that the *expected*
// variance of the triangle slopes (finite differences, as traced) is alpha^2/2 per axis, so
// the nominal NDF is Beckmann(alpha_x, alpha_y) (001 Sec. 3.3); one tile's realised variance
// fluctuates around it, which is the between-surface error DESIGN.md asks to report.
Microsurface generate_gaussian(const GaussianParams& p);

}  // namespace microsim
