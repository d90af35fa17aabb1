// Thin command-line layer: option structs, and one function per command that calls the
// library and writes the outputs.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "microsim/surface/gaussian.hpp"

namespace microsim::cli {

struct GlobalOptions {
  int threads = 0;  // 0 = all cores
  bool quiet = false;
};

struct GenerateOptions {
  std::string output;
  GaussianParams gaussian;
  double alpha = -1;  // isotropic shorthand; -1 = not given
  bool alpha_x_given = false, alpha_y_given = false;
};

struct MeasureOptions {
  std::string surface, output;
  std::vector<std::string> extra_surfaces;  // measure g1: an ensemble of independent surfaces
  std::string theta = "0:85:5", phi = "0";
  long long rays = 1000000;
  std::uint64_t seed = 1;
  int theta_bins = 90, phi_bins = 72;
};

// Parses "a:b:step" (inclusive) or "a,b,c" or "a" into a list of values in degrees.
std::vector<double> parse_angle_list(const std::string& text, const std::string& option);

int run_generate_gaussian(GenerateOptions o, const GlobalOptions& g);
int run_convert(const std::string& input, const std::string& output, const GlobalOptions& g);
int run_info(const std::string& surface, const std::string& json_out, const GlobalOptions& g);
int run_measure_ndf(const MeasureOptions& o, const GlobalOptions& g);
int run_measure_g1(const MeasureOptions& o, const GlobalOptions& g);
// generate + measure ndf + measure g1 into `dir`, printing both tables.
int run_demo(GenerateOptions gen, MeasureOptions meas, const std::string& dir,
             const GlobalOptions& g);

}  // namespace microsim::cli
