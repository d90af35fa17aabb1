// Tests of the directional albedo and its lookup table (measure/albedo_measure.hpp): the white
// furnace on a mirror heightfield (E = 1 at every mu, and the order slots sum to it), the
// quadrature in mu (exact on polynomials; E_avg of a flat conductor, where E(mu) is Fresnel's
// F(mu) exactly, against an independent integral within the stated quadrature error), the
// calibration of the replicate errors (z-scores between two seeds), and the command's files.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <functional>
#include <algorithm>

#include "cli_helpers.hpp"
#include "microsim/api/albedo_resolve.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/albedo_measure.hpp"
#include "microsim/measure/stats.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;
namespace mm = microsim::models;

namespace {

AlbedoRequest mirror_request(long long rays, std::uint64_t seed = 1) {
  AlbedoRequest r;
  r.material = "mirror";
  r.rays = rays;
  r.seed = seed;
  r.mu_nodes = 8;
  r.check();
  return r;
}

// 1 - the sum of a node's reflected order slots (orders 1 .. K+), leaving out slot `dropped`
// (-1: none): the white furnace's deficit, computed from the orders rather than from the total.
double furnace_deficit(const AlbedoNode& n, int orders, int dropped = -1) {
  double sum = 0;
  for (int k = 0; k < orders; ++k)
    if (k != dropped) sum += n.side[0][k].mean;
  return 1.0 - sum;
}

// 2 int_0^1 g(mu) mu dmu by the composite Simpson rule on 20000 intervals (independent of the
// Gauss-Legendre nodes).
double simpson_average(const std::function<double(double)>& g) {
  const int n = 20000;
  double s = 0;
  for (int i = 0; i <= n; ++i) {
    const double mu = static_cast<double>(i) / n;
    const double c = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
    s += c * 2.0 * mu * g(mu);
  }
  return s / (3.0 * n);
}

}  // namespace

TEST(AlbedoQuadrature, GaussLegendreInMuIsExactOnPolynomials) {
  for (int N : {2, 5, 8, 13}) {
    const MuQuadrature q = gauss_legendre_mu(N);
    ASSERT_EQ(q.mu.size(), static_cast<std::size_t>(N));
    for (std::size_t j = 1; j < q.mu.size(); ++j) EXPECT_LT(q.mu[j - 1], q.mu[j]);
    // 2 int_0^1 mu^p mu dmu = 2 / (p + 2): exact up to p = 2N - 2, the lower rule up to its
    // subset's size - 1.
    const int low_degree = (N + 1) / 2 - 1;
    for (int p = 0; p <= 2 * N - 2; ++p) {
      double high = 0, low = 0;
      for (std::size_t j = 0; j < q.mu.size(); ++j) {
        high += q.weight[j] * std::pow(q.mu[j], p);
        low += q.low_weight[j] * std::pow(q.mu[j], p);
      }
      EXPECT_NEAR(high, 2.0 / (p + 2), 1e-13) << N << " " << p;
      if (p <= low_degree) {
        EXPECT_NEAR(low, 2.0 / (p + 2), 1e-12) << N << " " << p;
      }
    }
    // Power: one degree beyond its subset, the lower rule is no longer exact, so that |Q - Q_low|
    // sees what the nodes do not resolve.
    double beyond = 0;
    for (std::size_t j = 0; j < q.mu.size(); ++j) beyond += q.low_weight[j] * std::pow(q.mu[j], low_degree + 1);
    EXPECT_GT(std::abs(beyond - 2.0 / (low_degree + 3)), 1e-9) << N;
  }
}

TEST(AlbedoQuadrature, TrapezoidIntegratesPiecewiseLinearAlbedoExactly) {
  const std::vector<double> mu = {0.9, 0.2, 0.5, 0.7};
  const MuQuadrature q = trapezoid_mu(mu);
  ASSERT_EQ(q.mu.front(), 0.2);
  // E(mu) = 3 - 2 mu between the nodes, held constant beyond them: 2 int E mu dmu in closed form.
  auto E = [](double m) { return 3.0 - 2.0 * std::clamp(m, 0.2, 0.9); };
  std::vector<Estimate> e;
  for (double m : q.mu) e.push_back({E(m), 0.01, 1});
  const AlbedoAverage a = average_albedo(q, e);
  const double exact = E(0.2) * 0.04 + (2 * (0.9 * 0.9 - 0.04) / 2 * 3 - 2 * 2 * (0.729 - 0.008) / 3) +
                       E(0.9) * (1 - 0.81);
  EXPECT_NEAR(a.value, exact, 1e-13);
  EXPECT_NEAR(a.quadrature_error, 0.0, 1e-13);  // linear: the lower rule is exact too
  double w2 = 0;
  for (double w : q.weight) w2 += w * w;
  EXPECT_NEAR(a.stderr_, 0.01 * std::sqrt(w2), 1e-15);
}

