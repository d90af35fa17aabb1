// A run of a BsdfRequest: the surface loaded and checked, every incidence measured
// (measure/bsdf_table.hpp), the record built and the table files written.
#pragma once
#include <string>

#include "microsim/api/bsdf_request.hpp"

namespace microsim {

// The record's path for an output `path`: itself for .json, else the same name with .json (the
// record goes beside the table).
std::string bsdf_record_path(const std::string& path);

// A run of the request: the record and what the command line prints beside it.
struct BsdfRun {
  Json record;
  bool nominal_ndf = false;  // the surface has a nominal NDF (the microfacet models are beside)
  double seconds = 0.0;      // the walks' time over every incidence
};

// Checks the request, loads and checks the surface, measures every incidence and returns the
// record (command "measure bsdf"). A table format (exr, bsdf, binary, pbsdf) is written to
// `table_path` and adds its fields to the record; the EXR header names bsdf_record_path(table_path).
BsdfRun run_bsdf_request(const BsdfRequest& r, const RunContext& ctx, const std::string& table_path = "");
// The record of run_bsdf_request.
Json measure_bsdf_record(const BsdfRequest& r, const RunContext& ctx, const std::string& table_path = "");

}  // namespace microsim
