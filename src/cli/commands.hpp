// Options and run functions shared between commands (demo chains generate and measure).
#pragma once
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "microsim/surface/gaussian.hpp"

namespace microsim::cli {

struct GenerateOptions {
  std::string output;
  GaussianParams gaussian;
  double alpha = 0.5;  // isotropic shorthand, used when alpha_given
  bool alpha_given = false, alpha_x_given = false, alpha_y_given = false;
};
void add_gaussian_options(CLI::App& cmd, GenerateOptions& go);

struct MeasureOptions {
  std::string surface, output;
  std::vector<std::string> extra_surfaces;  // measure g1: an ensemble of independent surfaces
  std::string theta = "0:85:5", phi = "0";
  long long rays = 1000000;
  std::uint64_t seed = 1;
  int theta_bins = 90, phi_bins = 72;
};

int run_generate_gaussian(GenerateOptions o, const GlobalOptions& g);
int run_measure_ndf(const MeasureOptions& o, const GlobalOptions& g);
int run_measure_g1(const MeasureOptions& o, const GlobalOptions& g);

}  // namespace microsim::cli