TEST(AlbedoWhiteFurnace, MirrorHeightfieldReflectsEverythingAtEveryMu) {
  // A rough mirror (alpha 1: orders 2+ carry tens of percent at grazing) keeps all the power.
  const Microsurface s = beckmann_tile(64, 3, 1.0);
  const AlbedoRequest r = mirror_request(20000);
  const AlbedoSurface a = measure_albedo(s, "beckmann", r);
  ASSERT_EQ(a.nodes.size(), 8u);
  for (const AlbedoNode& n : a.nodes) {
    EXPECT_NEAR(n.total.mean, 1.0, 1e-4) << n.mu;
    EXPECT_NEAR(n.side[0][r.orders].mean, 1.0, 1e-4) << n.mu;
    EXPECT_NEAR(furnace_deficit(n, r.orders), 0.0, 1e-4) << n.mu;
    EXPECT_EQ(n.lost + n.unterminated, 0u) << n.mu;
    // Power: a deliberately dropped order (order 2) fails the same check at every node.
    EXPECT_GT(std::abs(furnace_deficit(n, r.orders, 1)), 1e-4) << n.mu;
  }
  const AlbedoAverage avg = average_albedo(albedo_quadrature(r), albedo_series_values(a, "albedo"));
  EXPECT_NEAR(avg.value, 1.0, 1e-4);
  const AlbedoAverage order1 = average_albedo(albedo_quadrature(r), albedo_series_values(a, "reflected_order_1"));
  EXPECT_LT(order1.value, 1.0 - 1e-2);  // the multiple scattering the compensation restores
}

TEST(AlbedoAverageQuadrature, FlatConductorMatchesIndependentFresnelIntegral) {
  // A flat conductor reflects F(mu) in order 1 exactly: E_avg by the Gauss-Legendre nodes
  // against 2 int F(mu) mu dmu by Simpson, within the stated quadrature error.
  const Microsurface s = flat_heightfield(16);
  for (const auto& [eta, k] : std::vector<std::pair<double, double>>{{1.5, 0.0}, {0.2, 3.0}, {1.1, 0.5}}) {
    AlbedoRequest r;
    r.material = "conductor";
    r.eta = eta;
    r.k = k;
    r.rays = 2000;
    r.mu_nodes = 8;
    r.check();
    const AlbedoSurface a = measure_albedo(s, "flat", r);
    auto F = [&, eta = eta, k = k](double mu) { return mm::fresnel_conductor(mu, eta, k).unpolarized(); };
    for (const AlbedoNode& n : a.nodes) EXPECT_NEAR(n.total.mean, F(n.mu), 1e-12) << n.mu;
    const AlbedoAverage avg = average_albedo(albedo_quadrature(r), albedo_series_values(a, "albedo"));
    const double exact = simpson_average(F);
    EXPECT_LE(std::abs(avg.value - exact), avg.quadrature_error + 1e-12)
        << eta << " " << k << ": " << avg.value << " vs " << exact << ", quadrature error " << avg.quadrature_error;
    std::cout << "eta " << eta << " k " << k << ": E_avg " << avg.value << ", Simpson " << exact
              << ", |difference| " << std::abs(avg.value - exact) << ", stated quadrature error "
              << avg.quadrature_error << "\n";
    EXPECT_LT(avg.quadrature_error, 1e-2) << "the estimate says nothing";
    // The 8-point rule itself is far better than its stated (lower-rule) error on a smooth F.
    EXPECT_LT(std::abs(avg.value - exact), 1e-6);
    // Power: the average without the cosine weight (int E dmu, a common slip) is off by more
    // than the stated error.
    double no_cosine = 0;
    const MuQuadrature q = albedo_quadrature(r);
    for (std::size_t j = 0; j < q.mu.size(); ++j) no_cosine += q.weight[j] / (2 * q.mu[j]) * a.nodes[j].total.mean;
    EXPECT_GT(std::abs(no_cosine - exact), avg.quadrature_error);
  }
}

