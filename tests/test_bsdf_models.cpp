// Tests of the BSDF models: Fresnel (models/fresnel.hpp), the single-scattering microfacet
// BSDF and its pieces (models/microfacet_bsdf.hpp) and the Smith random-walk multiple-scattering
// model (models/smith_random_walk.hpp).
//
// Exact identities are checked to rounding level; integrals by deterministic quadrature with
// tolerances far above the quadrature error (checked by refinement) and far below the size of a
// plausible mistake (a wrong eta factor is a factor 2.25); the random walk by z-tests against
// its own standard error with fixed seeds (Sidak-corrected where several are tested together).
#include <gtest/gtest.h>

#include "microsim/measure/stats.hpp"
#include "microsim/statistics.hpp"

#include <microsim/common.hpp>
#include <microsim/models/fresnel.hpp>
#include <microsim/models/microfacet_bsdf.hpp>
#include <microsim/models/smith_random_walk.hpp>

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace {

namespace mm = microsim::models;
using mm::Material;
using mm::MicrofacetBsdf;
using mm::Masking;
using mm::Ndf;
using mm::Vec3;
using microsim::CounterRng;

constexpr double kPi = 3.14159265358979323846;

Vec3 dir(double theta, double phi) {
  return Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
}
double rad(double d) { return d * kPi / 180.0; }

using microsim::sidak_z;  // microsim/measure/stats.hpp

// Orthonormal tangents of a unit vector.
void tangents(const Vec3& c, Vec3& a, Vec3& b) {
  a = (std::abs(c.z()) < 0.9 ? c.cross(Vec3::UnitZ()) : c.cross(Vec3::UnitX())).normalized();
  b = c.cross(a);
}

// Integral of f over the sphere in polar coordinates around `center`: rho in [0, pi] by
// Gauss-Legendre panels refined geometrically toward rho = 0 (edges scale * 2^k), phi by the
// periodic trapezoid rule. Resolves lobes of angular width ~scale centered on `center`.
template <class F>
double integrate_sphere_around(const F& f, const Vec3& center, double scale, int nphi = 256) {
  Vec3 a, b;
  tangents(center, a, b);
  std::vector<double> edges = {0.0};
  for (double e = scale / 64; e < kPi; e *= 1.5) edges.push_back(e);
  edges.push_back(kPi);
  const auto gl = mm::detail::gauss_legendre(12);
  double sum = 0.0;
  for (std::size_t k = 0; k + 1 < edges.size(); ++k) {
    const double mid = 0.5 * (edges[k] + edges[k + 1]), half = 0.5 * (edges[k + 1] - edges[k]);
    for (const auto& [x, w] : gl) {
      const double rho = mid + half * x;
      const double s = std::sin(rho), c = std::cos(rho);
      double row = 0.0;
      for (int j = 0; j < nphi; ++j) {
        const double phi = 2 * kPi * (j + 0.5) / nphi;
        row += f(c * center + s * (std::cos(phi) * a + std::sin(phi) * b));
      }
      sum += w * half * s * row * (2 * kPi / nphi);
    }
  }
  return sum;
}

// ---------------------------------------------------------------------------------------------
// Fresnel
// ---------------------------------------------------------------------------------------------

TEST(Fresnel, ReflectedPlusTransmittedIsOne) {
  // R from the reflected amplitudes, T from the transmitted ones: independent formulas.
  for (double n : {1.5, 1.0 / 1.5, 2.4, 1.0001, 0.3})
    for (int k = 0; k <= 100; ++k) {
      const double c = k / 100.0;
      const auto R = mm::fresnel_dielectric(c, n);
      const auto T = mm::fresnel_dielectric_transmittance(c, n);
      EXPECT_NEAR(R.Rs + T.Rs, 1.0, 1e-12) << "n=" << n << " cos=" << c;
      EXPECT_NEAR(R.Rp + T.Rp, 1.0, 1e-12) << "n=" << n << " cos=" << c;
      EXPECT_GE(R.Rs, R.Rp - 1e-15);  // s always reflects at least as much as p
    }
}

TEST(Fresnel, MatchesClosedFormsOfEq8b) {
  // [GeomBSDF24, eq. 8b/8c] (labels as in the physics convention, see fresnel.hpp).
  for (double n : {1.5, 1.0 / 1.33})
    for (double tdeg = 1.0; tdeg < 89.5; tdeg += 2.0) {
      const double tv = rad(tdeg);
      const double st = std::sin(tv) / n;
      if (st >= 1.0) continue;
      const double tt = std::asin(st);
      const auto R = mm::fresnel_dielectric(std::cos(tv), n);
      const double rs = std::sin(tv - tt) / std::sin(tv + tt);
      const double rp = (std::sin(2 * tv) - std::sin(2 * tt)) / (std::sin(2 * tv) + std::sin(2 * tt));
      EXPECT_NEAR(R.Rs, rs * rs, 1e-12) << tdeg;
      EXPECT_NEAR(R.Rp, rp * rp, 1e-12) << tdeg;
      EXPECT_NEAR(R.unpolarized(), 0.5 * (rs * rs + rp * rp), 1e-12);
      EXPECT_NEAR(R.polarized(0.5), R.unpolarized(), 1e-15);
    }
  // Normal incidence ((n-1)/(n+1))^2, Brewster's angle tan(theta_B) = n zeroes R_p.
  const double n = 1.5;
  EXPECT_NEAR(mm::fresnel_dielectric(1.0, n).unpolarized(), 0.04, 1e-15);
  const double tb = std::atan(n);
  EXPECT_NEAR(mm::fresnel_dielectric(std::cos(tb), n).Rp, 0.0, 1e-15);
  EXPECT_GT(mm::fresnel_dielectric(std::cos(tb), n).Rs, 0.1);
  // Symmetry of the two sides [GeomBSDF24, after eq. 8c]: F(theta_v, n) = F(theta_t, 1/n).
  for (double tdeg = 0; tdeg < 89; tdeg += 7) {
    const double ci = std::cos(rad(tdeg));
    const double ct = mm::fresnel_cos_transmitted(ci, n);
    EXPECT_NEAR(mm::fresnel_dielectric_unpolarized(ci, n), mm::fresnel_dielectric_unpolarized(ct, 1 / n), 1e-14);
  }
}

TEST(Fresnel, TotalInternalReflection) {
  const double n = 1.0 / 1.5, critical = std::asin(n);
  EXPECT_EQ(mm::fresnel_dielectric_unpolarized(std::cos(critical + 1e-6), n), 1.0);
  EXPECT_LT(mm::fresnel_dielectric_unpolarized(std::cos(critical - 1e-3), n), 1.0);
  EXPECT_NEAR(mm::fresnel_dielectric_unpolarized(std::cos(critical - 1e-9), n), 1.0, 1e-3);
  EXPECT_LT(mm::fresnel_cos_transmitted(std::cos(critical + 1e-6), n), 0.0);
}

TEST(Fresnel, Conductor) {
  // k = 0 is a dielectric (also with total internal reflection).
  for (double eta : {1.5, 0.7})
    for (double c = 0.0; c <= 1.0; c += 0.05) {
      const auto a = mm::fresnel_conductor(c, eta, 0.0), b = mm::fresnel_dielectric(c, eta);
      EXPECT_NEAR(a.Rs, b.Rs, 1e-12);
      EXPECT_NEAR(a.Rp, b.Rp, 1e-12);
    }
  // Normal incidence: ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2); grazing: 1. Gold-like index.
  const double eta = 0.2, k = 3.4;
  const double r0 = ((eta - 1) * (eta - 1) + k * k) / ((eta + 1) * (eta + 1) + k * k);
  EXPECT_NEAR(mm::fresnel_conductor(1.0, eta, k).Rs, r0, 1e-14);
  EXPECT_NEAR(mm::fresnel_conductor(1.0, eta, k).Rp, r0, 1e-14);
  EXPECT_NEAR(mm::fresnel_conductor(0.0, eta, k).unpolarized(), 1.0, 1e-14);
  // Absorption: R < 1 everywhere except grazing; the p minimum (pseudo-Brewster) is > 0.
  for (double c = 0.01; c <= 1.0; c += 0.01) {
    const auto R = mm::fresnel_conductor(c, eta, k);
    EXPECT_LT(R.unpolarized(), 1.0);
    EXPECT_GT(R.Rp, 0.0);
    EXPECT_GE(R.Rs, R.Rp);
  }
}

// ---------------------------------------------------------------------------------------------
// Reflection / refraction vectors, inverse maps, Jacobians
// ---------------------------------------------------------------------------------------------

std::vector<std::pair<Vec3, Vec3>> view_normal_pairs() {
  std::vector<std::pair<Vec3, Vec3>> out;
  CounterRng rng(7, 1, 0);
  while (out.size() < 200) {
    // Draws in named variables: the order of evaluation of call arguments is unspecified.
    const double uv_t = rng.uniform(), uv_p = rng.uniform();
    const double um_t = rng.uniform(), um_p = rng.uniform();
    const Vec3 v = dir(std::acos(uv_t), 2 * kPi * uv_p);
    const Vec3 m = dir(0.45 * kPi * um_t, 2 * kPi * um_p);
    if (v.dot(m) > 0.05) out.push_back({v, m});
  }
  return out;
}

TEST(MicrofacetVectors, ReflectionAndItsInverse) {
  for (const auto& [vb, m] : view_normal_pairs()) {
    const Vec3 v = vb;  // a lambda cannot capture a structured binding in C++17
    const Vec3 r = mm::reflect(v, m);  // [GeomBSDF24, eq. 13a]
    EXPECT_NEAR(r.norm(), 1.0, 1e-14);
    EXPECT_NEAR(r.dot(m), v.dot(m), 1e-14);
    EXPECT_LT((mm::half_vector_reflection(v, r) - m).norm(), 1e-12);  // 13b inverts 13a
  }
}

TEST(MicrofacetVectors, RefractionAndItsInverse) {
  for (double e : {1.0 / 1.5, 1.5, 1.0 / 2.4})
    for (const auto& [vb, m] : view_normal_pairs()) {
      const Vec3 v = vb;  // a lambda cannot capture a structured binding in C++17
      Vec3 t;
      if (!mm::refract(v, m, e, &t)) {  // total internal reflection only when e |v x m| > 1
        EXPECT_GT(e * v.cross(m).norm(), 1.0 - 1e-12);
        continue;
      }
      EXPECT_NEAR(t.norm(), 1.0, 1e-13);
      EXPECT_LT(t.dot(m), 0.0);                                     // crosses the facet
      EXPECT_NEAR(t.cross(m).norm(), e * v.cross(m).norm(), 1e-13);  // Snell [GeomBSDF24, eq. 5a]
      EXPECT_NEAR(v.cross(m).normalized().dot(t.cross(m).normalized()), -1.0, 1e-9);  // coplanar, opposite
      EXPECT_LT((mm::half_vector_refraction(v, t, e) - m).norm(), 1e-11);  // 15b inverts 15a
    }
}

// Solid-angle ratio of the map d -> m(d) at d by central differences (parallelogram areas).
template <class Map>
double numeric_jacobian(const Map& map, const Vec3& d, double h = 1e-5) {
  Vec3 a, b;
  tangents(d, a, b);
  const Vec3 da = (d + h * a).normalized() - (d - h * a).normalized();
  const Vec3 db = (d + h * b).normalized() - (d - h * b).normalized();
  const Vec3 ma = map((d + h * a).normalized()) - map((d - h * a).normalized());
  const Vec3 mb = map((d + h * b).normalized()) - map((d - h * b).normalized());
  return ma.cross(mb).norm() / da.cross(db).norm();
}

TEST(Jacobians, ReflectionMatchesFiniteDifferences) {
  for (const auto& [vb, m] : view_normal_pairs()) {
    const Vec3 v = vb;  // a lambda cannot capture a structured binding in C++17
    const Vec3 r = mm::reflect(v, m);
    const double numeric = numeric_jacobian([&](const Vec3& d) { return mm::half_vector_reflection(v, d); }, r);
    const double exact = mm::jacobian_reflection(r, m);  // [GeomBSDF24, eq. 19b]
    EXPECT_NEAR(numeric / exact, 1.0, 1e-6);
    EXPECT_NEAR(exact, r.dot(m) / (r + v).squaredNorm(), 1e-12 * exact);  // first form of 19b
  }
}

TEST(Jacobians, RefractionMatchesFiniteDifferences) {
  for (double e : {1.0 / 1.5, 1.5})
    for (const auto& [vb, m] : view_normal_pairs()) {
      const Vec3 v = vb;  // a lambda cannot capture a structured binding in C++17
      Vec3 t;
      if (!mm::refract(v, m, e, &t)) continue;
      if (e * v.cross(m).norm() > 0.98) continue;  // too close to the critical angle for differences
      const double numeric =
          numeric_jacobian([&](const Vec3& d) { return mm::half_vector_refraction(v, d, e); }, t);
      const double exact = mm::jacobian_refraction(v, t, m, e);  // [GeomBSDF24, eq. 20b]
      EXPECT_NEAR(numeric / exact, 1.0, 1e-5);
      // The other two forms of 20b.
      const double ct = std::abs(t.dot(m)), cv = v.dot(m);
      EXPECT_NEAR(exact, ct / std::pow(e * cv - ct, 2), 1e-10 * exact);
      const double st2 = t.cross(m).squaredNorm();
      EXPECT_NEAR(exact, ct / std::pow(std::sqrt(e * e - st2) + t.dot(m), 2), 1e-9 * exact);
    }
}

// ---------------------------------------------------------------------------------------------
// Microfacet sampling: visible normals [Heitz14, eq. 13] mapped to reflected or refracted directions
// have the density D_v(h) |J(h, o)| [GeomBSDF24, eq. 19b / 20b] at the half vector h of the direction
// [GeomBSDF24, eq. 13b / 15b], checked by the chi-square harness on the sphere; refused samples (total
// internal reflection) against the mass the density leaves out. Power: the density without
// its Jacobian (reflection), or with a 5% wrong index ratio (refraction), renormalized.
// ---------------------------------------------------------------------------------------------
struct SamplingCase {
  const char* name;
  mm::Distribution kind;
  double alpha, theta_deg;
  double eta_ratio;  // 0: reflection; otherwise refraction with e = eta_v / eta_t
};
class MicrofacetSampling : public ::testing::TestWithParam<SamplingCase> {};

TEST_P(MicrofacetSampling, DirectionsFollowTheJacobianDensity) {
  const SamplingCase& c = GetParam();
  const Ndf ndf = c.kind == mm::Distribution::Beckmann ? Ndf::beckmann(c.alpha, c.alpha) : Ndf::ggx(c.alpha, c.alpha);
  const Vec3 v = dir(rad(c.theta_deg), 0.3);
  const bool reflection = c.eta_ratio == 0;
  // Density of the outgoing direction o under the map with index ratio e (0: reflection).
  auto density = [&](double e, bool with_jacobian) {
    return [&ndf, v, e, with_jacobian](const Vec3& o) {
      const Vec3 h = e == 0 ? mm::half_vector_reflection(v, o) : mm::half_vector_refraction(v, o, e);
      if (!(h.z() > 0) || !(v.dot(h) > 0)) return 0.0;
      if (e != 0 && !(o.dot(h) < 0)) return 0.0;  // a refracted direction crosses its facet
      const double j = !with_jacobian ? 1.0 : e == 0 ? mm::jacobian_reflection(o, h) : mm::jacobian_refraction(v, o, h, e);
      return ndf.D_visible(v, h) * j;
    };
  };
  microsim::ChiSquareTest::Options o;
  o.samples = 200000;
  o.res_u = 32;
  o.res_v = 64;
  o.seed = 17;
  microsim::ChiSquareTest t(
      microsim::ChiSquareDomain::sphere(),
      [&](CounterRng& rng) -> std::optional<Vec3> {
        const double u1 = rng.uniform(), u2 = rng.uniform();
        const Vec3 m = ndf.sample_visible_normal(v, u1, u2);
        if (reflection) return mm::reflect(v, m);
        Vec3 out;
        if (!mm::refract(v, m, c.eta_ratio, &out)) return std::nullopt;
        return out;
      },
      density(c.eta_ratio, true), o);
  const microsim::ChiSquareResult& r = t.run();
  EXPECT_TRUE(r.passed(0.01, 4)) << t.describe();  // family-wise over the four cases
  if (reflection) { EXPECT_NEAR(t.pdf_integral(), 1.0, 1e-3); }
  const microsim::ChiSquareResult w =
      reflection ? t.run_against(density(0, false), true) : t.run_against(density(1.05 * c.eta_ratio, true), true);
  EXPECT_LT(w.p_value, 1e-4) << w.summary();
  std::printf("[ info ] %s\n[ info ] wrong density: %s\n", r.summary().c_str(), w.summary().c_str());
}
INSTANTIATE_TEST_SUITE_P(
    MicrofacetBsdf, MicrofacetSampling,
    ::testing::Values(SamplingCase{"ggx_reflection", mm::Distribution::GGX, 0.4, 60.0, 0.0},
                      SamplingCase{"beckmann_reflection", mm::Distribution::Beckmann, 0.3, 30.0, 0.0},
                      SamplingCase{"ggx_refraction_into_glass", mm::Distribution::GGX, 0.4, 50.0, 1 / 1.5},
                      SamplingCase{"beckmann_refraction_out_of_glass", mm::Distribution::Beckmann, 0.4, 20.0, 1.5}),
    [](const ::testing::TestParamInfo<SamplingCase>& i) { return std::string(i.param.name); });

// ---------------------------------------------------------------------------------------------
// Single-scattering BSDF
// ---------------------------------------------------------------------------------------------

TEST(MicrofacetBsdf, ReciprocityWithEtaSquared) {
  // [GeomBSDF24, eq. 4c]: f(o, i) / f(i, o) = eta_o^2 / eta_i^2 (1 for reflection).
  CounterRng rng(3, 2, 0);
  int transmissions = 0, reflections = 0;
  for (auto kind : {mm::Distribution::Beckmann, mm::Distribution::GGX})
    for (auto masking : {Masking::SmithHeightCorrelated, Masking::VCavity})
      for (double eta : {1.5, 1.0 / 1.5}) {
        const Ndf ndf = kind == mm::Distribution::Beckmann ? Ndf::beckmann(0.4, 0.7) : Ndf::ggx(0.6, 0.3);
        const MicrofacetBsdf f{ndf, Material::dielectric(eta), masking};
        for (int k = 0; k < 400; ++k) {
          const double uo_t = rng.uniform(), uo_p = rng.uniform();
          const double ui_t = rng.uniform(), ui_p = rng.uniform();
          const Vec3 o = dir(std::acos(2 * uo_t - 1), 2 * kPi * uo_p);
          const Vec3 i = dir(std::acos(2 * ui_t - 1), 2 * kPi * ui_p);
          const double a = f.eval(o, i), b = f.eval(i, o);
          const double eo = o.z() > 0 ? 1.0 : eta, ei = i.z() > 0 ? 1.0 : eta;
          if (a == 0.0) {
            EXPECT_EQ(b, 0.0);
            continue;
          }
          ((o.z() > 0) == (i.z() > 0) ? reflections : transmissions)++;
          EXPECT_NEAR(a / b, eo * eo / (ei * ei), 1e-10) << "o=" << o.transpose() << " i=" << i.transpose();
        }
      }
  EXPECT_GT(transmissions, 200);
  EXPECT_GT(reflections, 200);
}

TEST(MicrofacetBsdf, WeakWhiteFurnaceEq19) {
  // [Heitz14, eq. 19]: int G1(o, m) D(m) / (4 |o.n|) d omega_i = 1 (F = 1, masking only, i over the
  // whole sphere), here through MicrofacetBsdf::eval: int f(o, i) |i.n| d omega_i = 1.
  // (GGX only up to alpha = 0.6: its D does not vanish at the horizon of m, so at alpha = 1 the
  // integrand jumps across the curve m.z = 0 and this quadrature converges only to ~1e-3.)
  for (auto kind : {mm::Distribution::Beckmann, mm::Distribution::GGX})
    for (double alpha : {0.2, 0.6, 1.0})
      for (double tdeg : {0.0, 40.0, 75.0}) {
        if (kind == mm::Distribution::GGX && alpha > 0.6) continue;
        const Ndf ndf = kind == mm::Distribution::Beckmann ? Ndf::beckmann(alpha, alpha) : Ndf::ggx(alpha, alpha);
        const MicrofacetBsdf f{ndf, Material::mirror(), Masking::SmithMaskingOnly};
        const Vec3 o = dir(rad(tdeg), 0.3);
        const Vec3 spec(-o.x(), -o.y(), o.z());
        const double I = integrate_sphere_around([&](const Vec3& i) { return f.eval(o, i) * std::abs(i.z()); },
                                                 spec, alpha);
        EXPECT_NEAR(I, 1.0, 2e-4) << mm::to_string(kind) << " alpha=" << alpha << " theta=" << tdeg;
      }
  // With shadowing (height-correlated G2) the single-scattering BRDF loses energy [Heitz14, Table 3c].
  const MicrofacetBsdf hc{Ndf::beckmann(0.6, 0.6), Material::mirror(), Masking::SmithHeightCorrelated};
  const Vec3 o = dir(rad(60), 0.0);
  const double I = integrate_sphere_around([&](const Vec3& i) { return hc.eval(o, i) * std::abs(i.z()); },
                                           Vec3(-o.x(), -o.y(), o.z()), 0.6);
  EXPECT_LT(I, 0.97);
}

TEST(MicrofacetBsdf, SmoothLimitGivesEq7dAndEq10b) {
  // 7d: int f_r(v, l) dOmega_n(l) = F; 10b: int (eta_l^2/eta_v^2) f_t(v, l) dOmega_n(l) = 1 - F,
  // for the rough BSDF at small roughness (deviation O(alpha^2)), integrating over the incident
  // directions l: this checks the BTDF's eta factor and Jacobian end to end.
  const double alpha = 0.02;
  for (double eta : {1.5, 1.0 / 1.5})
    for (bool v_above : {true, false})
      for (double tdeg : {0.0, 30.0, 55.0}) {
        const MicrofacetBsdf f{Ndf::beckmann(alpha, alpha), Material::dielectric(eta), Masking::SmithHeightCorrelated};
        Vec3 v = dir(rad(tdeg), 0.0);
        if (!v_above) v = mm::mirror_z(v);
        const double eta_v = v_above ? 1.0 : eta, eta_t = v_above ? eta : 1.0;
        const double F = mm::fresnel_dielectric_unpolarized(std::cos(rad(tdeg)), eta_t / eta_v);
        const Vec3 spec(-v.x(), -v.y(), v.z());
        const double R = integrate_sphere_around(
            [&](const Vec3& l) { return l.z() * v.z() > 0 ? f.eval(v, l) * std::abs(l.z()) : 0.0; }, spec, alpha);
        EXPECT_NEAR(R, F, 2e-3) << "eta=" << eta << " above=" << v_above << " theta=" << tdeg;
        if (F >= 1.0) continue;
        // refracted direction of v at the macro normal ([GeomBSDF24, eq. 15a] with m = n)
        Vec3 t;
        ASSERT_TRUE(mm::refract(v, v_above ? Vec3::UnitZ() : Vec3(-Vec3::UnitZ()), eta_v / eta_t, &t));
        const double T = integrate_sphere_around(
            [&](const Vec3& l) {
              return l.z() * v.z() < 0 ? (eta_t * eta_t) / (eta_v * eta_v) * f.eval(v, l) * std::abs(l.z()) : 0.0;
            },
            t, alpha * 0.5);
        EXPECT_NEAR(T, 1.0 - F, 2e-3) << "eta=" << eta << " above=" << v_above << " theta=" << tdeg;
        EXPECT_NEAR(R + T, 1.0, 3e-3);
      }
}

// single_scattering_albedo (VNDF quadrature, G2/G1) against int f(o, i) |o.z| d omega_o (eval:
// D, Jacobians, eta factors; midpoint rule in (theta_o, phi_o)): two independent routes.
struct AlbedoCase {
  Masking masking;
  double eta, tdeg;
};
class AlbedoFromVisibleNormals : public ::testing::TestWithParam<AlbedoCase> {};

TEST_P(AlbedoFromVisibleNormals, MatchesIntegralOfEval) {
  const auto [masking, eta, tdeg] = GetParam();
  const double alpha = 0.5;
  const MicrofacetBsdf f{Ndf::beckmann(alpha, alpha), Material::dielectric(eta), masking};
  const Vec3 i = dir(rad(tdeg), 0.0);
  const auto a = mm::single_scattering_albedo(f, i, 1024);
  const int N = 700, M = 700;  // theta_o in [0, pi], phi_o in [0, pi] (mirror symmetric in y)
  double R = 0, T = 0;
  for (int p = 0; p < N; ++p) {
    const double th = (p + 0.5) / N * kPi, st = std::sin(th), ct = std::cos(th);
    for (int q = 0; q < M; ++q) {
      const double ph = (q + 0.5) / M * kPi;
      const double v = f.eval(Vec3(st * std::cos(ph), st * std::sin(ph), ct), i) * std::abs(ct) * st;
      (ct > 0 ? R : T) += v;
    }
  }
  R *= 2 * (kPi / N) * (kPi / M);
  T *= 2 * (kPi / N) * (kPi / M);
  EXPECT_NEAR(a.reflected, R, 1e-4);
  EXPECT_NEAR(a.transmitted, T, 1e-4);
  EXPECT_LT(a.reflected + a.transmitted, 1.0);
  EXPECT_GT(a.reflected + a.transmitted, 0.7);
}
INSTANTIATE_TEST_SUITE_P(MicrofacetBsdf, AlbedoFromVisibleNormals,
                         ::testing::Values(AlbedoCase{Masking::SmithHeightCorrelated, 1.5, 60.0},
                                           AlbedoCase{Masking::SmithHeightCorrelated, 1 / 1.5, 0.0},
                                           AlbedoCase{Masking::VCavity, 1.5, 0.0},
                                           AlbedoCase{Masking::VCavity, 1 / 1.5, 60.0}),
                         [](const ::testing::TestParamInfo<AlbedoCase>& i) {
                           return std::string(i.param.masking == Masking::VCavity ? "vcavity" : "smith_height_correlated") +
                                  (i.param.eta > 1 ? "_eta150" : "_eta067") + "_theta" +
                                  std::to_string(static_cast<int>(i.param.tdeg));
                         });

// ---------------------------------------------------------------------------------------------
// Smith random walk
// ---------------------------------------------------------------------------------------------

struct Rng {
  CounterRng r;
  double uniform() { return r.uniform(); }
};
auto rng_factory(std::uint64_t seed, std::uint64_t stream) {
  return [=](std::uint64_t k) { return Rng{CounterRng(seed, stream, k)}; };
}

// sample_visible_normal_any for u.z < 0 against the density max(0, u.m) D(m) / (|u.z| Lambda(-u)),
// by the chi-square harness: its integral of the density checks the visible-area formula, the
// histogram checks the sampler, and the same samples refuse the density of a 5% larger roughness.
struct BelowHorizonCase {
  mm::Distribution kind;
  double theta_deg;
};
class VisibleNormalsBelowTheHorizon : public ::testing::TestWithParam<BelowHorizonCase> {};

TEST_P(VisibleNormalsBelowTheHorizon, FollowTheirDensity) {
  const mm::Distribution kind = GetParam().kind;  // named variables, not structured bindings:
  const double tdeg = GetParam().theta_deg;       // C++17 lambdas may not capture those
  auto make = [&](double s) { return kind == mm::Distribution::Beckmann ? Ndf::beckmann(0.5 * s, 0.8 * s) : Ndf::ggx(0.5 * s, 0.8 * s); };
  const Ndf ndf = make(1.0);
  const Vec3 u = dir(rad(tdeg), 0.7);
  auto density = [](const Ndf& d, const Vec3& u) {
    const double area = std::abs(u.z()) * d.Lambda(-u);
    return [u, d, area](const Vec3& m) { return std::max(0.0, u.dot(m)) * d.D(m) / area; };
  };
  CounterRng check(11, 5, static_cast<std::uint64_t>(tdeg));
  for (int k = 0; k < 2000; ++k) {
    const double u1 = check.uniform(), u2 = check.uniform();
    const Vec3 m = mm::sample_visible_normal_any(ndf, u, u1, u2);
    ASSERT_NEAR(m.norm(), 1.0, 1e-12);
    ASSERT_GT(u.dot(m), -1e-12);
    ASSERT_GE(m.z(), 0.0);
  }
  microsim::ChiSquareTest::Options o;
  o.samples = 200000;
  o.seed = 11 + static_cast<std::uint64_t>(tdeg);
  o.res_u = 32;
  o.res_v = 64;
  // Equal-area cells: below the horizon the visible normals crowd toward theta_m = 90 degrees.
  microsim::ChiSquareTest t(
      microsim::ChiSquareDomain::hemisphere(),
      [&](CounterRng& rng) -> std::optional<Vec3> {
        const double u1 = rng.uniform(), u2 = rng.uniform();
        return mm::sample_visible_normal_any(ndf, u, u1, u2);
      },
      density(ndf, u), o);
  const microsim::ChiSquareResult& r = t.run();
  EXPECT_NEAR(t.pdf_integral(), 1.0, 5e-4);  // the normalization |u.z| Lambda(-u)
  EXPECT_TRUE(r.passed(0.01, 6)) << t.describe();  // family-wise over the six cases
  // Power: the visible half-space without the projection factor u.m (renormalized). (A 5% wrong
  // roughness is refused for Beckmann but not for GGX at 120 and 160 degrees: GGX's far tail,
  // normalized, hardly depends on alpha.)
  const microsim::ChiSquareResult w =
      t.run_against([&](const Vec3& m) { return u.dot(m) > 0 ? ndf.D(m) : 0.0; }, true);
  EXPECT_LT(w.p_value, 1e-4) << w.summary();
  std::printf("[ info ] %s\n[ info ] without u.m: %s\n", r.summary().c_str(), w.summary().c_str());
}
std::string below_horizon_name(const ::testing::TestParamInfo<BelowHorizonCase>& i) {
  return std::string(mm::to_string(i.param.kind)) + "_theta" + std::to_string(static_cast<int>(i.param.theta_deg));
}
INSTANTIATE_TEST_SUITE_P(SmithWalk, VisibleNormalsBelowTheHorizon,
                         ::testing::Values(BelowHorizonCase{mm::Distribution::Beckmann, 95.0},
                                           BelowHorizonCase{mm::Distribution::Beckmann, 120.0},
                                           BelowHorizonCase{mm::Distribution::Beckmann, 160.0},
                                           BelowHorizonCase{mm::Distribution::GGX, 95.0},
                                           BelowHorizonCase{mm::Distribution::GGX, 120.0},
                                           BelowHorizonCase{mm::Distribution::GGX, 160.0}),
                         below_horizon_name);

// The walk's order-1 term is the single-scattering BSDF with height-correlated Smith G2.
struct OrderOneCase {
  const char* name;
  Ndf ndf;
  Material mat;
  double theta_deg;
};
const OrderOneCase kOrderOneCases[] = {
    {"beckmann50_mirror_theta0", Ndf::beckmann(0.5, 0.5), Material::mirror(), 0.0},
    {"beckmann100_mirror_theta60", Ndf::beckmann(1.0, 1.0), Material::mirror(), 60.0},
    {"ggx70_mirror_theta70", Ndf::ggx(0.7, 0.7), Material::mirror(), 70.0},
    {"beckmann50_conductor_theta60", Ndf::beckmann(0.5, 0.5), Material::conductor(0.2, 3.4), 60.0},
    {"beckmann50_dielectric150_theta0", Ndf::beckmann(0.5, 0.5), Material::dielectric(1.5), 0.0},
    {"beckmann50_dielectric150_theta60", Ndf::beckmann(0.5, 0.5), Material::dielectric(1.5), 60.0},
    {"ggx60_dielectric067_theta30", Ndf::ggx(0.6, 0.6), Material::dielectric(1.0 / 1.5), 30.0},
    // large Lambda on both sides: distinguishes the transmission G2 B(1+Lo, 1+Li) from
    // 1/(1 + Lo + Li) (they differ at second order in Lambda)
    {"beckmann100_dielectric150_theta80", Ndf::beckmann(1.0, 1.0), Material::dielectric(1.5), 80.0},
};
constexpr int kOrderOneTests = 2 * static_cast<int>(sizeof(kOrderOneCases) / sizeof(kOrderOneCases[0]));
class OrderOne : public ::testing::TestWithParam<int> {};

TEST_P(OrderOne, EqualsSingleScatteringAlbedo) {
  const int c = GetParam();
  const OrderOneCase& cs = kOrderOneCases[c];
  const int n = 200000;
  const double zmax = sidak_z(0.01, kOrderOneTests);
  const Vec3 wi = dir(rad(cs.theta_deg), 0.4);
  const mm::SmithRandomWalk walk(cs.ndf, cs.mat);
  const auto a = mm::smith_walk_albedos(walk, wi, n, 4, rng_factory(5, 100 + c));
  const auto ref = mm::single_scattering_albedo(MicrofacetBsdf{cs.ndf, cs.mat, Masking::SmithHeightCorrelated}, wi, 384);
  EXPECT_EQ(a.lost, 0u);
  const double zr = (a.mean(0, 0) - ref.reflected) / a.stderr_(0, 0);
  EXPECT_LT(std::abs(zr), zmax) << "R1 walk " << a.mean(0, 0) << " +- " << a.stderr_(0, 0) << " model " << ref.reflected;
  if (cs.mat.transmits()) {
    const double zt = (a.mean(1, 0) - ref.transmitted) / a.stderr_(1, 0);
    EXPECT_LT(std::abs(zt), zmax) << "T1 walk " << a.mean(1, 0) << " +- " << a.stderr_(1, 0) << " model " << ref.transmitted;
  }
}
INSTANTIATE_TEST_SUITE_P(SmithWalk, OrderOne, ::testing::Range(0, kOrderOneTests / 2),
                         [](const ::testing::TestParamInfo<int>& i) { return std::string(kOrderOneCases[i.param].name); });

// The directions of the walks that leave after one event follow the single-scattering BSDF:
// density f(o, i) |o.z| on the sphere (reflection above, transmission below), of mass the
// order-1 albedo; the other walks are refused draws. Power: the V-cavity G2 and a 5% wrong
// roughness (renormalized to the same mass) are refused by the same directions.
struct WalkDirectionCase {
  const char* name;
  Ndf ndf;
  Material mat;
  double theta_deg;
};
class WalkOrderOneDirections : public ::testing::TestWithParam<WalkDirectionCase> {};

TEST_P(WalkOrderOneDirections, FollowTheSingleScatteringBsdf) {
  const WalkDirectionCase& c = GetParam();
  const Vec3 wi = dir(rad(c.theta_deg), 0.4);
  const mm::SmithRandomWalk walk(c.ndf, c.mat);
  const MicrofacetBsdf f{c.ndf, c.mat, Masking::SmithHeightCorrelated};
  const MicrofacetBsdf vc{c.ndf, c.mat, Masking::VCavity};
  const Ndf wider = c.ndf.kind == mm::Distribution::Beckmann ? Ndf::beckmann(1.05 * c.ndf.alpha_x, 1.05 * c.ndf.alpha_y)
                                                             : Ndf::ggx(1.05 * c.ndf.alpha_x, 1.05 * c.ndf.alpha_y);
  const MicrofacetBsdf fw{wider, c.mat, Masking::SmithHeightCorrelated};
  microsim::ChiSquareTest::Options o;
  o.samples = 200000;
  o.res_u = 32;
  o.res_v = 64;
  o.seed = 23;
  microsim::ChiSquareTest t(
      microsim::ChiSquareDomain::sphere(),
      [&](CounterRng& rng) -> std::optional<Vec3> {
        const mm::WalkExit e = walk.walk(wi, rng);
        if (e.lost || e.order != 1) return std::nullopt;
        return e.direction;
      },
      [&](const Vec3& d) { return f.eval(d, wi) * std::abs(d.z()); }, o);
  const microsim::ChiSquareResult& r = t.run();
  EXPECT_TRUE(r.passed(0.01, 2)) << t.describe();  // family-wise over the two cases
  const microsim::ChiSquareResult wv = t.run_against([&](const Vec3& d) { return vc.eval(d, wi) * std::abs(d.z()); }, true);
  const microsim::ChiSquareResult wa = t.run_against([&](const Vec3& d) { return fw.eval(d, wi) * std::abs(d.z()); }, true);
  EXPECT_LT(wv.p_value, 1e-4) << wv.summary();
  EXPECT_LT(wa.p_value, 1e-4) << wa.summary();
  std::printf("[ info ] %s (order-1 mass %.4f)\n[ info ] V-cavity G2: %s\n[ info ] alpha x1.05: %s\n", r.summary().c_str(),
              t.pdf_integral(), wv.summary().c_str(), wa.summary().c_str());
}
INSTANTIATE_TEST_SUITE_P(
    SmithWalk, WalkOrderOneDirections,
    ::testing::Values(WalkDirectionCase{"beckmann50_mirror_theta60", Ndf::beckmann(0.5, 0.5), Material::mirror(), 60.0},
                      WalkDirectionCase{"ggx50_dielectric150_theta40", Ndf::ggx(0.5, 0.5), Material::dielectric(1.5), 40.0}),
    [](const ::testing::TestParamInfo<WalkDirectionCase>& i) { return std::string(i.param.name); });

TEST(SmithWalk, OrderOneRejectsTheWrongShadowing) {
  // Power: the separable G2 [Heitz14, eq. 20] is far outside the walk's error at grazing incidence.
  const Ndf ndf = Ndf::beckmann(1.0, 1.0);
  const Vec3 wi = dir(rad(70), 0.0);
  const auto a = mm::smith_walk_albedos(mm::SmithRandomWalk(ndf, Material::mirror()), wi, 100000, 4, rng_factory(5, 9));
  // separable form via VNDF quadrature
  double s = 0.0;
  const int q = 256;
  for (int p = 0; p < q; ++p)
    for (int r = 0; r < q; ++r) {
      const Vec3 m = ndf.sample_visible_normal(wi, (p + 0.5) / q, (r + 0.5) / q);
      const Vec3 o = mm::reflect(wi, m);
      if (o.z() > 0) s += mm::G2_separable(ndf, o, wi, m) / ndf.G1(wi);
    }
  s /= q * q;
  EXPECT_GT(std::abs(a.mean(0, 0) - s) / a.stderr_(0, 0), 10.0);
}

// f of the walk averaged over a cone of half-angle `cone` around d (exits of orders >= min_order
// on the side of d), from n walks: p / int_cone |cos| d omega, with its standard error.
std::pair<double, double> walk_f_in_cone(const mm::SmithRandomWalk& w, const Vec3& wi, const Vec3& d, double cone,
                                         int min_order, int n, std::uint64_t stream) {
  int hits = 0;
  for (int k = 0; k < n; ++k) {
    Rng rng{CounterRng(17, stream, k)};
    const mm::WalkExit e = w.walk(wi, rng);
    if (e.lost || e.order < min_order) continue;
    if (e.direction.dot(d) >= std::cos(cone)) ++hits;
  }
  // int over the cone of |cos theta| d omega, by the midpoint rule in the cone's polar coordinates
  Vec3 a, b;
  tangents(d, a, b);
  double ci = 0.0;
  const int nr = 200, np = 200;
  for (int i = 0; i < nr; ++i)
    for (int j = 0; j < np; ++j) {
      const double r = (i + 0.5) / nr * cone, ph = 2 * kPi * (j + 0.5) / np;
      const Vec3 v = std::cos(r) * d + std::sin(r) * (std::cos(ph) * a + std::sin(ph) * b);
      ci += std::abs(v.z()) * std::sin(r);
    }
  ci *= (cone / nr) * (2 * kPi / np);
  const double p = static_cast<double>(hits) / n;
  return {p / ci, std::sqrt(p * (1 - p) / n) / ci};
}

TEST(SmithWalk, MultipleScatteringIsReciprocal) {
  // [GeomBSDF24, eq. 4c] for the walk's orders >= 2 (mirror) and all orders of the transmission (light
  // from below = the same Smith surface mirrored with the inverse index): an independent check
  // of the height and direction sampling beyond order 1.
  const Ndf ndf = Ndf::beckmann(1.0, 1.0);
  const double cone = rad(6);
  const int n = 600000;
  std::vector<double> zs;
  {
    const mm::SmithRandomWalk w(ndf, Material::mirror());
    const Vec3 a = dir(rad(30), 0.0), b = dir(rad(65), kPi);
    const auto f1 = walk_f_in_cone(w, a, b, cone, 2, n, 1);
    const auto f2 = walk_f_in_cone(w, b, a, cone, 2, n, 2);
    zs.push_back((f1.first - f2.first) / std::hypot(f1.second, f2.second));
    EXPECT_GT(f1.first, 20 * f1.second);
  }
  {
    const double eta = 1.5;
    const mm::SmithRandomWalk down(ndf, Material::dielectric(eta)), up(ndf, Material::dielectric(1 / eta));
    const Vec3 a = dir(rad(40), 0.0), b = mm::mirror_z(dir(rad(20), kPi));  // above -> below
    const auto f1 = walk_f_in_cone(down, a, b, cone, 1, n, 3);
    // reverse: light from b (below) toward a: in the mirrored frame light from mirror(b) above,
    // leaving toward mirror(a) below
    const auto f2 = walk_f_in_cone(up, mm::mirror_z(b), mm::mirror_z(a), cone, 1, n, 4);
    // f(b <- a) / eta_b^2 = f(a <- b) / eta_a^2
    zs.push_back((f1.first / (eta * eta) - f2.first) / std::hypot(f1.second / (eta * eta), f2.second));
    EXPECT_GT(f1.first, 20 * f1.second);
  }
  for (double z : zs) EXPECT_LT(std::abs(z), sidak_z(0.01, 2)) << z;
}

TEST(SmithWalk, OrderTwoMatchesAnIndependentEstimator) {
  // Order 2 of the mirror walk against an estimator that draws the second intersection height
  // from a different (tempered) proposal and weights by the Smith intersection density, instead
  // of inverting that density as the walk does. Densities in c = C1(h): upward ray from c1,
  // p(c) = L c1^L c^(-L-1) on (c1, 1) (mass 1 - c1^L; it escapes otherwise), proposal with L/2;
  // downward ray, p(c) = (1+L') c^L' / c1^(1+L') on (0, c1), proposal with (1+L')/2.
  // With a = -(L/2) ln c1 the upward weight p/q is 2 ((1-u) + u e^-a)(1 - e^-a), the downward 2u.
  for (const auto& [alpha, tdeg] : {std::pair{1.0, 60.0}, std::pair{0.5, 0.0}, std::pair{1.0, 0.0}}) {
    const Ndf ndf = Ndf::beckmann(alpha, alpha);
    const Vec3 wi = dir(rad(tdeg), 0.0);
    const int n = 300000;
    double sum = 0.0, sum2 = 0.0;
    for (int k = 0; k < n; ++k) {
      CounterRng rng(23, 1, k);
      const double c1 = std::pow(1.0 - rng.uniform(), 1.0 / (1.0 + ndf.Lambda(wi)));
      const double a1 = rng.uniform(), b1 = rng.uniform();
      const Vec3 m1 = ndf.sample_visible_normal(wi, a1, b1);
      const Vec3 w1 = mm::reflect(wi, m1);
      const double u = rng.uniform();
      double c2, weight;
      if (w1.z() > 0) {
        const double L = ndf.Lambda(w1);
        const double a = -0.5 * L * std::log(c1);
        const double g = (1.0 - u) + u * std::exp(-a);
        c2 = std::isinf(L) ? c1 : L > 1e-200 ? std::exp(-(2.0 / L) * (a + std::log(g))) : 1.0;
        weight = 2.0 * g * (1.0 - std::exp(-a));
      } else {
        const double L = ndf.Lambda(-w1);
        c2 = c1 * std::pow(u, 2.0 / (1.0 + L));
        weight = 2.0 * u;
      }
      const double a2 = rng.uniform(), b2 = rng.uniform();
      const Vec3 m2 = mm::sample_visible_normal_any(ndf, -w1, a2, b2);
      const Vec3 w2 = mm::reflect(-w1, m2);
      const double x = w2.z() > 0 ? weight * std::pow(c2, ndf.Lambda(w2)) : 0.0;
      sum += x;
      sum2 += x * x;
    }
    const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / (n - 1));
    const auto a = mm::smith_walk_albedos(mm::SmithRandomWalk(ndf, Material::mirror()), wi, n, 4, rng_factory(29, 1));
    std::printf("order 2: walk %.5f +- %.5f, weighted %.5f +- %.5f\n", a.mean(0, 1), a.stderr_(0, 1), mean, se);
    EXPECT_LT(std::abs(a.mean(0, 1) - mean) / std::hypot(a.stderr_(0, 1), se), sidak_z(0.01, 3))
        << alpha << " " << tdeg << ": walk " << a.mean(0, 1) << " +- " << a.stderr_(0, 1) << ", weighted " << mean
        << " +- " << se;
  }
}

