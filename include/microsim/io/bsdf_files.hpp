// The files of a BSDF measurement (measure/bsdf_record.hpp): the EXR hemisphere tables, the RGL
// tensor file and the MERL table, written from the measured tables and the record. What they
// take of a request comes as plain values (BsdfTableFile; api/bsdf_files.hpp fills it).
#pragma once
#include <string>

#include "microsim/io/output.hpp"
#include "microsim/measure/bsdf_record.hpp"

namespace microsim {

// The EXR table of one incidence: per side and slot f and its standard error on the hemisphere
// map, every parameter in the header (`attributes` are added to it).
ExrTable bsdf_exr_table(const BsdfResult& r, const Json& attributes);
// EXR of every incidence: channels "incidence_<k>.<side>.f_<order>" (and _stderr), k = p *
// n_theta + t; the header lists the incidences (`incidences`: [[theta_deg, phi_deg], ...]) and
// the layout. A single incidence keeps the single-incidence channel names.
ExrTable bsdf_table_exr(const BsdfTable& t, const Json& attributes);
// The header attributes of `measure bsdf`'s EXR (record: as put_bsdf_record wrote it).
Json bsdf_exr_attributes(const Json& record, const std::string& json_path);

// What a table file takes of the measurement's request (api/bsdf_files.hpp fills it).
struct BsdfTableFile {
  std::string format = "json";  // exr, bsdf (RGL tensor file), binary (MERL), pbsdf; json: no table
  int table_resolution = 64;    // .bsdf tables; .pbsdf grids
  std::string rgl_description;  // the .bsdf file's description of the measurement
};
// Writes the table in the file's format to `path` (exr, bsdf, binary, pbsdf; json: nothing)
// and adds the record's "table" field for the renderer tables.
void write_bsdf_table_file(const std::string& path, const BsdfTableFile& file, const BsdfTable& t,
                           const Microsurface& s, Json& record, const std::string& json_path);

}  // namespace microsim
