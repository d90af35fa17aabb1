// Energy-compensation models (models/energy_compensation.hpp) and the lobe maps and distance
// (measure/compensation_maps.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/measure/compensation_maps.hpp"
#include "microsim/models/energy_compensation.hpp"

using namespace microsim;
using models::EssTable;
using models::Material;
using models::Ndf;

namespace {
Vec3 incidence(double theta_deg) {
  const double t = theta_deg * kPi / 180.0;
  return Vec3(std::sin(t), 0.0, std::cos(t));
}

// int f(o, i) o.z d omega_o by Monte Carlo with cosine-weighted o (pi E[f]): an estimate of the albedo that
// does not use the visible-normal sampler of the quadrature. Returns mean and standard error.
std::pair<double, double> albedo_monte_carlo(const models::MicrofacetBsdf& b, const Vec3& i, int n) {
  double s = 0.0, s2 = 0.0;
  for (int k = 0; k < n; ++k) {
    CounterRng rng(7, 3, k);
    const double r = std::sqrt(rng.uniform()), phi = 2.0 * kPi * rng.uniform();
    const Vec3 o(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - r * r)));
    const double x = kPi * b.eval(o, i);
    s += x;
    s2 += x * x;
  }
  const double m = s / n;
  return {m, std::sqrt((s2 / n - m * m) / (n - 1))};
}
}  // namespace

TEST(EnergyCompensation, EssMatchesMonteCarloOfTheSmithBrdf) {
  for (const Ndf& ndf : {Ndf::beckmann(0.7, 0.7), Ndf::ggx(0.5, 0.5)})
    for (double th : {0.0, 60.0, 80.0}) {
      const Vec3 i = incidence(th);
      const double e = models::directional_albedo_ss(ndf, i.z());
      const auto [mc, se] = albedo_monte_carlo({ndf, Material::mirror(), models::Masking::SmithHeightCorrelated}, i, 1 << 20);
      EXPECT_NEAR(e, mc, 4.0 * se) << ndf.alpha_x << " " << th;
      // The same Monte Carlo tells the V-cavity G2 apart at 80 degrees: the check resolves an error of G2.
      const auto sep = models::single_scattering_albedos(ndf, Material::mirror(), i, 256).vcavity.reflected;
      if (th == 80.0) {
        EXPECT_GT(std::abs(sep - mc), 10.0 * se) << "V-cavity G2 not resolved";
      }
    }
}

TEST(EnergyCompensation, TableInterpolationErrorAndAverage) {
  for (const Ndf& ndf : {Ndf::beckmann(0.3, 0.3), Ndf::beckmann(1.0, 1.0), Ndf::ggx(0.1, 0.1), Ndf::ggx(1.0, 1.0)}) {
    const EssTable t(ndf);
    EXPECT_LT(t.interpolation_error(1), 1e-4) << ndf.alpha_x;  // mu > 1/4096
    EXPECT_LT(t.interpolation_error(), 5e-4) << ndf.alpha_x;   // with the interval at grazing
    // The average of the interpolant against Gauss-Legendre on the quadrature itself.
    const double direct =
        models::cosine_weighted_average_sqrt([&](double mu) { return models::directional_albedo_ss(ndf, mu); }, 4);
    EXPECT_NEAR(t.E_avg(), direct, 2e-5) << ndf.alpha_x;
    EXPECT_GT(t.E_avg(), 0.4);
    EXPECT_LT(t.E_avg(), 1.0);
  }
}

TEST(EnergyCompensation, FresnelAverage) {
  EXPECT_DOUBLE_EQ(models::fresnel_average(Material::mirror()), 1.0);
  // Independent midpoint rule on 2 int F mu dmu for a dielectric-like index (k = 0): about 0.092 for 1.5.
  for (auto [eta, k] : {std::pair{1.5, 0.0}, std::pair{0.47, 2.4}, std::pair{3.2, 3.3}}) {
    const Material m = Material::conductor(eta, k);
    double s = 0.0;
    const int n = 200000;
    for (int q = 0; q < n; ++q) {
      const double mu = (q + 0.5) / n;
      s += 2.0 * m.reflectance(mu, true) * mu / n;
    }
    EXPECT_NEAR(models::fresnel_average(m), s, 1e-7) << eta << " " << k;
  }
  EXPECT_NEAR(models::fresnel_average(Material::conductor(1.5, 0.0)), 0.0918, 5e-4);
}

TEST(EnergyCompensation, KullaContyWhiteFurnaceIsExactOnTheTable) {
  const EssTable t(Ndf::beckmann(0.7, 0.7));
  const models::KullaContyLobe kc(t, Material::mirror());
  EXPECT_DOUBLE_EQ(kc.fresnel_factor, 1.0);
  for (double mu_o : {0.05, 0.5, 1.0}) {
    const Vec3 o(std::sqrt(1 - mu_o * mu_o), 0, mu_o);
    // f_ms is isotropic: int f cos d omega_i = pi * (2 int f mu dmu), on the table's own quadrature.
    const double furnace = kPi * t.average([&](double mu) { return kc.eval(o, Vec3(std::sqrt(1 - mu * mu), 0, mu)); });
    EXPECT_NEAR(furnace, 1.0 - t.E(mu_o), 1e-13);
    // E_ss + E_ms = 1 at F = 1 with E_ss from the quadrature, within the table's interpolation error.
    EXPECT_NEAR(models::directional_albedo_ss(t.ndf(), mu_o) + kc.albedo(mu_o), 1.0, t.interpolation_error() + 1e-12);
  }
}

