// The closed-form V-groove models beside `measure bsdf` (models/vgroove_multiple.hpp): for a
// periodic V-groove tile (`vgroove`, not --2d) the per-order albedo of its groove
// (`vgroove_multiple`), for a V-cavity ensemble (`vcavity`) the V-cavity multiple-scattering
// model of its nominal D (`vcavity_multiple`) and the same closed form averaged over the
// ensemble's own grooves (`vcavity_multiple_grooves`: for a mirror or conductor the exact
// expectation of the traced estimate).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "microsim/measure/bsdf_result.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// Per-slot reflected albedo of the closed form for this surface and incidence, or nothing when
// the surface has none. `which`: "vgroove_multiple", "vcavity_multiple", "vcavity_multiple_grooves".
// `stderr_out` (optional) receives, for vcavity_multiple_grooves, the standard error of the groove
// average as an estimate of the nominal model (between-groove spread / sqrt(grooves)).
std::optional<std::vector<double>> groove_model_albedo(const Microsurface& s, const BsdfOptions& o,
                                                      const std::string& which,
                                                      std::vector<double>* stderr_out = nullptr);

// Adds the models to a bsdf summary (bsdf_summary_json): albedo_models.<name> with `reflected`
// and `transmitted` per order (transmitted null: the closed form does not follow refracted
// light), and per row of `rows` the model value and z-score beside the measurement. Surfaces
// without a closed form get null fields.
void add_groove_models(Json& summary, const BsdfResult& r, const Microsurface& s);

// Adds `normalization` to a bsdf summary: what the albedos are per unit of (macro area for tiles
// and V-cavity ensembles; the flux falling on the macrosurface for finite objects, with the share
// of the reflected albedo that leaves below the base plane, not binned in the hemisphere maps).
void add_macro_normalization(Json& summary, const BsdfResult& r, const Microsurface& s);

}  // namespace microsim
