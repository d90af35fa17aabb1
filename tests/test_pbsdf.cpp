// Polarized BRDF tables for Mitsuba 3's measured_polarized (io/pbsdf.hpp): the node geometry
// against the plugin's Rusinkiewicz conversion and Stokes frames (written here from its
// description in docs/theory/polarization.md), a flat-Fresnel table at specular configurations,
// the NaN domain, and the file round trip.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>

#include "microsim/common.hpp"
#include "microsim/io/pbsdf.hpp"
#include "microsim/io/rgl_reader.hpp"

using namespace microsim;
using models::Mueller;

namespace {

Vec3 rotate_z(const Vec3& v, double a) {
  return Vec3(std::cos(a) * v.x() - std::sin(a) * v.y(), std::sin(a) * v.x() + std::cos(a) * v.y(), v.z());
}

// The plugin's reference axes, step by step as it builds them: the incoming beam travels along
// z_i = -l, t_i = normalize((l - v) x z_i), y_i = normalize(t_i x z_i), x_i = y_i x z_i; the
// outgoing one along z_o = v, t_o = normalize((v - l) x z_o), y_o = normalize(t_o x z_o), x_o = y_o x z_o.
void plugin_axes(const Vec3& l, const Vec3& v, Vec3* x_in, Vec3* x_out) {
  const Vec3 zi = -l, ti = (l - v).cross(zi).normalized(), yi = ti.cross(zi).normalized();
  *x_in = yi.cross(zi);
  const Vec3 zo = v, to = (v - l).cross(zo).normalized(), yo = to.cross(zo).normalized();
  *x_out = yo.cross(zo);
}

const std::vector<std::uint16_t> kWavelengths = {450, 500, 550, 600, 650};

// A wavelength-dependent conductor (the index varies with the wavelength so that the
// wavelength axis of the table is checked too).
models::Material gold_at(double nm) { return models::Material::conductor(0.47 + (nm - 450) / 1000, 2.4 - (nm - 450) / 500); }

// The facet Fresnel matrix of the half vector, in microsim's frames: a smooth-facet pBRDF
// without D and G.
Mueller half_vector_fresnel(const Vec3& l, const Vec3& v, double nm) {
  const Vec3 h = (l + v).normalized();
  return models::path_mueller(l, {{h, false}}, gold_at(nm)).M;
}

}  // namespace

TEST(Pbsdf, NodesInvertThePluginsRusinkiewiczConversion) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0;
  for (int k = 0; k < 500; ++k) {
    const double th = 0.02 + 1.5 * u(rng), td = 0.02 + 1.5 * u(rng), pd = -3.1 + 6.2 * u(rng);
    const RusinkiewiczPair r = directions_of_rusinkiewicz(th, td, pd);
    // The view is the light mirrored about h; the angles come back, also after a rotation about z.
    EXPECT_LT((r.view - (2 * r.light.dot(r.h) * r.h - r.light)).norm(), 1e-14);
    const double psi = 6.28 * u(rng);
    double a, b, c;
    rusinkiewicz_of_directions(rotate_z(r.light, psi), rotate_z(r.view, psi), &a, &b, &c);
    worst = std::max({worst, std::abs(a - th), std::abs(b - td), std::abs(c - pd)});
    // The plugin's axes are p x h for both beams (= normalize(l x v)).
    Vec3 xi, xo;
    plugin_axes(r.light, r.view, &xi, &xo);
    worst = std::max({worst, (xi - pbsdf_reference_axis(r)).norm(), (xo - pbsdf_reference_axis(r)).norm(),
                      (r.light.cross(r.view).normalized() - pbsdf_reference_axis(r)).norm()});
  }
  EXPECT_LT(worst, 1e-9);
}

// A table of the half-vector facet's Fresnel matrix: at every valid node the plugin-frame block is
// the closed-form s/p Fresnel matrix at cos(theta_d), whatever theta_h and phi_d (the frames are
// the s axes of the facet h), and M00 is the unpolarized reflectance.
TEST(Pbsdf, FlatFresnelTableIsTheSpMatrixAtThetaD) {
  const PolarizedTable t = fill_pbsdf(evenly_spaced(0, kPi / 2, 10), evenly_spaced(0, kPi / 2, 9),
                                      evenly_spaced(-kPi, kPi, 13), kWavelengths, half_vector_fresnel);
  double worst = 0.0, worst_m00 = 0.0, off_frame = 0.0;
  int valid = 0;
  for (std::size_t p = 0; p < t.phi_d.size(); ++p)
    for (std::size_t d = 0; d < t.theta_d.size(); ++d)
      for (std::size_t h = 0; h < t.theta_h.size(); ++h)
        for (std::size_t l = 0; l < 5; ++l) {
          const Mueller m = t.block(p, d, h, l);
          if (std::isnan(m(0, 0))) continue;
          ++valid;
          const double c = std::cos(static_cast<double>(t.theta_d[d]));
          const models::Material mat = gold_at(t.wavelengths[l]);
          const Mueller expected = models::facet_reflection_mueller(mat, c);
          worst = std::max(worst, (m - expected).cwiseAbs().maxCoeff());
          worst_m00 = std::max(worst_m00, std::abs(m(0, 0) - models::fresnel_conductor(c, mat.eta, mat.k).unpolarized()));
          // The same matrix left in microsim's frames differs off the plane of incidence.
          const RusinkiewiczPair r = directions_of_rusinkiewicz(t.theta_h[h], t.theta_d[d], t.phi_d[p]);
          off_frame = std::max(off_frame, (half_vector_fresnel(r.light, r.view, t.wavelengths[l]) - expected).cwiseAbs().maxCoeff());
        }
  EXPECT_GT(valid, 1000);
  EXPECT_LT(worst, 2e-7);  // float32 storage
  EXPECT_LT(worst_m00, 1e-7);
  EXPECT_GT(off_frame, 0.1);
}

