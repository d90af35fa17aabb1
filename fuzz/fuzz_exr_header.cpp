// The microsim header of a heightfield EXR, structure-aware: a valid EXR is written with the
// fuzzed text as its "microsim_macrosurface" and "microsim_description" attributes and a small
// fuzzed grid, so that mutations reach the JSON header checks rather than OpenEXR's parser.
// Input: 2 bytes (width, height, each 1..16), then MACRO_JSON "\n--\n" DESCRIPTION_JSON.
#include <cstring>

#include "fuzz_common.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/surface_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  microsim::ExrTable t;
  t.width = 1 + data[0] % 16;
  t.height = 1 + data[1] % 16;
  const auto [macro, description] =
      microsim::fuzz::split({reinterpret_cast<const char*>(data + 2), size - 2}, "\n--\n");
  t.channel_names = {"Z"};
  std::vector<float> z(static_cast<std::size_t>(t.width) * t.height);
  for (std::size_t k = 0; k < z.size(); ++k) z[k] = 0.01f * static_cast<float>(k % 7);
  t.channels = {z};
  t.attributes["microsim_surface"] = "heightfield";
  t.attributes["microsim_macrosurface"] = std::string(macro);
  t.attributes["microsim_description"] = std::string(description);
  const std::string path = (microsim::fuzz::work_dir() / "header.exr").string();
  microsim::write_exr(path, t);
  microsim::fuzz::expect_only<microsim::UsageError>([&] { microsim::load_surface(path); });
  return 0;
}
