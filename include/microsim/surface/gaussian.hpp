// Periodic Gaussian random heightfield with Beckmann slope statistics.
#pragma once
#include <cstdint>

#include "microsim/surface/microsurface.hpp"

namespace microsim {

struct GaussianParams {
  int resolution = 1024;            // grid cells per side (square tile)
  double size = 1.0;                // tile side length L (heights in the same unit)
  double correlation_length = 0.0;  // of the Gaussian autocorrelation exp(-r^2/l^2); 0 = default
  double alpha_x = 0.5;             // Beckmann roughness: slope variance per axis alpha^2/2
  double alpha_y = 0.5;
  std::uint64_t seed = 1;
};

// The correlation length used when none is given: 16 cells per l, the grid on which the
// discretization study (docs/theory/discretization.md) finds the mirror albedos of orders 1-3, D,
// G1 and the VNDF equal to 32 cells per l within their errors; but at least 16 correlation
// lengths per tile (the study's smallest tile) and at least 4 cells per l. The default 1024^2
// tile gets 16 cells per l and 64 l per tile, the study's recommended level; a 64^2 tile 4 cells.
double default_correlation_length(int resolution, double size);

// Validates the parameters (UsageError naming the option and its accepted range), including a
// memory estimate made before anything is allocated.
void validate(const GaussianParams& p);
// Peak bytes of generating a tile of this resolution and writing it (for the refusal above;
// generate_gaussian_ggx refuses on its own, larger, estimate). A measurement checks its own
// costs when it loads the tile.
double gaussian_memory_estimate(int resolution);
double gaussian_ggx_memory_estimate(int resolution);

// Heights h = F^-1[ sqrt(S(k)) F[w] ], w white Gaussian noise, S the spectrum of the Gaussian
// autocorrelation. The tile is exactly periodic. Heights are scaled so that the *expected*
// variance of the triangle slopes (finite differences, as traced) is alpha^2/2 per axis, so
// the nominal NDF is Beckmann(alpha_x, alpha_y) [Heitz14, Sec. 3.3]; one tile's realised variance
// fluctuates around it, which is the between-surface error of docs/theory/error-bars.md.
Microsurface generate_gaussian(const GaussianParams& p);

// gaussian-ggx: a periodic heightfield whose pooled NDF is GGX(alpha), from the identity
// GGX(alpha) = int_0^inf Beckmann(alpha / sqrt(E)) e^-E dE (the GGX slope density is this
// scale mixture of Gaussians). A Gaussian field g of unit Beckmann roughness (short correlation
// length l) is multiplied by a local roughness alpha / sqrt(E(x)) that varies slowly (correlation
// length L >> l); E(x) is the rank transform of a smooth Gaussian field onto the exact Exp(1)
// quantiles, so that over the tile E has exactly the Exp(1) distribution. E is floored at
// -ln(1 - tail_fraction): the roughest tail_fraction of the area has its local roughness capped
// (GGX has infinite slope variance; a finite tile cannot). The product adds the slope term
// g grad(alpha_local), of relative size ~ l / L.
struct GaussianGgxParams {
  int resolution = 1024;
  double size = 1.0;
  double correlation_length = 0.0;            // l of g; 0 = default_correlation_length
  double roughness_correlation_length = 0.0;  // L of E(x); 0 = min(16 l, size/4)
  double alpha_x = 0.5, alpha_y = 0.5;
  double tail_fraction = 1e-3;
  std::uint64_t seed = 1;
};
Microsurface generate_gaussian_ggx(const GaussianGgxParams& p);

}  // namespace microsim
