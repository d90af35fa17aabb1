// Generators of structured microsurfaces (the exact references of the estimators).
#pragma once
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// flat: a periodic plane z = 0 (every estimator's exact reference: D a delta at n, G1 = 1,
// visible area ratio 1, Fresnel reflection and refraction only).
struct FlatParams {
  int resolution = 16;  // grid cells per side (the plane is exact at any resolution)
  double size = 1.0;
};
Microsurface generate_flat(const FlatParams& p);

}  // namespace microsim
