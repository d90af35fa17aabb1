// The library's measurement requests (microsim/api/) bound to Python: microsim/__init__.py sets
// their fields from keyword arguments and runs them here, without the GIL; the record is the
// library's, the same as the command line's -o record.json.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "held_surface.hpp"
#include "json_to_python.hpp"
#include "thread_limit.hpp"
#include "microsim/api/g1_request.hpp"
#include "microsim/api/g2_request.hpp"
#include "microsim/api/ndf_request.hpp"
#include "microsim/api/record_file.hpp"
#include "microsim/api/request_checks.hpp"
#include "microsim/api/vndf_request.hpp"
#include "microsim/io/output.hpp"

namespace py = pybind11;

namespace microsim::python {

namespace {

// Surfaces given as (record name, Surface) pairs.
using NamedSurfaces = std::vector<std::pair<std::string, Surface>>;

std::vector<SurfaceInput> held(const NamedSurfaces& given) {
  std::vector<SurfaceInput> out;
  for (const auto& [name, s] : given) out.push_back(surface_held(name, s.s));
  return out;
}

// Runs record(r) on `threads` threads without the GIL; the record is also written to `output`
// when given (its format checked first, as the command line checks -o).
template <class Request>
py::object run_request(const Request& r, Json (*record)(const Request&, const RunContext&),
                       const std::optional<std::string>& output, int threads,
                       std::initializer_list<const char*> formats) {
  if (output) require_output_format(*output, formats);
  const auto limit = thread_limit(threads);
  Json j;
  {
    py::gil_scoped_release nogil;  // measurements run on TBB threads without the GIL
    RunContext ctx;
    ctx.threads = threads;
    j = record(r, ctx);
    if (output) write_record_file(*output, j);
  }
  return to_python(j);
}

// measure ndf: the record, or None when `output` is an EXR table (written, as the command line
// writes it, instead of a record).
py::object run_ndf_request(const NdfRequest& r, const std::optional<std::string>& output, int threads) {
  if (!output || extension_of(*output) != "exr")
    return run_request(r, &measure_ndf_record, output, threads, {"json", "csv", "exr"});
  const auto limit = thread_limit(threads);
  {
    py::gil_scoped_release nogil;
    const NdfRun run = run_ndf(r);
    write_exr(*output, ndf_to_exr(run.result, *run.surface));
  }
  return py::none();
}

// An angle list field: set from its text ("0:85:5", "30,80"), read back as that text.
template <class Request>
void angle_field(py::class_<Request>& c, const char* name, AngleList Request::*field, bool azimuths) {
  c.def_property(
      name, [field](const Request& r) { return (r.*field).text; },
      [field, name, azimuths](Request& r, const std::string& text) {
        r.*field = azimuths ? azimuth_list(text, name) : angle_list(text, name);
      });
}

// The surfaces of an ensemble request: (record name, Surface) pairs.
template <class Request>
void surfaces_field(py::class_<Request>& c) {
  c.def_property(
      "surfaces", [](const Request& r) { return r.surfaces.size(); },
      [](Request& r, const NamedSurfaces& given) { r.surfaces = held(given); });
}

void bind_ndf(py::module_& m) {
  py::class_<NdfRequest> c(m, "NdfRequest", "measure ndf's parameters (microsim/api/ndf_request.hpp)");
  c.def(py::init<>())
      .def_property(
          "surface", [](const NdfRequest& r) { return r.surface.name; },
          [](NdfRequest& r, const std::pair<std::string, Surface>& s) { r.surface = surface_held(s.first, s.second.s); })
      .def_readwrite("theta_bins", &NdfRequest::theta_bins)
      .def_readwrite("phi_bins", &NdfRequest::phi_bins);
  m.def("_measure_ndf", &run_ndf_request, py::arg("request"), py::arg("output"), py::arg("threads"));
}

void bind_g1(py::module_& m) {
  py::class_<G1Request> c(m, "G1Request", "measure g1's parameters (microsim/api/g1_request.hpp)");
  c.def(py::init<>());
  surfaces_field(c);
  angle_field(c, "theta", &G1Request::theta, false);
  angle_field(c, "phi", &G1Request::phi, true);
  c.def_readwrite("rays", &G1Request::rays)
      .def_readwrite("seed", &G1Request::seed)
      .def_readwrite("replicates", &G1Request::replicates);
  m.def("_measure_g1", [](const G1Request& r, const std::optional<std::string>& output, int threads) {
    return run_request(r, &measure_g1_record, output, threads, {"json", "csv"});
  }, py::arg("request"), py::arg("output"), py::arg("threads"));
}

void bind_g2(py::module_& m) {
  py::class_<G2Request> c(m, "G2Request", "measure g2's parameters (microsim/api/g2_request.hpp)");
  c.def(py::init<>());
  surfaces_field(c);
  angle_field(c, "theta_o", &G2Request::theta_o, false);
  angle_field(c, "phi_o", &G2Request::phi_o, true);
  angle_field(c, "theta_i", &G2Request::theta_i, false);
  angle_field(c, "phi_i", &G2Request::phi_i, true);
  c.def_readwrite("rays", &G2Request::rays)
      .def_readwrite("seed", &G2Request::seed)
      .def_readwrite("replicates", &G2Request::replicates);
  m.def("_measure_g2", [](const G2Request& r, const std::optional<std::string>& output, int threads) {
    return run_request(r, &measure_g2_record, output, threads, {"json", "csv"});
  }, py::arg("request"), py::arg("output"), py::arg("threads"));
}

void bind_vndf(py::module_& m) {
  py::class_<VndfRequest> c(m, "VndfRequest", "measure vndf's parameters (microsim/api/vndf_request.hpp)");
  c.def(py::init<>());
  surfaces_field(c);
  angle_field(c, "theta", &VndfRequest::theta, false);
  angle_field(c, "phi", &VndfRequest::phi, true);
  c.def_readwrite("rays", &VndfRequest::rays)
      .def_readwrite("sampler_samples", &VndfRequest::sampler_samples)
      .def_readwrite("seed", &VndfRequest::seed)
      .def_readwrite("theta_bins", &VndfRequest::theta_bins)
      .def_readwrite("phi_bins", &VndfRequest::phi_bins);
  m.def("_measure_vndf", [](const VndfRequest& r, const std::optional<std::string>& output, int threads) {
    return run_request(r, &measure_vndf_record, output, threads, {"json", "csv"});
  }, py::arg("request"), py::arg("output"), py::arg("threads"));
}

}  // namespace

void bind_requests(py::module_& m) {
  bind_ndf(m);
  bind_g1(m);
  bind_g2(m);
  bind_vndf(m);
}

}  // namespace microsim::python
