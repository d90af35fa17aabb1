#include "microsim/api/bsdf_record.hpp"

namespace microsim {

namespace {
// The record's parameters: the request as run (one incidence: its angles as numbers).
Json bsdf_parameters_json(const BsdfRequest& o, const BsdfTable& t) {
  const BsdfResult& r = t.results.at(0);
  const bool single = t.results.size() == 1;
  Json parameters = {{"material", o.material},
                     {"eta", o.eta ? Json(*o.eta) : Json(nullptr)},
                     {"k", o.k ? Json(*o.k) : Json(nullptr)},
                     {"theta_i_deg", single ? Json(o.theta_i_deg[0]) : Json(o.theta_i_deg)},
                     {"phi_i_deg", single ? Json(o.phi_i_deg[0]) : Json(o.phi_i_deg)},
                     {"orders", o.orders},
                     {"rays", t.paths(0, 0)},  // over every azimuth of an averaged table
                     {"rays_requested", o.rays},
                     {"seed", o.seed},
                     {"replicates", r.options.replicates},
                     {"resolution", o.resolution},
                     {"in_plane_bins", r.plane.size()},
                     {"in_plane_band_half_width_deg", deg(r.plane.half_width())},
                     {"max_events", r.options.max_events},
                     {"smith_multiple_walks", r.options.model_walks},
                     {"models", o.models}};
  if (o.format == "bsdf") parameters["table_resolution"] = o.table_resolution;
  if (o.polarized) parameters["polarized"] = true;
  if (!r.spectral.empty()) {
    const auto table = bsdf_index_table(o);
    parameters["metal"] = o.metal.empty() ? Json(nullptr) : Json(o.metal);
    parameters["ior_file"] = o.ior_file.empty() ? Json(nullptr) : Json(o.ior_file);
    parameters["index_source"] = table->source;
    parameters["wavelengths_nm"] = r.options.wavelengths_nm;
  }
  return parameters;
}
}  // namespace

void put_bsdf_record(Json& j, const BsdfRequest& o, const BsdfTable& t, const Microsurface& s,
                     const std::string& file) {
  const BsdfResult& r = t.results.at(0);
  j["file"] = file;
  j["surface"] = s.description;
  j["parameters"] = bsdf_parameters_json(o, t);
  j["definitions"] = bsdf_definitions_json(r, o.polarized);
  put_bsdf_incidences(j, t, s);
}

}  // namespace microsim
