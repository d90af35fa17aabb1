#include "microsim/surface/generators.hpp"

namespace microsim {

Microsurface generate_flat(const FlatParams& p) {
  if (p.resolution < 1 || p.resolution > 4096)
    throw UsageError("--resolution must be in [1, 4096] for flat (got " +
                     std::to_string(p.resolution) + ")");
  if (!(p.size > 0)) throw UsageError("--size must be > 0");
  Microsurface s = Microsurface::heightfield(
      p.resolution, p.resolution, p.size, p.size,
      std::vector<float>(static_cast<std::size_t>(p.resolution) * p.resolution, 0.0f));
  s.description = {{"kind", "flat"}, {"resolution", p.resolution}, {"size", p.size}};
  return s;
}

}  // namespace microsim
