// Small surfaces built directly in tests: exact geometric cases.
#pragma once
#include <cmath>
#include <vector>

#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim::testing {

// A periodic Gaussian tile with Beckmann slopes (the estimators' statistical cases).
inline Microsurface beckmann_tile(int resolution, std::uint64_t seed, double alpha = 0.5) {
  GaussianParams p;
  p.resolution = resolution;
  p.correlation_length = 4.0 / resolution;  // 4 cells per l, as the estimator tests were set on
  p.alpha_x = p.alpha_y = alpha;
  p.seed = seed;
  return generate_gaussian(p);
}

// Flat periodic plane z = 0.
inline Microsurface flat_heightfield(int n = 16, double size = 1.0) {
  return Microsurface::heightfield(n, n, size, size, std::vector<float>(n * n, 0.0f));
}

// Periodic 1D V-grooves along y: a triangle wave in x with `period` cells per groove and facet
// normals (+-sin t, 0, cos t), tan t = slope.
inline Microsurface vgroove_heightfield(int period, int grooves, double facet_angle,
                                        int ny = 8) {
  const int nx = period * grooves;
  const double size = 1.0, dx = size / nx, slope = std::tan(facet_angle);
  std::vector<float> h(static_cast<std::size_t>(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      int k = i % period;
      double x = (k <= period / 2 ? k : period - k) * dx;  // distance from the valley
      h[static_cast<std::size_t>(j) * nx + i] = static_cast<float>(slope * x);
    }
  return Microsurface::heightfield(nx, ny, size, size * ny / nx, std::move(h));
}

// Smooth periodic bumps (sum of cosines on the tile's frequency lattice).
inline Microsurface bumpy_heightfield(int n, double amplitude) {
  std::vector<float> h(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double x = 2 * kPi * i / n, y = 2 * kPi * j / n;
      h[static_cast<std::size_t>(j) * n + i] = static_cast<float>(
          amplitude * (std::cos(3 * x + 0.3) * std::sin(2 * y) + 0.5 * std::cos(5 * x - 7 * y)));
    }
  return Microsurface::heightfield(n, n, 1.0, 1.0, std::move(h));
}

}  // namespace microsim::testing
