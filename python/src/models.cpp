// microsim.models: the analytic theory of include/microsim/models/ (the same code as the
// library's models columns), vectorized over numpy arrays. Directions are unit 3-vectors in the
// last axis, n = +z, pointing away from the surface; angles in radians.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "microsim/common.hpp"
#include "microsim/models/fresnel.hpp"
#include "microsim/models/g2_forms.hpp"
#include "microsim/models/metals.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/models/spectral_rgb.hpp"
#include "microsim/models/ndf.hpp"

namespace py = pybind11;
using microsim::Vec3;  // Eigen::Vector3d, as models::Vec3
namespace models = microsim::models;

namespace microsim::python {

namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Directions broadcast against each other (numpy rules, last axis of length 3).
std::vector<Array> directions(std::vector<py::object> in) {
  py::tuple b = py::module_::import("numpy").attr("broadcast_arrays")(*py::tuple(py::cast(in)));
  std::vector<Array> out;
  for (auto x : b) {
    Array a = Array::ensure(x);
    if (!a || a.ndim() < 1 || a.shape(a.ndim() - 1) != 3)
      throw UsageError("directions must be arrays of 3-vectors (last axis of length 3)");
    out.push_back(a);
  }
  return out;
}

// f applied to every direction (tuple) of the broadcast inputs (at most 3); shape without the
// last axis.
template <class F>
py::object map_directions(std::vector<py::object> in, F f) {
  std::vector<Array> d = directions(std::move(in));
  std::vector<py::ssize_t> shape(d[0].shape(), d[0].shape() + d[0].ndim() - 1);
  const py::ssize_t n = d[0].size() / 3;
  Array out(shape);
  double* o = out.mutable_data();
  std::vector<const double*> p;
  for (auto& a : d) p.push_back(a.data());
  Vec3 v[3];
  for (py::ssize_t k = 0; k < n; ++k) {
    for (std::size_t j = 0; j < p.size(); ++j) v[j] = Vec3(p[j][3 * k], p[j][3 * k + 1], p[j][3 * k + 2]);
    o[k] = f(static_cast<const Vec3*>(v));
  }
  if (shape.empty()) return py::float_(o[0]);
  return std::move(out);
}

models::Ndf make_ndf(const std::string& distribution, double alpha_x, std::optional<double> alpha_y) {
  const double ay = alpha_y.value_or(alpha_x);
  if (distribution == "beckmann") return models::Ndf::beckmann(alpha_x, ay);
  if (distribution == "ggx") return models::Ndf::ggx(alpha_x, ay);
  throw UsageError("distribution must be 'beckmann' or 'ggx' (got '" + distribution + "')");
}

models::Masking masking_of(const std::string& name) {
  for (auto m : {models::Masking::SmithHeightCorrelated, models::Masking::VCavity,
                 models::Masking::SmithMaskingOnly})
    if (name == models::to_string(m)) return m;
  throw UsageError("masking must be smith_height_correlated, vcavity or smith_masking_only (got '" +
                        name + "')");
}

}  // namespace

void bind_compensation(py::module_& m);

