// The files of an AlbedoRequest's run: its record (the request's parameters before the measured
// part, measure/albedo_measure.hpp put_albedo_results) and the lookup table E(mu, alpha).
#pragma once
#include <vector>

#include "microsim/api/albedo_request.hpp"
#include "microsim/measure/albedo_measure.hpp"

namespace microsim {

// The record of `measure albedo` after its run header: file, parameters, then quadrature,
// definitions, surfaces, rows (per node) and averages (E_avg per series).
void put_albedo_record(Json& record, const AlbedoRequest& request, const std::vector<AlbedoSurface>& surfaces);

// The lookup table of the request's surfaces (measure/albedo_measure.hpp albedo_lut_exr on the
// request's quadrature, its header naming the request's material, rays and orders).
ExrTable albedo_lut_exr(const AlbedoRequest& request, const std::vector<AlbedoSurface>& surfaces);

}  // namespace microsim
