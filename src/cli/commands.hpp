// Options and run functions shared between commands (demo chains generate and measure).
#pragma once
#include <CLI/CLI.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "microsim/surface/surface_spec.hpp"

namespace microsim::cli {

// A surface kind's options on a command (generate KIND, demo), registered from the library's
// table (surface/surface_spec.hpp): values as text, flags as bools.
struct SurfaceOptionValues {
  std::map<std::string, std::string> text;
  std::map<std::string, bool> flags;
  std::map<std::string, CLI::Option*> options;
};
void add_surface_options(CLI::App& cmd, const SurfaceKind& kind, SurfaceOptionValues& v);
// The options given (on the command line or in the preset) as a request.
SurfaceRequest given_surface_options(const SurfaceKind& kind, const SurfaceOptionValues& v);
// Generates the surface, saves it at `path` and prints.
void write_generated(const SurfaceRequest& r, const std::string& path, const GlobalOptions& g);

struct MeasureOptions {
  std::string surface, output;
  std::vector<std::string> extra_surfaces;  // measure g1: an ensemble of independent surfaces
  std::string theta = "0:85:5", phi = "0";
  long long rays = 1000000;
  std::uint64_t seed = 1;
  int replicates = 32;  // measure g1: independent replicates (standard errors)
  int theta_bins = 90, phi_bins = 72;
};

int run_measure_ndf(const MeasureOptions& o, const GlobalOptions& g);
int run_measure_g1(const MeasureOptions& o, const GlobalOptions& g);

}  // namespace microsim::cli
