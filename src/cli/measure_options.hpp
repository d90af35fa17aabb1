// What the ray estimators' commands (measure g1, g2, vndf) share on the command line: --rays and
// --seed (their requests are the library's, microsim/api/).
#pragma once
#include <string>

#include "cli_common.hpp"
#include "option_checks.hpp"

namespace microsim::cli {

// --rays (with its help) and --seed.
inline void add_rays_seed_options(CLI::App& cmd, long long& rays, std::uint64_t& seed, const std::string& rays_help) {
  cmd.add_option("--rays", rays, rays_help)->capture_default_str()->check(integer_in(1, kMaxRays));
  cmd.add_option("--seed", seed, "Random seed")->capture_default_str()->check(seed_value());
}

}  // namespace microsim::cli