void bind_models(py::module_& m) {
  bind_compensation(m);
  m.def("direction", [](py::array_t<double> theta, py::array_t<double> phi) {
    py::tuple b = py::module_::import("numpy").attr("broadcast_arrays")(theta, phi);
    Array t = Array::ensure(b[0]), p = Array::ensure(b[1]);
    std::vector<py::ssize_t> shape(t.shape(), t.shape() + t.ndim());
    shape.push_back(3);
    Array out(shape);
    double* o = out.mutable_data();
    for (py::ssize_t k = 0; k < t.size(); ++k) {
      const Vec3 d = direction_from_angles(t.data()[k], p.data()[k]);
      for (int c = 0; c < 3; ++c) o[3 * k + c] = d[c];
    }
    return out;
  }, py::arg("theta"), py::arg("phi") = 0.0, "Unit direction(s) from zenith theta and azimuth phi (radians)");

  py::class_<models::Ndf>(m, "NDF", "Beckmann or GGX microfacet distribution [Heitz14, Sec. 3.3], anisotropic by eq. (11)")
      .def(py::init(&make_ndf), py::arg("distribution"), py::arg("alpha_x"), py::arg("alpha_y") = py::none(),
           "NDF('beckmann' or 'ggx', alpha_x, alpha_y=alpha_x)")
      .def_property_readonly("distribution", [](const models::Ndf& n) { return models::to_string(n.kind); })
      .def_readonly("alpha_x", &models::Ndf::alpha_x)
      .def_readonly("alpha_y", &models::Ndf::alpha_y)
      .def("D", [](const models::Ndf& n, py::object mm) {
        return map_directions({mm}, [&](const Vec3* v) { return n.D(v[0]); });
      }, py::arg("m"), "D(m), [Heitz14, App. A]")
      .def("Lambda", [](const models::Ndf& n, py::object v) {
        return map_directions({v}, [&](const Vec3* d) { return n.Lambda(d[0]); });
      }, py::arg("v"), "Smith Lambda(v), [Heitz14, Sec. 3.2/3.3] (+inf at and below the horizon)")
      .def("G1", [](const models::Ndf& n, py::object v, py::object mm) {
        if (mm.is_none())
          return map_directions({v}, [&](const Vec3* d) { return n.G1(d[0]); });
        return map_directions({v, mm}, [&](const Vec3* d) { return n.G1(d[0], d[1]); });
      }, py::arg("v"), py::arg("m") = py::none(), "Smith G1(v) or G1(v, m), [Heitz14, eq. 10]")
      .def("D_visible", [](const models::Ndf& n, py::object v, py::object mm) {
        return map_directions({v, mm}, [&](const Vec3* d) { return n.D_visible(d[0], d[1]); });
      }, py::arg("v"), py::arg("m"), "Distribution of visible normals D_v(m), [Heitz14, eq. 13]")
      .def("P22", py::vectorize([](models::Ndf n, double sx, double sy) { return n.P22(sx, sy); }),
           py::arg("slope_x"), py::arg("slope_y"), "Slope distribution P22, [Heitz14, App. A]")
      .def("alpha_o", py::vectorize([](models::Ndf n, double phi) { return n.alpha_o(phi); }),
           py::arg("phi"), "Projected roughness, [Heitz14, eq. 11]")
      .def("sample_visible_normal", [](const models::Ndf& n, py::array_t<double> v, py::array_t<double> u1,
                                       py::array_t<double> u2) {
        Array vv = Array::ensure(v);
        if (vv.size() != 3) throw UsageError("v must be one direction (3 numbers)");
        const Vec3 view(vv.data()[0], vv.data()[1], vv.data()[2]);
        py::tuple b = py::module_::import("numpy").attr("broadcast_arrays")(u1, u2);
        Array a = Array::ensure(b[0]), c = Array::ensure(b[1]);
        std::vector<py::ssize_t> shape(a.shape(), a.shape() + a.ndim());
        shape.push_back(3);
        Array out(shape);
        double* o = out.mutable_data();
        for (py::ssize_t k = 0; k < a.size(); ++k) {
          const Vec3 mm = n.sample_visible_normal(view, a.data()[k], c.data()[k]);
          for (int j = 0; j < 3; ++j) o[3 * k + j] = mm[j];
        }
        return out;
      }, py::arg("v"), py::arg("u1"), py::arg("u2"),
         "Exact sampling of D_visible(v, .) from uniform numbers u1, u2 in [0, 1): normals (..., 3)")
      .def("__repr__", [](const models::Ndf& n) {
        return std::string("NDF('") + models::to_string(n.kind) + "', " + std::to_string(n.alpha_x) + ", " +
               std::to_string(n.alpha_y) + ")";
      });

  m.def("beckmann_lambda", py::vectorize(&models::beckmann_lambda), py::arg("a"),
        "Beckmann Lambda(a), a = 1/(alpha tan theta), [Heitz14, Sec. 3.3] (erf form)");
  m.def("ggx_lambda", py::vectorize(&models::ggx_lambda), py::arg("a"), "GGX Lambda(a), [Heitz14, Sec. 3.3]");
  // The joint masking-shadowing forms [Heitz14, Sec. 5] and the V-cavity [Heitz14, Sec. 6].
  const std::map<std::string, double (*)(const models::Ndf&, const Vec3&, const Vec3&, const Vec3&)> g2 = {
      {"separable", &models::G2_separable},
      {"height_correlated", &models::G2_height_correlated},
      {"direction_correlated", &models::G2_direction_correlated},
      {"height_direction_correlated", &models::G2_height_direction_correlated}};
  m.def("G2", [g2](const models::Ndf& n, py::object o, py::object i, py::object mm, const std::string& form) {
    if (form == "vcavity")
      return map_directions({o, i, mm}, [](const Vec3* d) { return models::vcavity_G2(d[0], d[1], d[2]); });
    auto it = g2.find(form);
    if (it == g2.end())
      throw UsageError("form must be separable, height_correlated, direction_correlated, "
                            "height_direction_correlated or vcavity (got '" + form + "')");
    auto f = it->second;
    return map_directions({o, i, mm}, [&](const Vec3* d) { return f(n, d[0], d[1], d[2]); });
  }, py::arg("ndf"), py::arg("o"), py::arg("i"), py::arg("m"), py::arg("form") = "height_correlated",
     "Smith G2(o, i, m): [Heitz14, eq. 20] separable, (21) height_correlated, (22) direction_correlated, "
     "(23) height_direction_correlated; or the V-cavity [Heitz14, Sec. 6]");
  m.def("g2_forms_from_lambda", [](double lo, double li, double phi) {
    const models::G2Forms f = models::g2_forms_from_lambda(lo, li, phi);
    return py::dict(py::arg("separable") = f.separable, py::arg("height_correlated") = f.height_correlated,
                    py::arg("direction_correlated") = f.direction_correlated,
                    py::arg("height_direction_correlated") = f.height_direction_correlated);
  }, py::arg("lambda_o"), py::arg("lambda_i"), py::arg("phi"),
     "The four Smith G2 forms [Heitz14, eq. 20-23] from two Lambda values and the azimuth difference");
  m.def("vcavity_G1", [](py::object v, py::object mm) {
    return map_directions({v, mm}, [](const Vec3* d) { return models::vcavity_G1(d[0], d[1]); });
  }, py::arg("v"), py::arg("m"), "V-cavity G1(v, m), [Heitz14, eq. 24]");

  // Fresnel [GeomBSDF24, eq. 8]: unpolarized reflectance, or (Rs, Rp).
  m.def("fresnel_dielectric", py::vectorize(&models::fresnel_dielectric_unpolarized), py::arg("cos_i"),
        py::arg("eta"), "Unpolarized dielectric reflectance (eta = far side / near side; 1 beyond the critical angle)");
  m.def("fresnel_dielectric_sp", [](double c, double eta) {
    const auto r = models::fresnel_dielectric(c, eta);
    return py::make_tuple(r.Rs, r.Rp);
  }, py::arg("cos_i"), py::arg("eta"), "(Rs, Rp) of a dielectric interface");
  m.def("fresnel_dielectric_transmittance",
        py::vectorize([](double c, double eta) { return models::fresnel_dielectric_transmittance(c, eta).unpolarized(); }),
        py::arg("cos_i"), py::arg("eta"), "Unpolarized power transmittance of a dielectric interface");
  m.def("fresnel_conductor",
        py::vectorize([](double c, double eta, double k) { return models::fresnel_conductor(c, eta, k).unpolarized(); }),
        py::arg("cos_i"), py::arg("eta"), py::arg("k"), "Unpolarized conductor reflectance, complex index eta + i k");
  m.def("fresnel_conductor_sp", [](double c, double eta, double k) {
    const auto r = models::fresnel_conductor(c, eta, k);
    return py::make_tuple(r.Rs, r.Rp);
  }, py::arg("cos_i"), py::arg("eta"), py::arg("k"), "(Rs, Rp) of a conductor");

  // Spectral conductors: the shipped tables of measured optical constants and the colour of a
  // sampled spectrum (models/metals.hpp, models/spectral_rgb.hpp).
  m.def("metal_names", &models::metal_names, "Symbols of the shipped optical-constant tables");
  m.def("metal_index", [](const std::string& symbol, double nm) {
    const models::OpticalConstant c = models::metal_table(symbol).at(nm);
    return py::make_tuple(c.n, c.k);
  }, py::arg("symbol"), py::arg("wavelength_nm"),
     "(n, k) of a shipped metal at a wavelength in nm, linear between the table's rows");
  m.def("spectrum_to_rgb", [](const std::vector<double>& nm, const std::vector<double>& values) {
    if (values.size() != nm.size()) throw std::invalid_argument("one value per wavelength");
    const auto c = models::SpectrumToRgb(nm).rgb(values);
    return py::make_tuple(c[0], c[1], c[2]);
  }, py::arg("wavelengths_nm"), py::arg("values"),
     "White-balanced linear sRGB of a sampled spectrum (CIE 1931 2-degree observer, equal-energy white)");

  py::class_<models::Material>(m, "Material", "Facet material: mirror, conductor or dielectric")
      .def_static("mirror", &models::Material::mirror)
      .def_static("conductor", &models::Material::conductor, py::arg("eta"), py::arg("k"))
      .def_static("dielectric", &models::Material::dielectric, py::arg("eta"))
      .def_property_readonly("kind", [](const models::Material& x) { return models::to_string(x.kind); })
      .def_readonly("eta", &models::Material::eta)
      .def_readonly("k", &models::Material::k)
      .def("reflectance", py::vectorize([](models::Material x, double c, bool above) {
        return x.reflectance(c, above);
      }), py::arg("cos_i"), py::arg("from_above") = true, "Unpolarized facet reflectance");

  py::class_<models::MicrofacetBsdf>(m, "MicrofacetBSDF",
                                      "Single-scattering microfacet BRDF/BTDF ([GeomBSDF24, eq. 21d], [Heitz14, eq. 18], [RefractionBlog24, eq. 6])")
      .def(py::init([](const models::Ndf& n, const models::Material& mat, const std::string& masking) {
        return models::MicrofacetBsdf{n, mat, masking_of(masking)};
      }), py::arg("ndf"), py::arg("material") = models::Material::mirror(),
         py::arg("masking") = "smith_height_correlated")
      .def_readonly("ndf", &models::MicrofacetBsdf::ndf)
      .def_readonly("material", &models::MicrofacetBsdf::material)
      .def_property_readonly("masking", [](const models::MicrofacetBsdf& b) { return models::to_string(b.masking); })
      .def("eval", [](const models::MicrofacetBsdf& b, py::object o, py::object i) {
        return map_directions({o, i}, [&](const Vec3* d) { return b.eval(d[0], d[1]); });
      }, py::arg("o"), py::arg("i"), "f(o, i): reflection on the same side, transmission across")
      .def("albedo", [](const models::MicrofacetBsdf& b, py::array_t<double> i, int n) {
        Array a = Array::ensure(i);
        if (a.size() != 3) throw UsageError("i must be one direction (3 numbers)");
        const auto r = models::single_scattering_albedo(b, Vec3(a.data()[0], a.data()[1], a.data()[2]), n);
        return py::make_tuple(r.reflected, r.transmitted);
      }, py::arg("i"), py::arg("n") = 1024, "Single-scattering albedo (reflected, transmitted) for light from i");
}

}  // namespace microsim::python
