// What the ray estimators' commands (measure g1, g2, vndf) share: --rays and --seed, the
// estimator options they set, and the start of the record.
#pragma once
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "option_checks.hpp"

namespace microsim::cli {

// --rays (with its help) and --seed.
inline void add_rays_seed_options(CLI::App& cmd, long long& rays, std::uint64_t& seed, const std::string& rays_help) {
  cmd.add_option("--rays", rays, rays_help)->capture_default_str()->check(integer_in(1, kMaxRays));
  cmd.add_option("--seed", seed, "Random seed")->capture_default_str()->check(seed_value());
}

// An estimator's options (G1Options, G2Options, VndfOptions) with the rays, the seed and the
// shards/MPI split (scaleout.hpp) of the command.
template <class Options>
Options estimator_options(long long rays, std::uint64_t seed, const GlobalOptions& g) {
  Options o;
  o.split = g.split;
  o.rays = static_cast<std::uint64_t>(rays);
  o.seed = seed;
  return o;
}

// The record's first fields: run_header, then "file" (a string, or the list of an ensemble).
inline Json measure_record(const std::string& command, const std::vector<std::string>& files, const GlobalOptions& g) {
  Json j = run_header(command, g);
  j["file"] = files.size() == 1 ? Json(files[0]) : Json(files);
  return j;
}

}  // namespace microsim::cli