// NaN exactly where a direction is below the horizon: l.z = cos td cos th - sin td sin th cos pd,
// v.z = cos td cos th + sin td sin th cos pd, both >= 0 iff tan td tan th |cos pd| <= 1.
TEST(Pbsdf, NanOutsideTheUpperHemisphere) {
  const PolarizedTable t = fill_pbsdf(evenly_spaced(0, kPi / 2, 12), evenly_spaced(0, kPi / 2, 11),
                                      evenly_spaced(-kPi, kPi, 17), kWavelengths, half_vector_fresnel);
  int nan = 0, checked = 0;
  for (std::size_t p = 0; p < t.phi_d.size(); ++p)
    for (std::size_t d = 0; d < t.theta_d.size(); ++d)
      for (std::size_t h = 0; h < t.theta_h.size(); ++h) {
        const double th = t.theta_h[h], td = t.theta_d[d], pd = t.phi_d[p];
        const double a = std::cos(td) * std::cos(th), b = std::sin(td) * std::sin(th) * std::abs(std::cos(pd));
        if (std::abs(a - b) < 1e-6) continue;  // grazing to rounding
        ++checked;
        const bool below = b > a;
        for (std::size_t l = 0; l < 5; ++l)
          for (int k = 0; k < 16; ++k) EXPECT_EQ(std::isnan(t.M[t.offset(p, d, h, l) + k]), below);
        nan += below;
      }
  EXPECT_GT(checked, 1500);
  EXPECT_GT(nan, 300);
}

// An isotropic pBRDF in microsim's frames gives one plugin-frame matrix per node whatever the
// azimuth of the pair: the conversion is covariant.
TEST(Pbsdf, ConversionIsTheSameForEveryAzimuthOfThePair) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0;
  for (int k = 0; k < 200; ++k) {
    const RusinkiewiczPair r = directions_of_rusinkiewicz(0.05 + 0.7 * u(rng), 0.05 + 0.7 * u(rng), -3 + 6 * u(rng));
    const Mueller ref = to_pbsdf_frames(half_vector_fresnel(r.light, r.view, 550), r);
    const double psi = 6.28 * u(rng);
    RusinkiewiczPair q = r;
    q.light = rotate_z(r.light, psi);
    q.view = rotate_z(r.view, psi);
    q.h = rotate_z(r.h, psi);
    q.p = rotate_z(r.p, psi);
    worst = std::max(worst, (to_pbsdf_frames(half_vector_fresnel(q.light, q.view, 550), q) - ref).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-12);
}

TEST(Pbsdf, FileRoundTripAndRefusals) {
  const PolarizedTable t = fill_pbsdf(evenly_spaced(0, kPi / 2, 5), evenly_spaced(0, kPi / 2, 4),
                                      evenly_spaced(-kPi, kPi, 7), kWavelengths, half_vector_fresnel);
  const std::string path = ::testing::TempDir() + "/round_trip.pbsdf";
  write_pbsdf(path, t);
  const PolarizedTable r = read_pbsdf(path);
  EXPECT_EQ(r.theta_h, t.theta_h);
  EXPECT_EQ(r.theta_d, t.theta_d);
  EXPECT_EQ(r.phi_d, t.phi_d);
  EXPECT_EQ(r.wavelengths, t.wavelengths);
  ASSERT_EQ(r.M.size(), t.M.size());
  EXPECT_EQ(std::memcmp(r.M.data(), t.M.data(), t.M.size() * sizeof(float)), 0);  // NaNs included
  // The fields as the plugin checks them: 2-dimensional float32 grids, uint16 wavelengths, M of rank 6.
  const auto f = read_tensor_file(path);
  EXPECT_EQ(f.at("theta_h").shape, (std::vector<std::uint64_t>{1, 5}));
  EXPECT_EQ(f.at("wvls").dtype, 3);
  EXPECT_EQ(f.at("M").shape, (std::vector<std::uint64_t>{7, 4, 5, 5, 4, 4}));
  // Refused: four wavelengths (the plugin reads five), a decreasing grid, a table of the wrong size.
  PolarizedTable bad = t;
  bad.wavelengths.pop_back();
  EXPECT_THROW(write_pbsdf(path + ".x", bad), UsageError);
  bad = t;
  std::swap(bad.theta_d[0], bad.theta_d[1]);
  EXPECT_THROW(write_pbsdf(path + ".x", bad), UsageError);
  bad = t;
  bad.M.pop_back();
  EXPECT_THROW(write_pbsdf(path + ".x", bad), UsageError);
  EXPECT_FALSE(std::filesystem::exists(path + ".x"));
  // A tensor file without the pbsdf fields.
  write_tensor_file(path + ".y", {TensorField::f32("theta_h", {5}, t.theta_h)});
  EXPECT_THROW(read_pbsdf(path + ".y"), UsageError);
  std::remove(path.c_str());
  std::remove((path + ".y").c_str());
}
