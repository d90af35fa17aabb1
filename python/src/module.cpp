// The compiled part of the Python module `microsim` (microsim._core): surfaces as numpy views,
// the library's requests (requests.cpp, bsdf_albedo.cpp, generate.cpp, validate.cpp) and the
// analytic models (models.cpp). python/microsim/__init__.py turns keyword arguments into request
// fields. The command line is no part of it: the requests hold every check and record.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>

#include "held_surface.hpp"
#include "json_to_python.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/surface/surface_spec.hpp"

namespace py = pybind11;
using namespace microsim;

namespace microsim::python {
void bind_models(py::module_& m);
void bind_requests(py::module_& m);
void bind_generate(py::module_& m);
void bind_validate(py::module_& m);
void bind_bsdf_albedo(py::module_& m);
}

namespace {

using python::Surface;

// A read-only numpy view of `data` kept alive by `owner`.
template <class T>
py::array view(const T* data, std::vector<py::ssize_t> shape, py::handle owner) {
  py::array a(py::dtype::of<T>(), shape, data, owner);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

py::object nominal(const Microsurface& s) {
  if (!s.nominal) return py::none();
  py::dict d;
  d["distribution"] = models::to_string(s.nominal->kind);
  d["alpha_x"] = s.nominal->alpha_x;
  d["alpha_y"] = s.nominal->alpha_y;
  return std::move(d);
}

// A library parameter as Python names it: the keyword argument of the same name.
std::string keyword_spelling(std::string_view parameter) { return std::string(parameter); }

// The surface spec's table: kind -> its options (keyword = the option name with '_' for '-').
py::dict surface_kinds_table() {
  static const char* types[] = {"int", "float", "seed", "str", "flag"};
  py::dict kinds;
  for (const SurfaceKind& k : surface_kinds()) {
    py::list options;
    for (const SurfaceOption& o : k.options) {
      py::dict d;
      std::string keyword = o.name;
      for (char& c : keyword) c = c == '-' ? '_' : c;
      d["name"] = o.name;
      d["keyword"] = keyword;
      d["type"] = types[static_cast<int>(o.type)];
      d["default"] = o.default_text.empty() ? py::object(py::none()) : py::object(py::str(o.default_text));
      if (o.check == SurfaceOption::Check::Range) d["range"] = o.range.text();
      else if (o.check == SurfaceOption::Check::Integer)
        d["range"] = "[" + std::to_string(o.lo) + ", " + std::to_string(o.hi) + "]";
      else if (o.check == SurfaceOption::Check::Seed) d["range"] = "[0, 2^64-1]";
      else d["range"] = py::none();
      d["required"] = o.required;
      d["help"] = o.help;
      d["sets"] = o.sets;
      options.append(d);
    }
    py::dict kind;
    kind["help"] = k.help;
    kind["options"] = options;
    kinds[py::str(k.name)] = kind;
  }
  return kinds;
}

// microsim.Surface: the geometry as read-only numpy views, the description and the macrosurface.
void bind_surface(py::module_& m) {
  py::class_<Surface>(m, "Surface", "A microsurface (heightfield or mesh) with its macrosurface")
      .def_property_readonly("kind", [](const Surface& s) {
        return s.s->kind() == Microsurface::Kind::Heightfield ? "heightfield" : "mesh";
      })
      .def_property_readonly("heights", [](py::object self) -> py::object {
        const Surface& s = self.cast<const Surface&>();
        if (s.s->kind() != Microsurface::Kind::Heightfield) return py::none();
        // heights()[i + nx j]: row j, column i (a view, not a copy; read-only).
        return view(s.s->heights().data(), {s.s->ny(), s.s->nx()}, self);
      }, "Heights as a read-only (ny, nx) float32 numpy view (row j, column i; None for a mesh)")
      .def_property_readonly("vertices", [](py::object self) -> py::object {
        const Surface& s = self.cast<const Surface&>();
        const auto& v = s.s->vertices();
        if (v.empty()) return py::none();
        return view(v[0].data(), {static_cast<py::ssize_t>(v.size()), 3}, self);
      }, "Mesh vertices, (n, 3) float32 view (None for a heightfield)")
      .def_property_readonly("triangles", [](py::object self) -> py::object {
        const Surface& s = self.cast<const Surface&>();
        const auto& t = s.s->triangles();
        if (t.empty()) return py::none();
        return view(t[0].data(), {static_cast<py::ssize_t>(t.size()), 3}, self);
      }, "Mesh triangles, (n, 3) uint32 view (None for a heightfield)")
      .def_property_readonly("description", [](const Surface& s) { return python::to_python(s.s->description); },
                             "The generator's name and parameters (the record's `surface`)")
      .def_property_readonly("nominal", [](const Surface& s) { return nominal(*s.s); },
                             "The generator's nominal NDF, or None")
      .def_property_readonly("size", [](const Surface& s) {
        return py::make_tuple(s.s->macro().size_x, s.s->macro().size_y);
      }, "Tile (or window) extent along x and y")
      .def_property_readonly("area", [](const Surface& s) { return s.s->macro().area; }, "Macrosurface area A")
      .def_property_readonly("periodic", [](const Surface& s) { return s.s->macro().periodic; })
      .def_property_readonly("num_facets", [](const Surface& s) { return s.s->num_facets(); })
      .def_property_readonly("path", [](const Surface& s) { return s.path; },
                             "The file it was loaded from, or None")
      .def("save", [](const Surface& s, const std::string& path) {
        py::gil_scoped_release nogil;
        save_surface(*s.s, path);
      }, py::arg("path"), "Save as .exr (heightfields), .ply, .obj or .off")
      .def("__repr__", [](const Surface& s) {
        std::string r = "<microsim.Surface " + s.s->description.value("kind", std::string("surface"));
        if (s.s->kind() == Microsurface::Kind::Heightfield)
          r += " " + std::to_string(s.s->nx()) + "x" + std::to_string(s.s->ny());
        r += ", " + std::to_string(s.s->num_facets()) + " facets";
        if (s.path) r += ", " + *s.path;
        return r + ">";
      });
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "microsim: explicit microsurface Monte Carlo simulator (compiled core)";
  static py::exception<UsageError> usage_error(m, "UsageError", PyExc_ValueError);
  static py::exception<RuntimeFailure> runtime_failure(m, "RuntimeFailure", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const UsageError& e) {
      usage_error(spelled_message(e, keyword_spelling).c_str());
    } catch (const RuntimeFailure& e) {
      runtime_failure(e.what());
    } catch (const py::builtin_exception&) {
      throw;  // pybind11's own (TypeError of a wrong argument, ...) keep their Python classes
    } catch (const std::exception& e) {
      // What the command line reports as "failed" with exit 1 (std::bad_alloc, a file that
      // cannot be written, ...): RuntimeFailure, as an exit code of 1 is.
      runtime_failure(e.what());
    }
  });

  bind_surface(m);

  m.def("load", [](const std::string& path) {
    Surface s;
    {
      py::gil_scoped_release nogil;
      s.s = std::make_shared<const Microsurface>(load_surface(path));
    }
    s.path = path;
    return s;
  }, py::arg("path"), "Load a surface file (.exr, .ply, .obj, .off)");

  python::bind_requests(m);
  python::bind_generate(m);
  python::bind_validate(m);
  python::bind_bsdf_albedo(m);
  m.def("surface_kinds", &surface_kinds_table,
        "Every surface kind of generate(kind, **options) with its options: name, keyword, type, default, "
        "range, required, help and the generator parameter it sets (the library's surface spec)");

  py::module_ models = m.def_submodule("models", "Analytic microfacet theory (include/microsim/models)");
  python::bind_models(models);
}
