// A BsdfRequest resolved against its surface into what the measurement takes
// (measure/bsdf_table.hpp BsdfTableOptions): the checks that need the surface, and the table's
// options (the material and indices of api/bsdf_request.hpp, the counts, the incidences).
#pragma once
#include <string>

#include "microsim/api/bsdf_request.hpp"
#include "microsim/measure/bsdf_table.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// The checks that need the surface: the renderer tables need a periodic tile, and an anisotropic
// surface needs azimuths over the full circle (`name`: the surface file, for messages).
void check_bsdf_surface(const BsdfRequest& request, const Microsurface& s, const std::string& name);
// The table's options for a checked request (`split`: shards and MPI ranks, or nullptr).
BsdfTableOptions bsdf_table_options(const BsdfRequest& request, const Microsurface& s,
                                    TallySplit* split = nullptr);

}  // namespace microsim