TEST(SmithWalk, EnergyConservation) {
  const int n = 50000;
  const Vec3 wi = dir(rad(60), 0.0);
  for (double alpha : {0.3, 1.0}) {
    const Ndf ndf = Ndf::beckmann(alpha, alpha);
    // Mirror: every walk leaves upward with weight 1 (white furnace, [Heitz14, Sec. 4.3]).
    const auto m = mm::smith_walk_albedos(mm::SmithRandomWalk(ndf, Material::mirror()), wi, n, 4, rng_factory(1, 1));
    EXPECT_EQ(m.lost, 0u);
    EXPECT_DOUBLE_EQ(m.mean(0, 4), 1.0);
    EXPECT_EQ(m.mean(1, 4), 0.0);
    // Dielectric: every walk leaves, up or down: R + T = 1 (both sides, TIR included).
    for (double eta : {1.5, 1.0 / 1.5}) {
      const auto d = mm::smith_walk_albedos(mm::SmithRandomWalk(ndf, Material::dielectric(eta)), wi, n, 4,
                                            rng_factory(1, 2));
      EXPECT_EQ(d.lost, 0u);
      EXPECT_NEAR(d.mean(0, 4) + d.mean(1, 4), 1.0, 1e-12);
      EXPECT_GT(d.mean(1, 4), eta > 1 ? 0.5 : 0.01);  // 60 deg is beyond the critical angle for 1/1.5
      double orders = 0;
      for (int k = 0; k < 4; ++k) orders += d.mean(0, k) + d.mean(1, k);
      EXPECT_NEAR(orders, 1.0, 1e-12);
    }
    // Conductor: the same random numbers give the same paths as the mirror (the conductor draws
    // nothing more), weighted by the product of Fresnel factors: per order below the mirror,
    // equal to it when F -> 1.
    const auto c = mm::smith_walk_albedos(mm::SmithRandomWalk(ndf, Material::conductor(0.2, 3.4)), wi, n, 4,
                                          rng_factory(1, 1));
    for (int k = 0; k <= 4; ++k) EXPECT_LT(c.mean(0, k), m.mean(0, k));
    EXPECT_GT(c.mean(0, 4), 0.5);
    const auto c1 = mm::smith_walk_albedos(mm::SmithRandomWalk(ndf, Material::conductor(1.0, 1e7)), wi, n, 4,
                                           rng_factory(1, 1));
    for (int k = 0; k <= 4; ++k) EXPECT_NEAR(c1.mean(0, k), m.mean(0, k), 1e-5);
  }
}