TEST(AlbedoErrors, ReplicateErrorsCalibratedBetweenSeeds) {
  // Two seeds on one surface differ by ray noise only: z = (a - b) / sqrt(se_a^2 + se_b^2) over
  // the nodes and order slots has mean square 1 (calibrated errors) and no outlier.
  const Microsurface s = beckmann_tile(64, 5, 0.7);
  AlbedoRequest r1;
  r1.material = "dielectric";
  r1.eta = 1.5;
  r1.rays = 8000;
  r1.mu_nodes = 6;
  r1.check();
  AlbedoRequest r2 = r1;
  r2.seed = 2;
  const AlbedoSurface a = measure_albedo(s, "b", r1), b = measure_albedo(s, "b", r2);
  std::vector<double> z;
  for (std::size_t j = 0; j < a.nodes.size(); ++j)
    for (int sd = 0; sd < 2; ++sd)
      for (int k = 0; k <= r1.orders; ++k) {
        const Estimate x = a.nodes[j].side[sd][k], y = b.nodes[j].side[sd][k];
        const double se = std::hypot(x.stderr_, y.stderr_);
        if (se > 1e-9) z.push_back((x.mean - y.mean) / se);
      }
  ASSERT_GE(z.size(), 50u);
  double mean_sq = 0;
  for (double v : z) mean_sq += v * v;
  mean_sq /= static_cast<double>(z.size());
  // Mean square of n (correlated within a node) z^2: sd about sqrt(2 / n) ~ 0.2; bounds 0.4 .. 2.
  EXPECT_GT(mean_sq, 0.4);
  EXPECT_LT(mean_sq, 2.0);
  double zmax = 0;
  for (double v : z) zmax = std::max(zmax, std::abs(v));
  EXPECT_LT(zmax, sidak_z(0.001, static_cast<int>(z.size())));
  // Power: errors a factor 2 too small (or too large) leave those bounds.
  EXPECT_GT(4 * mean_sq, 2.0);
  EXPECT_LT(mean_sq / 4, 0.4);
}

TEST(AlbedoRequestChecks, ParametersNamedInMessages) {
  AlbedoRequest r;
  r.material = "mirror";
  r.mu_nodes = 1;
  EXPECT_THROW(r.check(), ParameterError);
  r.mu_nodes = 8;
  r.rays = 10;  // fewer than the replicates
  try {
    r.check();
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("{rays}"), std::string::npos) << e.what();
  }
  r.rays = 1000;
  r.material = "conductor";
  EXPECT_THROW(r.check(), ParameterError);  // no eta, k
  r.metal = "Au";
  r.check();
  r.wavelength_nm = 5000;  // outside the table
  EXPECT_THROW(r.check(), ParameterError);
}

TEST(AlbedoCommand, LookupTableRowsAreSurfacesColumnsAreMu) {
  const std::string s1 = temp_path("albedo", "a1.exr"), s2 = temp_path("albedo", "a2.exr");
  ASSERT_EQ(run_microsim("-q generate gaussian --resolution 64 --alpha 0.3 -o " + s1).code, 0);
  ASSERT_EQ(run_microsim("-q generate gaussian --resolution 64 --alpha 0.6 -o " + s2).code, 0);
  const std::string lut = temp_path("albedo", "lut.exr");
  const Result r = run_microsim("-q measure albedo " + s1 + " " + s2 +
                                " --material mirror --mu-nodes 5 --rays 4000 -o " + lut);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string stem = lut.substr(0, lut.size() - 3);
  EXPECT_TRUE(exists(stem + "csv"));
  EXPECT_TRUE(exists(stem + "json"));
  const ExrTable t = read_exr(lut);
  EXPECT_EQ(t.width, 5);
  EXPECT_EQ(t.height, 2);
  const auto channel = [&](const std::string& name) -> const std::vector<float>& {
    for (std::size_t c = 0; c < t.channel_names.size(); ++c)
      if (t.channel_names[c] == name) return t.channels[c];
    throw std::runtime_error("no channel " + name);
  };
  for (float e : channel("E")) EXPECT_NEAR(e, 1.0, 1e-4);
  for (float e : channel("E_stderr")) EXPECT_LT(e, 1e-6);
  // Near normal incidence (column 4: the largest mu) order 1 falls with alpha (row 1).
  const auto& o1 = channel("reflected_order_1");
  EXPECT_LT(o1[5 + 4], o1[4]);
  EXPECT_GT(o1[4], 0.99);
  const std::string csv = slurp(stem + "csv");
  EXPECT_EQ(lines(csv), 1 + 2 * 5);
  // Bad input: one mu node, exit 2 naming the option.
  const Result bad = run_microsim("-q measure albedo " + s1 + " --material mirror --mu-nodes 1 -o " + lut);
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--mu-nodes"), std::string::npos) << bad.err;
}
