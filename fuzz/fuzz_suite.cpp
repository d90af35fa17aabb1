// Validation suite files (JSON with comments): fields, entries, options, presets, seeds.
#include "fuzz_common.hpp"
#include "microsim/validate/validate.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = microsim::fuzz::write_file(
      "suite.json", {reinterpret_cast<const char*>(data), size});
  microsim::fuzz::expect_only<microsim::UsageError>([&] { microsim::validation::load_suite(path); });
  return 0;
}
