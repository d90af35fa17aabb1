#include "microsim/api/bsdf_resolve.hpp"

#include <cmath>
#include <cstdint>

namespace microsim {

void check_bsdf_surface(const BsdfRequest& o, const Microsurface& s, const std::string& name) {
  const std::string& ext = o.format;
  if (s.macro().finite_object() && (ext == "bsdf" || ext == "binary" || ext == "pbsdf"))
    throw ParameterError(literal_text(name) + ": {output} ." + ext + " tables need a periodic tile (this surface is a finite object)");
  const bool anisotropic_surface = s.nominal && std::abs(s.nominal->alpha_x - s.nominal->alpha_y) > 1e-12;
  if (ext == "binary" && anisotropic_surface)
    throw ParameterError(literal_text(name) + ": {output} .binary needs an isotropic surface (MERL tables are isotropic; nominal "
                         "alpha_x != alpha_y); write a .bsdf with {phi_i} -180:180:STEP instead");
  if (ext == "pbsdf" && anisotropic_surface)
    throw ParameterError(literal_text(name) + ": {output} .pbsdf needs an isotropic surface (Mitsuba's measured_polarized "
                         "tables are isotropic; nominal alpha_x != alpha_y)");
  if (ext == "bsdf" && anisotropic_surface && o.phi_i_deg.size() == 1)
    throw ParameterError(literal_text(name) + ": an anisotropic surface (alpha_x != alpha_y) needs {phi_i} over the full "
                         "circle for a .bsdf (e.g. {phi_i} -180:180:30)");
}

BsdfTableOptions bsdf_table_options(const BsdfRequest& o, const Microsurface& s, TallySplit* split) {
  BsdfTableOptions to;
  to.base.material = bsdf_material(o);
  if (const auto table = bsdf_index_table(o)) {
    to.base.wavelengths_nm = bsdf_wavelengths(o);
    to.base.spectral = spectral_conductors(*table, to.base.wavelengths_nm);
  }
  to.base.orders = o.orders;
  to.base.rays = static_cast<std::uint64_t>(o.rays);
  to.base.split = split;
  to.base.seed = o.seed;
  to.base.resolution = o.resolution;
  to.base.replicates = o.replicates;
  to.base.models = o.models;
  to.base.polarized = o.polarized;
  to.base.model_walks = s.nominal && o.models ? to.base.rays : 0;
  for (double t : o.theta_i_deg) to.theta_i.push_back(rad(t));
  for (double p : o.phi_i_deg) to.phi_i.push_back(rad(p));
  const bool renderer_table = o.format == "bsdf" || o.format == "binary" || o.format == "pbsdf";
  to.table_azimuths = renderer_table && to.phi_i.size() == 1 ? o.table_azimuths : 1;
  // The turned runs feed the table alone: f for .bsdf and .binary, the Mueller bins for .pbsdf.
  if (renderer_table)
    to.turned_runs = o.format == "pbsdf" ? BsdfTableOptions::TurnedRuns::TableMueller : BsdfTableOptions::TurnedRuns::TableF;
  return to;
}

}  // namespace microsim
