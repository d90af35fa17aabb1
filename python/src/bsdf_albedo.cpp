// measure bsdf and measure albedo as the library's requests (microsim/api/bsdf_request.hpp,
// albedo_request.hpp) bound to Python: microsim/__init__.py sets their fields from keyword
// arguments (the command line's long options with '_' for '-') and runs them here, without the
// GIL; the record and the files are the library's, the same as the command line's.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "held_surface.hpp"
#include "json_to_python.hpp"
#include "thread_limit.hpp"
#include "microsim/api/albedo_run.hpp"
#include "microsim/api/angle_list.hpp"
#include "microsim/api/bsdf_run.hpp"
#include "microsim/api/record_file.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/albedo_measure.hpp"

namespace py = pybind11;

namespace microsim::python {

namespace {

// The output's format (its extension) after checking it against the command's formats; "json"
// without an output (the record only).
std::string output_format(const std::optional<std::string>& output, std::initializer_list<const char*> formats) {
  if (!output) return "json";
  require_output_format(*output, formats);
  return extension_of(*output);
}

// measure bsdf: the record; with `output` the table (or the record) written there and the
// record beside it, as the command line writes them.
py::object run_bsdf(BsdfRequest r, const std::optional<std::string>& output, int threads) {
  r.format = output_format(output, {"exr", "json", "bsdf", "binary", "pbsdf"});
  const auto limit = thread_limit(threads);
  Json j;
  {
    py::gil_scoped_release nogil;  // measurements run on TBB threads without the GIL
    RunContext ctx;
    ctx.threads = threads;
    j = measure_bsdf_record(r, ctx, output.value_or(""));
    if (output) write_record_file(bsdf_record_path(*output), j);
  }
  return to_python(j);
}

// measure albedo: the record; with `output` the files the command line writes there.
py::object run_albedo(AlbedoRequest r, const std::optional<std::string>& output, int threads) {
  r.format = output_format(output, {"json", "csv", "exr"});
  const auto limit = thread_limit(threads);
  Json j;
  {
    py::gil_scoped_release nogil;
    RunContext ctx;
    ctx.threads = threads;
    const AlbedoRun run = run_albedo_request(r, ctx);
    if (output) write_albedo_outputs(*output, r, run);
    j = run.record;
  }
  return to_python(j);
}

// A list of angles (or wavelengths) in degrees: set from its text ("0:80:40", "30,60"), read back
// as the values.
template <class Request>
void degrees_field(py::class_<Request>& c, const char* name, std::vector<double> Request::*field) {
  c.def_property(
      name, [field](const Request& r) { return r.*field; },
      [field, name](Request& r, const std::string& text) { r.*field = angle_list(text, name).degrees; });
}

void bind_bsdf(py::module_& m) {
  py::class_<BsdfRequest> c(m, "BsdfRequest", "measure bsdf's parameters (microsim/api/bsdf_request.hpp)");
  c.def(py::init<>())
      .def_property(
          "surface", [](const BsdfRequest& r) { return r.surface.name; },
          [](BsdfRequest& r, const std::pair<std::string, Surface>& s) { r.surface = surface_held(s.first, s.second.s); })
      .def_readwrite("material", &BsdfRequest::material)
      .def_readwrite("eta", &BsdfRequest::eta)
      .def_readwrite("k", &BsdfRequest::k)
      .def_readwrite("metal", &BsdfRequest::metal)
      .def_readwrite("ior_file", &BsdfRequest::ior_file);
  degrees_field(c, "wavelengths", &BsdfRequest::wavelengths_nm);
  degrees_field(c, "theta_i", &BsdfRequest::theta_i_deg);
  degrees_field(c, "phi_i", &BsdfRequest::phi_i_deg);
  c.def_readwrite("table_resolution", &BsdfRequest::table_resolution)
      .def_readwrite("table_azimuths", &BsdfRequest::table_azimuths)
      .def_readwrite("orders", &BsdfRequest::orders)
      .def_readwrite("rays", &BsdfRequest::rays)
      .def_readwrite("seed", &BsdfRequest::seed)
      .def_readwrite("replicates", &BsdfRequest::replicates)
      .def_readwrite("polarized", &BsdfRequest::polarized)
      // The command line's flag --no-models: the request's `models` turned around.
      .def_property(
          "no_models", [](const BsdfRequest& r) { return !r.models; },
          [](BsdfRequest& r, bool no_models) { r.models = !no_models; })
      .def_readwrite("resolution", &BsdfRequest::resolution);
  m.def("_measure_bsdf", &run_bsdf, py::arg("request"), py::arg("output"), py::arg("threads"));
}

void bind_albedo(py::module_& m) {
  py::class_<AlbedoRequest> c(m, "AlbedoRequest", "measure albedo's parameters (microsim/api/albedo_request.hpp)");
  c.def(py::init<>())
      .def_property(
          "surfaces", [](const AlbedoRequest& r) { return r.surfaces.size(); },
          [](AlbedoRequest& r, const std::vector<std::pair<std::string, Surface>>& given) {
            r.surfaces.clear();
            for (const auto& [name, s] : given) r.surfaces.push_back(surface_held(name, s.s));
          })
      .def_readwrite("material", &AlbedoRequest::material)
      .def_readwrite("eta", &AlbedoRequest::eta)
      .def_readwrite("k", &AlbedoRequest::k)
      .def_readwrite("metal", &AlbedoRequest::metal)
      .def_readwrite("wavelength_nm", &AlbedoRequest::wavelength_nm)
      .def_readwrite("mu_nodes", &AlbedoRequest::mu_nodes);
  degrees_field(c, "theta_i", &AlbedoRequest::theta_i_deg);
  // One azimuth, given as the angle lists are (a number or its text).
  c.def_property(
      "phi_i", [](const AlbedoRequest& r) { return r.phi_i_deg; },
      [](AlbedoRequest& r, const std::string& text) {
        const AngleList a = angle_list(text, "phi_i");
        if (a.degrees.size() != 1)
          throw ParameterError("{phi_i} is one azimuth in degrees (got '" + literal_text(text) + "')");
        r.phi_i_deg = a.degrees[0];
      });
  c.def_readwrite("azimuths", &AlbedoRequest::azimuths)
      .def_readwrite("orders", &AlbedoRequest::orders)
      .def_readwrite("rays", &AlbedoRequest::rays)
      .def_readwrite("seed", &AlbedoRequest::seed)
      .def_readwrite("replicates", &AlbedoRequest::replicates);
  m.def("_measure_albedo", &run_albedo, py::arg("request"), py::arg("output"), py::arg("threads"));
}

}  // namespace

void bind_bsdf_albedo(py::module_& m) {
  bind_bsdf(m);
  bind_albedo(m);
}

}  // namespace microsim::python
