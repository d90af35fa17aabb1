// Angle lists of --theta/--phi options: "a", "a,b,c" or "start:stop:step" in degrees.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "../src/cli/cli_common.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  microsim::fuzz::expect_only<microsim::UsageError>([&] {
    const std::vector<double> angles = microsim::cli::parse_angle_list(text, "--theta");
    if (angles.empty()) std::abort();  // an empty list is refused
    for (double a : angles)
      if (!std::isfinite(a)) std::abort();
  });
  return 0;
}
