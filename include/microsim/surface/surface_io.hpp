// Saving and loading microsurfaces: heightfields as single-channel float EXR with every
// parameter in the header; any surface as a PLY/OBJ/OFF mesh (OpenMesh) with a JSON sidecar
// "FILE.json" that keeps the macrosurface and the generator's description.
#pragma once
#include <string>

#include "microsim/surface/microsurface.hpp"

namespace microsim {

// Format chosen by extension: .exr (heightfields only), .ply, .obj, .off.
void save_surface(const Microsurface& s, const std::string& path);
// Throws UsageError with a one-line message for a missing, unreadable or corrupt file.
Microsurface load_surface(const std::string& path);
// load_surface, except that with allow_window a heightfield saved as a non-periodic window is
// returned (as a grid whose description has "boundary": "window") instead of refused: the
// metrology of `info` reads it as it is, the estimators load it with its guard band. is_window
// (surface/microsurface.hpp) tells such a surface.
Microsurface load_surface_or_window(const std::string& path, bool allow_window = false);
// UsageError "NAME: ..." unless every reader would accept `s` once saved: the macrosurface
// fields in the ranges load_surface checks, and for meshes the checks of check_mesh (no
// degenerate triangle, the rim, [GeomBSDF24, eq. 1b]).
void require_readable_surface(const Microsurface& s, const std::string& name);

// Converts a heightfield to a triangle mesh with the same facets (same triangulation).
Microsurface heightfield_to_mesh(const Microsurface& s);

}  // namespace microsim