TEST(EnergyCompensation, LobeMapsCarryTheModelsPower) {
  const HemisphereMap map(64);
  for (const Ndf& ndf : {Ndf::beckmann(0.5, 0.5), Ndf::ggx(0.7, 0.7)}) {
    const EssTable t(ndf);
    for (const Material& mat : {Material::mirror(), Material::conductor(0.47, 2.4)}) {
      const models::KullaContyLobe kc(t, mat);
      const models::TurquinLobe tq(t, mat);
      for (double th : {0.0, 60.0}) {
        const Vec3 i = incidence(th);
        // Kulla-Conty: F_ms (1 - E(mu_i)), by the map's pixel integral (independent of the mu quadrature).
        const double a_kc = map_albedo(map, lobe_map(map, [&](const Vec3& o) { return kc.eval(o, i); }, 8));
        EXPECT_NEAR(a_kc, kc.albedo(i.z()), 2e-5 * kc.albedo(i.z()) + 1e-7);
        // A lobe normalised without the 1 - E_avg of the denominator would miss by that factor.
        EXPECT_GT(std::abs(a_kc * (1.0 - t.E_avg()) - kc.albedo(i.z())), 100 * 2e-5 * kc.albedo(i.z()));
        // Turquin: scale * E_ss^F(mu_i); with F0 = 1 (mirror) f_ss + lobe integrates to 1.
        const double a_tq = map_albedo(map, lobe_map(map, [&](const Vec3& o) { return tq.eval(o, i); }, 8));
        const double e_f = models::single_scattering_albedos(ndf, mat, i, 256).smith.reflected;
        EXPECT_NEAR(a_tq, tq.scale(i.z()) * e_f, 1e-3 * a_tq);
        if (mat.kind == models::MaterialKind::Mirror) {
          EXPECT_NEAR(e_f * (1.0 + tq.scale(i.z())), 1.0, t.interpolation_error() / t.E(i.z()) + 1e-9);
        } else {
          EXPECT_NEAR(tq.F0, mat.reflectance(1.0, true), 0.0);
          EXPECT_LT(e_f * (1.0 + tq.scale(i.z())), 1.0);
        }
      }
    }
  }
}

TEST(EnergyCompensation, KullaContyFresnelFactorIsTheSeriesOfBounces) {
  // Light surviving k >= 2 bounces: sum_k F^k E (1 - E)^(k - 1), over (1 - E) (the F = 1 value).
  for (auto [f, e] : {std::pair{0.76, 0.8}, std::pair{0.3, 0.5}, std::pair{1.0, 0.6}}) {
    double s = 0.0;
    for (int k = 2; k < 2000; ++k) s += std::pow(f, k) * e * std::pow(1 - e, k - 1);
    EXPECT_NEAR(models::KullaContyLobe::fresnel_factor_of(f, e), s / (1 - e), 1e-12);
  }
}

TEST(EnergyCompensation, SmithWalkMapOfHigherOrdersHasTheMissingEnergy) {
  const Ndf ndf = Ndf::beckmann(1.0, 1.0);
  const HemisphereMap map(16);
  const Vec3 i = incidence(60);
  const std::uint64_t n = 400000;
  const WalkMap w = smith_walk_map(ndf, Material::mirror(), i, map, 2, n);
  EXPECT_NEAR(map_albedo(map, w.f), w.albedo, 1e-12);
  // Mirror: the walk's orders >= 2 are 1 - E_ss (the walk's order 1 is the single-scattering BRDF).
  const double ms = 1.0 - models::directional_albedo_ss(ndf, i.z());
  EXPECT_NEAR(w.albedo, ms, 4.0 * std::sqrt(ms * (1 - ms) / n));
}

TEST(LobeDistance, HellingerClosedForms) {
  const HemisphereMap map(8);
  std::vector<double> c(map.size());
  for (int px = 0; px < map.size(); ++px) c[px] = map.pixel_cos_integral(px);
  std::vector<double> f(map.size()), g(map.size()), h(map.size(), 0.0);
  for (int px = 0; px < map.size(); ++px) {
    f[px] = 1.0 + 0.3 * std::sin(px);  // arbitrary positive lobe
    g[px] = 5.0 * f[px];               // same shape, other albedo
  }
  EXPECT_NEAR(hellinger_distance(map, f, f), 0.0, 1e-7);
  EXPECT_NEAR(hellinger_distance(map, f, g), 0.0, 1e-7);
  // Power spread evenly over all pixels against the same over the first half: BC = 1/sqrt(2).
  std::vector<double> u(map.size()), v(map.size(), 0.0);
  for (int px = 0; px < map.size(); ++px) {
    u[px] = 1.0 / c[px];
    if (px < map.size() / 2) v[px] = 1.0 / c[px];
  }
  EXPECT_NEAR(hellinger_distance(map, u, v), std::sqrt(1.0 - 1.0 / std::sqrt(2.0)), 1e-12);
  // Disjoint supports: 1.
  std::vector<double> w(map.size(), 0.0);
  for (int px = map.size() / 2; px < map.size(); ++px) w[px] = 1.0;
  EXPECT_NEAR(hellinger_distance(map, v, w), 1.0, 1e-12);
  EXPECT_THROW(hellinger_distance(map, f, h), std::invalid_argument);
}
