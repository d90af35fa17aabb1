#include "microsim/api/bsdf_files.hpp"

#include "microsim/api/request_checks.hpp"

namespace microsim {

std::string bsdf_rgl_description(const BsdfRequest& o, const Microsurface& s, const BsdfTable& t) {
  const auto f4 = [](double x) { return fixed_text(x, 4); };
  std::string d = "microsim measured BSDF of an explicit microsurface (" + s.description.dump() +
                  "), material " + o.material;
  if (o.eta) d += " eta " + f4(*o.eta);
  if (o.k) d += " k " + f4(*o.k);
  if (!o.metal.empty()) d += " " + o.metal;
  if (!o.ior_file.empty()) d += " from index file " + o.ior_file;
  if (t.results[0].wavelengths() > 0) {
    d += " at";
    for (double nm : t.results[0].options.wavelengths_nm) d += " " + fixed_text(nm, 1);
    d += " nm (rgb: linear sRGB, CIE 1931 2-degree observer, equal-energy white)";
  }
  d += "; reflection, all scattering orders; " + std::to_string(t.paths(0, 0)) +
       " random walks per incidence";
  if (t.azimuths() > 1)
    d += " over " + std::to_string(t.azimuths()) + " incidence azimuths (the azimuthal mean)";
  d += ", seed " + std::to_string(o.seed);
  if (o.material == "dielectric") d += "; the reflected part only (transmission is not in this table)";
  return d;
}

void write_bsdf_tables(const std::string& path, const BsdfRequest& o, const BsdfTable& t,
                       const Microsurface& s, Json& j, const std::string& json_path) {
  BsdfTableFile file;
  file.format = o.format;
  file.table_resolution = o.table_resolution;
  if (o.format == "bsdf") file.rgl_description = bsdf_rgl_description(o, s, t);
  write_bsdf_table_file(path, file, t, s, j, json_path);
}

}  // namespace microsim
