// Heightfield EXR files, byte by byte: OpenEXR's parser, then microsim's header (surface kind,
// macrosurface and description JSON, nominal NDF) and the heights.
#include "fuzz_common.hpp"
#include "microsim/surface/surface_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = microsim::fuzz::write_file(
      "surface.exr", {reinterpret_cast<const char*>(data), size});
  microsim::fuzz::expect_only<microsim::UsageError>([&] { microsim::load_surface(path); });
  return 0;
}
