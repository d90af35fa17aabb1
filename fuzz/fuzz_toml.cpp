// TOML presets through the function every command uses for --config (cli::apply_preset): the
// library's preset reader (io/preset_file.hpp), key lookup and each option's own validator. The command
// here has one option of every kind the real commands declare (bounded number, integer, seed,
// flag, free string, comma list); the preset is applied after an empty command line, as
// `microsim generate KIND --config FILE` does.
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

#include "../src/cli/option_checks.hpp"
#include "microsim/common.hpp"
#include "fuzz_common.hpp"

namespace cli = microsim::cli;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path =
      microsim::fuzz::write_file("preset.toml", std::string_view(reinterpret_cast<const char*>(data), size));
  double alpha = 0.5;
  long long resolution = 64;
  std::uint64_t seed = 1;
  bool periodic = false;
  std::string ndf = "beckmann", normal = "0,0,1";
  CLI::App cmd{"preset target", "gaussian"};
  cmd.add_option("--alpha", alpha)->check(cli::number_in(microsim::open_closed(0, 10)));
  cmd.add_option("--resolution", resolution)->check(cli::integer_in(4, 32768));
  cmd.add_option("--seed", seed)->check(cli::seed_value());
  cmd.add_option("--size", alpha)->check(cli::finite_number());
  cmd.add_flag("--periodic", periodic);
  cmd.add_option("--ndf", ndf);
  cmd.add_option("--normal", normal);
  cli::add_preset_option(cmd, "preset");
  // Every refusal is the usage error naming the file (exit 2).
  microsim::fuzz::expect_only<microsim::UsageError>([&] {
    cmd.parse(std::vector<std::string>{path, "--config"});  // CLI11 takes the arguments reversed
    cli::apply_preset(cmd);
  });
  return 0;
}
