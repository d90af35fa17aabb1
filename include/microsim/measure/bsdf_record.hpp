// The record of a BSDF measurement (measure/bsdf_measure.hpp, measure/bsdf_table.hpp).
//
// The measure layer knows no request: a BsdfRequest (api/bsdf_request.hpp) is resolved into the
// table's options in api/bsdf_resolve.hpp and its record is put together in api/bsdf_record.hpp
// from the parts here. Each incidence's result becomes two Tables (measure/table.hpp):
// the albedo per side and scattering order with the models beside it, and the in-plane lobe per
// bin; the JSON record, the EXR file and the renderer tables' descriptions only format them
// (the files: io/bsdf_files.hpp).
//
// Comparisons follow the rule of table.hpp: z = (measured - model) / error, null where there is
// no error bar and the values differ. The models of the nominal NDF (smith_single,
// smith_multiple, vcavity_single) are statistics of the generated surfaces; compared with one
// surface, the ray-count error misses the surface-to-surface variation (docs/theory/error-bars.md,
// "Two kinds of error bar"), so z_<model> is null and the distance in units of the ray-count error is kept as
// z_<model>_rays. smooth_interface is exact [GeomBSDF24, eq. 7d, 10b]: its z is a verdict.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/bsdf_table.hpp"
#include "microsim/measure/table.hpp"
#include "microsim/models/metals.hpp"

namespace microsim {

// The albedo and in-plane tables' columns and merge rules without rows (`orders`: K of the
// request; the albedo table's columns do not depend on it).
Table bsdf_albedo_spec();
Table bsdf_in_plane_spec(int orders);

// Albedo rows of one incidence: side (reflected, transmitted for a dielectric) x slot, with
// albedo, albedo_stderr and beside them smith_multiple (its own Monte Carlo error combined in
// z_smith_multiple), smith_single and vcavity_single (order 1) and smooth_interface (total).
// Merged over surfaces (table.hpp merge), albedo becomes the mean with the between-surface
// error and the nominal models' z use it, with Student t p-values.
Table bsdf_albedo_table(const BsdfResult& r);
// In-plane rows: side x bin, theta_o_deg (signed, positive on the specular side), f per slot
// with errors, and the models averaged over the bin.
Table bsdf_in_plane_table(const BsdfResult& r);

// The JSON summary fields of one incidence (albedo, reflected_stderr, transmitted_stderr,
// albedo_models, rows, in_plane, V-groove models where the surface has them, bookkeeping),
// without the run header.
Json bsdf_summary_json(const BsdfResult& r, const Microsurface& s);
// Every incidence: {theta_i_deg, phi_i_deg, and the fields of bsdf_summary_json}, phi_i outer.
Json bsdf_incidences_json(const BsdfTable& t, const Microsurface& s);
// What the record's fields mean (a spectral run's fields too; `polarized`: the Mueller fields).
Json bsdf_definitions_json(const BsdfResult& r, bool polarized);
// The measured part of `measure bsdf`'s record (after its definitions): with one incidence its
// fields at the top level, and incidences.
void put_bsdf_incidences(Json& record, const BsdfTable& t, const Microsurface& s);

}  // namespace microsim
