// microsim.generate on the library's surface requests (surface/surface_spec.hpp): the keywords
// are the table's options, checked and built as `microsim generate KIND` checks and builds them.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "held_surface.hpp"
#include "thread_limit.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/surface/surface_spec.hpp"

namespace py = pybind11;

namespace microsim::python {

namespace {

// The request of `kind`: the preset's options (config), then the options given (which win), each
// checked against the table; ParameterError for a required option not given.
SurfaceRequest surface_request(const std::string& kind, const std::vector<std::pair<std::string, std::string>>& options,
                               const std::optional<std::string>& config) {
  const SurfaceKind& k = surface_kind(kind);
  SurfaceRequest r{k.name, {}};
  if (config) read_surface_preset(r, *config);
  for (const auto& [name, value] : options) set_surface_option(r, name, value);
  for (const SurfaceOption& o : k.options)
    if (o.required && !r.options.count(o.name)) throw ParameterError(surface_option_placeholder(o.name) + " is required");
  return r;
}

// Builds the surface (checked against the format of `path`), saves it at `path` when `save`, and
// prints the warnings `microsim generate` prints; without the GIL, on `threads` threads.
Surface generate(const std::string& kind, const std::vector<std::pair<std::string, std::string>>& options,
                 const std::optional<std::string>& config, const std::string& path, bool save, int threads) {
  const SurfaceRequest r = surface_request(kind, options, config);
  const auto limit = thread_limit(threads);
  py::gil_scoped_release nogil;
  auto s = std::make_shared<const Microsurface>(generate_surface(r, path));
  if (save) save_surface(*s, path);
  for (const auto& w : surface_report(r, *s, path, false).warnings) std::cerr << "microsim: warning: " << w << "\n";
  return {s, std::nullopt};
}

}  // namespace

void bind_generate(py::module_& m) {
  m.def("_generate", &generate, py::arg("kind"), py::arg("options"), py::arg("config"), py::arg("path"),
        py::arg("save"), py::arg("threads"),
        "A new surface of `kind` from (option name, value text) pairs and an optional preset file");
}

}  // namespace microsim::python
