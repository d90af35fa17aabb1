// The table files of a BsdfRequest's run: the request's format, table resolution and the RGL
// file's description of the measurement handed to the writers of io/bsdf_files.hpp.
#pragma once
#include <string>

#include "microsim/api/bsdf_request.hpp"
#include "microsim/io/bsdf_files.hpp"

namespace microsim {

// The RGL .bsdf file's description: the surface, the material as the request names it, the
// wavelengths, the walks per incidence, the azimuths averaged and the seed.
std::string bsdf_rgl_description(const BsdfRequest& request, const Microsurface& s, const BsdfTable& t);

// Writes the table in the request's format to `path` (exr, bsdf, binary, pbsdf; json: nothing)
// and adds the record's "table" field for the renderer tables.
void write_bsdf_tables(const std::string& path, const BsdfRequest& request, const BsdfTable& t,
                       const Microsurface& s, Json& record, const std::string& json_path);

}  // namespace microsim