TEST(SmithWalk, HeightDistributionDoesNotMatter) {
  // Under Smith the walk depends on heights only through C1(h): uniform and Gaussian heights
  // with the same random numbers give the same albedos (up to rounding of C1 o C1^-1).
  const Vec3 wi = dir(rad(75), 0.0);
  for (auto mat : {Material::mirror(), Material::dielectric(1.5)}) {
    const Ndf ndf = Ndf::beckmann(0.8, 0.8);
    const mm::SmithRandomWalk u(ndf, mat, mm::HeightDistribution::Uniform);
    const mm::SmithRandomWalk g(ndf, mat, mm::HeightDistribution::Gaussian);
    const auto a = mm::smith_walk_albedos(u, wi, 50000, 4, rng_factory(3, 3));
    const auto b = mm::smith_walk_albedos(g, wi, 50000, 4, rng_factory(3, 3));
    for (int s = 0; s < 2; ++s)
      for (int k = 0; k <= 4; ++k) EXPECT_NEAR(a.mean(s, k), b.mean(s, k), 1e-3) << s << " " << k;
    EXPECT_GT(a.mean(0, 1) + a.mean(1, 1), 0.01) << a.mean(0, 1) << " " << a.mean(1, 1);  // multiple scattering to compare
  }
  // The Gaussian quantile inverts the CDF.
  mm::SmithHeights gh{mm::HeightDistribution::Gaussian};
  for (double u : {1e-12, 1e-5, 0.01, 0.3, 0.5, 0.77, 0.999, 1 - 1e-9})
    EXPECT_NEAR(gh.C1(gh.invC1(u)), u, 1e-14 + 1e-12 * std::min(u, 1 - u));
}

}  // namespace
