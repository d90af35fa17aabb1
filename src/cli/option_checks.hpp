// Option rules of the command line, all built on microsim/io/checks.hpp: CLI11 validators that
// refuse non-finite, out-of-range or wrapped-around values before the command runs, and TOML
// presets (--config FILE) applied to any command, keys checked against its options.
#pragma once
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <string_view>

#include "microsim/api/request_checks.hpp"
#include "microsim/common.hpp"
#include "microsim/io/checks.hpp"

namespace microsim::cli {

// A library parameter as the command line names it: its option, "--" and the name with '-' for
// '_' (theta_i: --theta-i), or the option of the few whose name differs (output: -o).
std::string option_spelling(std::string_view parameter);
// The text of a usage error as the command line prints it: its parameters named as options.
std::string cli_message(const UsageError& e);

// A finite number inside r ("--alpha: must be a finite number in (0, 10] (got -1)").
CLI::Validator number_in(const Range& r);
// Any finite number (the range is checked where the parameters are validated).
CLI::Validator finite_number();
// A decimal integer in [lo, hi].
CLI::Validator integer_in(long long lo, long long hi);
// --replicates of the Monte Carlo estimators (measure/replicates.hpp): at least 2.
void add_replicates_option(CLI::App& cmd, int& replicates);
// A seed: a decimal integer in [0, 2^64 - 1] (no negative values wrapping around).
CLI::Validator seed_value();

// Largest accepted --rays: the library's kMaxRays (microsim/api/request_checks.hpp).

// Adds --config FILE (a TOML preset of this command's options) to cmd.
void add_preset_option(CLI::App& cmd, const std::string& help);
// Applies cmd's --config preset, if given: the file is read by the library's preset reader
// (microsim/io/preset_file.hpp, as read_surface_preset reads it), every key must be one of cmd's
// long options, values go through the option's own validators, and options given on the command
// line win. UsageError naming the file, and the line and key where there is one.
void apply_preset(CLI::App& cmd);
// cmd's callback, after its preset is applied.
void on_run(CLI::App* cmd, std::function<void()> run);

}  // namespace microsim::cli
