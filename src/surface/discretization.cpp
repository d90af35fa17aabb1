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
// grid matters most): the coarsest level at which every quantity of the group equals the
// finest level within its error bar (or 1% for albedos above 1e-3). README "Converged surfaces".
const std::vector<ConvergedLevel>& converged_levels() {
  static const std::vector<ConvergedLevel> levels = {
      {"d_nominal", 8, 32, "fitted alpha and D per ring"},
      {"g1", 8, 32, "averaged G1 and G1 per normal bin at 80 deg"},
      {"g2", 8, 32, "G2 at 70/70 deg"},
      {"vndf", 8, 32, "VNDF against the nominal D_v"},
      {"bsdf_albedo", 8, 32, "mirror albedo per scattering order"},
  };
  return levels;
}

std::optional<ConvergedLevel> converged_level(const std::string& quantity) {
  for (const ConvergedLevel& l : converged_levels())
    if (l.quantity == quantity) return l;
  return std::nullopt;
}

}  // namespace microsim
