// Validation rows of the BSDF albedos that only some surfaces have (used by the bsdf_albedo
// check in validate.cpp):
//  * finite objects, mirror: the total albedo per unit of the flux on the macrosurface against
//    the visible area ratio (identity: every ray that hits a mirror object leaves it). Box and
//    tiled boxes: 1 + (H/N) tan(theta) (|cos phi|/W + |sin phi|/D) (only the outer walls are
//    seen, [GeomBSDF24, "Inherent Assumptions", Fig. 5-6]); convex objects (ellipsoid, a single
//    parallelepiped): the front-facing projected area of the facets over A cos(theta).
//  * periodic V-grooves (not --2d): every order against the closed form of the groove
//    (models/vgroove_multiple.hpp; identity for the exact geometry).
//  * V-cavity ensembles: every order against the closed form averaged over the ensemble's own
//    grooves (identity) and against the V-cavity multiple-scattering model of the nominal D
//    (model; its error adds the between-groove spread over sqrt(grooves)).
#pragma once
#include <string>
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/validate/validate.hpp"

namespace microsim::validation {

// True when a mirror's total albedo is exactly 1 (periodic tiles, V-cavity ensembles); finite
// objects reflect their visible area ratio instead.
bool mirror_total_is_one(const Microsurface& s);

// Appends the rows above. `proto` carries entry and condition; `where` is appended to the
// condition, `group` prefixes the groups, `extra` the plot fields.
void append_bsdf_object_rows(const BsdfResult& r, const Microsurface& s, const Row& proto,
                             const std::string& where, const std::string& group,
                             const Json& extra, std::vector<Row>& rows);

}  // namespace microsim::validation
