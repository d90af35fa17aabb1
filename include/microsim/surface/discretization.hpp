// How finely a random heightfield resolves the continuous surface it stands for: cells per
// correlation length (l / dx) and correlation lengths per tile (L / l), and the levels at which
// the discretization study (analysis/convergence.sh, docs/theory/discretization.md) found each
// reported quantity equal to the finest level within its error bar.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "microsim/common.hpp"

namespace microsim {

struct Discretization {
  double cells_per_correlation_length = 0;   // l / dx, of the shortest correlation length
  double correlation_lengths_per_tile = 0;   // L / l, of the longest correlation length
};

// From a surface description: its own fields when present, else derived from the generator
// parameters of a Gaussian heightfield (correlation_length[_x/_y], size, resolution; files
// written before the fields existed). None for surfaces without a correlation length.
std::optional<Discretization> discretization_of(const Json& description);

// Adds cells_per_correlation_length and correlation_lengths_per_tile to a description.
void add_discretization(Json& description, double dx, double size, double ell_short, double ell_long);

// The converged level of one group of quantities (`quantity` names the validate check:
// d_nominal, g1, g2, vndf, bsdf_albedo), measured on Beckmann alpha = 1 tiles.
struct ConvergedLevel {
  std::string quantity;
  double cells_per_correlation_length;
  double correlation_lengths_per_tile;
  std::string what;  // the finding, one line
};
const std::vector<ConvergedLevel>& converged_levels();
// The level of `quantity`, or none when the study does not cover it.
std::optional<ConvergedLevel> converged_level(const std::string& quantity);

}  // namespace microsim
