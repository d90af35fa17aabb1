// An AlbedoRequest resolved into what the measurement takes (measure/albedo_measure.hpp): the
// quadrature the request asks for, the material it names and its counts.
#pragma once
#include <functional>
#include <string>

#include "microsim/api/albedo_request.hpp"
#include "microsim/measure/albedo_measure.hpp"

namespace microsim {

// The quadrature the request asks for: Gauss-Legendre on mu_nodes nodes, or the trapezoid rule
// on the given incidences.
MuQuadrature albedo_quadrature(const AlbedoRequest& request);
// The measurement's options: the quadrature, the material (albedo_material) and the counts.
AlbedoOptions albedo_options(const AlbedoRequest& request);

// Measures E at every node of the request's quadrature on one surface (measure_albedo of the
// request's options). `progress`: fraction done.
AlbedoSurface measure_albedo(const Microsurface& s, const std::string& file, const AlbedoRequest& request,
                             const std::function<void(double)>& progress = {});

}  // namespace microsim
