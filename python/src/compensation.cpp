// microsim.models energy compensation: the E_ss table, the Kulla-Conty and Turquin lobes and their
// hemisphere maps, the Smith walk's and the V-cavity model's maps of orders >= 2, and the Hellinger lobe
// distance (models/energy_compensation.hpp, measure/compensation_maps.hpp, measure/vcavity_multiple_map.hpp).
//
// Maps are returned as (R, R) arrays in the row order of the EXR files of `measure bsdf` (row 0 is the top,
// square coordinate b = +1), so that they compare pixel by pixel with the measured channels.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "microsim/measure/compensation_maps.hpp"
#include "microsim/measure/vcavity_multiple_map.hpp"
#include "microsim/models/energy_compensation.hpp"

namespace py = pybind11;

namespace microsim::python {

namespace {
Vec3 direction_of(const std::vector<double>& d) {
  if (d.size() != 3) throw std::invalid_argument("a direction is 3 numbers");
  return Vec3(d[0], d[1], d[2]).normalized();
}

// HemisphereMap pixel order (j R + i, b increasing with j) -> EXR image order (row y = R - 1 - j).
py::array_t<double> image_of(const HemisphereMap& map, const std::vector<double>& f) {
  const int R = map.resolution();
  py::array_t<double> out({R, R});
  auto a = out.mutable_unchecked<2>();
  for (int px = 0; px < map.size(); ++px) a(R - 1 - px / R, px % R) = f[px];
  return out;
}
std::vector<double> pixels_of(const HemisphereMap& map, py::array_t<double, py::array::c_style | py::array::forcecast> img) {
  const int R = map.resolution();
  if (img.ndim() != 2 || img.shape(0) != R || img.shape(1) != R) throw std::invalid_argument("map must be (R, R)");
  auto a = img.unchecked<2>();
  std::vector<double> f(map.size());
  for (int px = 0; px < map.size(); ++px) f[px] = a(R - 1 - px / R, px % R);
  return f;
}
}  // namespace

void bind_compensation(py::module_& m) {
  m.def("directional_albedo_ss", &models::directional_albedo_ss, py::arg("ndf"), py::arg("mu"), py::arg("n") = 256,
        "E_ss(mu): albedo of the height-correlated Smith single-scattering BRDF with F = 1");
  m.def("fresnel_average", &models::fresnel_average, py::arg("material"), "F_avg = 2 int F(mu) mu dmu");
  py::class_<models::EssTable>(m, "EssTable", "E_ss tabulated in sqrt(mu) (cubic Hermite)")
      .def(py::init<const models::Ndf&, int, int>(), py::arg("ndf"), py::arg("nodes") = 65, py::arg("quadrature_n") = 256)
      .def("E", [](const models::EssTable& t, py::array_t<double, py::array::c_style | py::array::forcecast> mu) {
        py::array_t<double> out(mu.request().shape);
        const double* in = mu.data();
        double* o = out.mutable_data();
        for (py::ssize_t k = 0; k < mu.size(); ++k) o[k] = t.E(in[k]);
        return out;
      }, py::arg("mu"))
      .def_property_readonly("E_avg", &models::EssTable::E_avg)
      .def_property_readonly("nodes", &models::EssTable::nodes)
      .def("interpolation_error", &models::EssTable::interpolation_error, py::arg("first") = 0);
  // Lobe maps for light from i: kind 'kulla_conty' (f_ms), 'turquin' (the multiple-scattering lobe
  // f_ss F0 (1 - E) / E) or 'single' (f_ss with the material's Fresnel).
  m.def("compensation_map", [](const models::EssTable& t, const models::Material& mat, const std::string& kind,
                               const std::vector<double>& i, int resolution, int sub) {
        const HemisphereMap map(resolution);
        const Vec3 wi = direction_of(i);
        const models::KullaContyLobe kc(t, mat);
        const models::TurquinLobe tq(t, mat);
        LobeFunction f;
        if (kind == "kulla_conty") f = [&](const Vec3& o) { return kc.eval(o, wi); };
        else if (kind == "turquin") f = [&](const Vec3& o) { return tq.eval(o, wi); };
        else if (kind == "single") f = [&](const Vec3& o) { return tq.single.eval(o, wi); };
        else throw std::invalid_argument("kind must be kulla_conty, turquin or single");
        std::vector<double> px;
        {
          py::gil_scoped_release release;
          px = lobe_map(map, f, sub);
        }
        return image_of(map, px);
      }, py::arg("table"), py::arg("material"), py::arg("kind"), py::arg("i"), py::arg("resolution"), py::arg("sub") = 8);
  m.def("kulla_conty_fresnel_factor", &models::KullaContyLobe::fresnel_factor_of, py::arg("f_avg"), py::arg("e_avg"));
  m.def("smith_walk_map", [](const models::Ndf& ndf, const models::Material& mat, const std::vector<double>& i,
                             int resolution, int min_order, std::uint64_t walks, std::uint64_t seed) {
        const HemisphereMap map(resolution);
        WalkMap w;
        {
          py::gil_scoped_release release;
          w = smith_walk_map(ndf, mat, direction_of(i), map, min_order, walks, seed);
        }
        return py::make_tuple(image_of(map, w.f), w.albedo);
      }, py::arg("ndf"), py::arg("material"), py::arg("i"), py::arg("resolution"), py::arg("min_order") = 2,
      py::arg("walks") = 1000000, py::arg("seed") = 1,
      "(map of the Smith walk's orders >= min_order, their albedo)");
  m.def("vcavity_multiple_map", [](const models::Ndf& ndf, const models::Material& mat, const std::vector<double>& i,
                                   int resolution, int min_order, int orders, int n_theta, int n_phi) {
        const HemisphereMap map(resolution);
        GrooveLobeMaps g;
        {
          py::gil_scoped_release release;
          g = vcavity_multiple_maps(ndf, mat, direction_of(i), map, orders, n_theta, n_phi);
        }
        return py::make_tuple(image_of(map, g.f_from_order(min_order)), g.albedo_from_order(min_order),
                              g.albedo[orders]);
      }, py::arg("ndf"), py::arg("material"), py::arg("i"), py::arg("resolution"), py::arg("min_order") = 2,
      py::arg("orders") = 4, py::arg("n_theta") = 1024, py::arg("n_phi") = 1024,
      "(map of the V-cavity multiple-scattering model's orders >= min_order, their albedo, the total albedo): "
      "every V-groove's interreflections in closed form, grooves weighted by (n.m) D(m)");
  m.def("hemisphere_cos_integrals", [](int resolution) {
        const HemisphereMap map(resolution);
        std::vector<double> c(map.size());
        for (int px = 0; px < map.size(); ++px) c[px] = map.pixel_cos_integral(px);
        return image_of(map, c);
      }, py::arg("resolution"), "int_pixel |cos| d omega of every pixel, in image order");
  m.def("hellinger_distance", [](py::array_t<double, py::array::c_style | py::array::forcecast> f,
                                 py::array_t<double, py::array::c_style | py::array::forcecast> g) {
        if (f.ndim() != 2) throw std::invalid_argument("map must be (R, R)");
        const HemisphereMap map(static_cast<int>(f.shape(0)));
        return hellinger_distance(map, pixels_of(map, f), pixels_of(map, g));
      }, py::arg("f"), py::arg("g"), "Hellinger distance between the power distributions of two maps");
}

}  // namespace microsim::python
