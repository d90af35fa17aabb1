#include "microsim/surface/discretization.hpp"

#include <algorithm>
#include <cmath>

namespace microsim {

namespace {
double number(const Json& d, const char* key) {
  return d.contains(key) && d[key].is_number() ? d[key].get<double>() : 0.0;
}
}  // namespace

void add_discretization(Json& description, double dx, double size, double ell_short, double ell_long) {
  description["cells_per_correlation_length"] = ell_short / dx;
  description["correlation_lengths_per_tile"] = size / ell_long;
}

std::optional<Discretization> discretization_of(const Json& d) {
  if (!d.is_object()) return std::nullopt;
  const double c = number(d, "cells_per_correlation_length"), t = number(d, "correlation_lengths_per_tile");
  if (c > 0 && t > 0) return Discretization{c, t};
  // Older files: the generator parameters (square tiles of `resolution` cells of side `size`).
  const std::string kind = d.value("kind", std::string());
  if (kind != "gaussian" && kind != "gaussian-ggx") return std::nullopt;
  const double n = number(d, "resolution"), size = number(d, "size"), ell = number(d, "correlation_length");
  if (!(n > 0 && size > 0 && ell > 0)) return std::nullopt;
  const double lx = number(d, "correlation_length_x"), ly = number(d, "correlation_length_y");
  const double ell_long = std::max({ell, lx, ly});
  return Discretization{ell / (size / n), size / ell_long};
}

// Measured by analysis/convergence.sh on Beckmann alpha = 1 (the roughest preset, where the
// grid matters most): grids against 32 cells per l on the same tiles (paired), tiles against
// 128-256 l per tile. A group's level is the coarsest grid from which the group's quantities
// equal the reference within two standard errors (or 1% for albedos above 1e-3). G2 and the
// mirror albedos take the recommended level, 16 cells per l and 64 l per tile (the default
// 1024^2 tile): there mirror E2 and E3 at 0 and 60 deg, every order at 0-80 deg up to order 3 at
// 60 deg and G2 at equal azimuths are converged; three quantities still move by a few percent
// (G2 at opposite azimuths -0.7%, mirror order 3 at 80 deg +3%, order 4+ at 60 deg +4%), for
// which docs/findings/discretization.md points to 32 cells per l. Beckmann alpha = 0.2 and 0.5 and the GGX heightfield
// (alpha = 0.5, at its preset's 64 l per tile) need the same grid: at 16 cells per l every
// quantity of theirs is within its error or 1% of 32 but mirror order 4+ (1.5-3.5%) and, for
// Beckmann 0.5, G2 at 70/70 deg (-0.1 to -0.3%). docs/theory/discretization.md.
const std::vector<ConvergedLevel>& converged_levels() {
  static const std::vector<ConvergedLevel> levels = {
      {"d_nominal", 8, 32, "fitted alpha and D per ring"},
      {"g1", 8, 64, "averaged G1 and G1 per normal bin at 80 deg"},
      {"g2", 16, 64, "G2 at 70/70 deg; opposite azimuths still -0.7% at 16 cells per l (32 for those)"},
      {"vndf", 8, 32, "VNDF against the nominal D_v"},
      {"bsdf_albedo", 16, 64,
       "mirror albedo per order: orders 1-3 up to 60 deg; order 3 at 80 deg and 4+ move by 3-4% to 32 cells per l"},
  };
  return levels;
}

std::optional<ConvergedLevel> converged_level(const std::string& quantity) {
  for (const ConvergedLevel& l : converged_levels())
    if (l.quantity == quantity) return l;
  return std::nullopt;
}

}  // namespace microsim
