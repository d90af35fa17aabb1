// TOML presets as CLI11 reads them for --config (CLI::ConfigTOML): sections, keys, values,
// arrays, quoting. The items are then looked at as a command would (name, parents, inputs).
#include <CLI/CLI.hpp>

#include <cstdint>
#include <sstream>
#include <string>

#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  // CLI11 reports a malformed file with a ParseError (exit 2 naming the file).
  microsim::fuzz::expect_only<CLI::ParseError>([&] {
    const std::vector<CLI::ConfigItem> items = CLI::ConfigTOML().from_config(in);
    std::size_t total = 0;
    for (const CLI::ConfigItem& item : items) {
      total += item.fullname().size();
      for (const std::string& v : item.inputs) total += v.size();
    }
    (void)total;
  });
  return 0;
}
