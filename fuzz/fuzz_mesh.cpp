// Meshes with their JSON sidecar: OpenMesh's PLY/OBJ/OFF readers, the manifold and rim checks,
// and the sidecar (macrosurface, description, nominal NDF).
// Input: 1 byte format (ply, obj, off), then MESH "\n--sidecar--\n" SIDECAR_JSON (no separator:
// no sidecar, the macrosurface is derived from the mesh).
#include "fuzz_common.hpp"
#include "microsim/surface/surface_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExt[3] = {"ply", "obj", "off"};
  const std::string name = std::string("mesh.") + kExt[data[0] % 3];
  const std::string_view in(reinterpret_cast<const char*>(data + 1), size - 1);
  const std::size_t sep = in.find("\n--sidecar--\n");
  const std::string path = microsim::fuzz::write_file(name, in.substr(0, sep));
  if (sep != std::string_view::npos)
    microsim::fuzz::write_file(name + ".json", in.substr(sep + 13));
  else
    microsim::fuzz::remove_file(name + ".json");
  microsim::fuzz::expect_only<microsim::UsageError>([&] { microsim::load_surface(path); });
  return 0;
}
