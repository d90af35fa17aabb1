// A run of an AlbedoRequest: each surface loaded in turn and measured
// (measure/albedo_measure.hpp), the record built and the lookup table written.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "microsim/api/albedo_request.hpp"

namespace microsim {

struct AlbedoSurface;  // measure/albedo_measure.hpp

// A run of the request: the record and each surface's measurement (the lookup table's rows;
// shared, so that a run is whole without measure/albedo_measure.hpp).
struct AlbedoRun {
  Json record;
  std::shared_ptr<const std::vector<AlbedoSurface>> surfaces;
};

// Checks the request, measures each surface in turn (each loaded when its turn comes) and
// returns the record (command "measure albedo") with the measurements.
AlbedoRun run_albedo_request(const AlbedoRequest& r, const RunContext& ctx);
// The record of run_albedo_request.
Json measure_albedo_record(const AlbedoRequest& r, const RunContext& ctx);
// Writes a run to `output` by its format: .json the record; .csv the rows and the record beside
// (.json); .exr the lookup table, the rows beside (.csv) and the record (.json). Returns the
// paths written, in words ("lut.exr, lut.csv and lut.json").
std::string write_albedo_outputs(const std::string& output, const AlbedoRequest& r, const AlbedoRun& run);

}  // namespace microsim
