// microsim.validate on the library's ValidateRequest (microsim/api/validate_request.hpp).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "held_surface.hpp"
#include "json_to_python.hpp"
#include "thread_limit.hpp"
#include "microsim/api/record_file.hpp"
#include "microsim/api/validate_request.hpp"

#ifndef MICROSIM_DATA_DIR
#define MICROSIM_DATA_DIR ""
#endif

namespace py = pybind11;

namespace microsim::python {

namespace {

// (record, failure message or None): the record is returned, and written to `output` when given,
// even when an exact identity FAILED (microsim/__init__.py raises ValidationFailed with it).
py::tuple validate(const ValidateRequest& r, const std::optional<std::string>& output, int threads) {
  require_surfaces_or_suite(!r.surfaces.empty(), !r.suite.empty(), r.suite_dirs);
  if (output) require_output_format(*output, {"json", "csv"});
  const auto limit = thread_limit(threads);
  ValidateRun run;
  {
    py::gil_scoped_release nogil;  // the checks run on TBB threads without the GIL
    RunContext ctx;
    ctx.threads = threads;
    ctx.warning = [](const std::string& w) { std::cerr << "microsim: warning: " << w << "\n"; };
    run = run_validate_request(r, ctx);
    if (output) write_record_file(*output, run.record);
    run.generated_surfaces->commit();
  }
  py::object failure = py::none();
  if (run.result.any_failure()) failure = py::str(validation_failure(run.result, output.value_or("")));
  return py::make_tuple(to_python(run.record), failure);
}

// An optional angle list: set from its text, read back as that text (None when not given).
void optional_angles(py::class_<ValidateRequest>& c, const char* name, std::optional<AngleList> ValidateRequest::*field,
                     bool azimuths) {
  c.def_property(
      name, [field](const ValidateRequest& r) { return r.*field ? std::optional<std::string>((r.*field)->text) : std::nullopt; },
      [field, name, azimuths](ValidateRequest& r, const std::string& text) {
        r.*field = azimuths ? azimuth_list(text, name) : angle_list(text, name);
      });
}

}  // namespace

void bind_validate(py::module_& m) {
  py::class_<ValidateRequest> c(m, "ValidateRequest", "validate's parameters (microsim/api/validate_request.hpp)");
  c.def(py::init([] {
    ValidateRequest r;
    r.suite_dirs = suite_search_dirs(MICROSIM_DATA_DIR);
    return r;
  }));
  c.def_property(
      "surfaces", [](const ValidateRequest& r) { return r.surfaces.size(); },
      [](ValidateRequest& r, const std::vector<std::pair<std::string, Surface>>& given) {
        r.surfaces.clear();
        for (const auto& [name, s] : given) r.surfaces.push_back(surface_held(name, s.s));
      });
  optional_angles(c, "theta", &ValidateRequest::theta, false);
  optional_angles(c, "phi", &ValidateRequest::phi, true);
  c.def_readwrite("suite", &ValidateRequest::suite)
      .def_readwrite("surfaces_dir", &ValidateRequest::surfaces_dir)
      .def_readwrite("rays", &ValidateRequest::rays)
      .def_readwrite("seed", &ValidateRequest::seed)
      .def_readwrite("checks", &ValidateRequest::checks)
      .def_readwrite("significance", &ValidateRequest::significance);
  m.def("_validate", &validate, py::arg("request"), py::arg("output"), py::arg("threads"));
}

}  // namespace microsim::python
