// The record of a BsdfRequest's run: the request's parameters beside the measured part
// (measure/bsdf_record.hpp: definitions, the incidences' tables and summaries).
#pragma once
#include <string>

#include "microsim/api/bsdf_request.hpp"
#include "microsim/measure/bsdf_record.hpp"

namespace microsim {

// The record of `measure bsdf` after its run header: file, surface, parameters, definitions,
// with one incidence its fields at the top level, and incidences.
void put_bsdf_record(Json& record, const BsdfRequest& request, const BsdfTable& t,
                     const Microsurface& s, const std::string& file);

}  // namespace microsim
