// The result table: merging the tables of K surfaces (mean, between-surface and ray-count
// errors, bins matched by key), the comparison rule (which error for which model, Student t
// p-values), and the calibration of that rule: over many simulated ensembles the nominal z
// crosses the Student t threshold at the nominal rate, and the wrong error (the ray-count one,
// or the normal quantile) fails that check.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "microsim/measure/stats.hpp"
#include "microsim/measure/table.hpp"

using namespace microsim;

namespace {

TableSpec spec() {
  TableSpec s;
  s.columns = {{"theta_deg", Merge::Copy},   {"surfaces", Merge::Count},  {"g", Merge::Measured},
               {"facets", Merge::Spread},    {"nominal", Merge::Copy},    {"area", Merge::Mean}};
  s.comparisons = {{"g", "nominal", ModelKind::Nominal, "z_nominal", "rel_dev_nominal", "p_nominal"},
                   {"g", "facets", ModelKind::Facets, "z_facets", "", ""}};
  s.bin_columns = {{"key", Merge::Key}, {"m", Merge::Direction}, {"g", Merge::Spread}};
  return s;
}

Table one_surface(double g, double se, double facets, std::vector<int> keys) {
  Table t;
  t.spec = spec();
  Json row = {{"theta_deg", 30.0}, {"g", g}, {"g_stderr", se}, {"facets", facets},
              {"nominal", 0.55}, {"area", 2 * g}, {"not_merged", 1}};
  Json bins = Json::array();
  for (int k : keys) bins.push_back({{"key", k}, {"m", {0.0, 0.0, 1.0 + k}}, {"g", g + k}});
  row["bins"] = bins;
  t.rows.push_back(row);
  return t;
}

}  // namespace

// K = 3 surfaces by hand: g = 0.5, 0.6, 0.7 -> mean 0.6, sd 0.1, between-surface error
// 0.1 / sqrt(3); ray-count error sqrt(0.01^2 + 0.02^2 + 0.02^2) / 3 = 0.01.
TEST(Table, MergeOfThreeSurfacesByHand) {
  const Table a = one_surface(0.5, 0.01, 0.49, {0, 1, 2});
  const Table b = one_surface(0.6, 0.02, 0.61, {2, 1, 0});  // bins in another order
  const Table c = one_surface(0.7, 0.02, 0.68, {0, 2});     // bin 1 empty on this surface
  const Table e = merge({&a, &b, &c});
  ASSERT_EQ(e.rows.size(), 1u);
  EXPECT_EQ(e.surfaces, 3u);
  EXPECT_EQ(e.error, ErrorKind::Surfaces);
  const Json& r = e.rows[0];
  std::vector<std::string> keys;
  for (auto it = r.begin(); it != r.end(); ++it) keys.push_back(it.key());
  const std::vector<std::string> expected = {
      "theta_deg", "surfaces", "t_dof", "g", "g_stderr", "g_stderr_rays", "facets", "facets_stderr",
      "nominal", "area", "z_nominal", "rel_dev_nominal", "p_nominal", "z_facets", "bins"};
  EXPECT_EQ(keys, expected);  // column order is the spec's: the JSON records keep it
  EXPECT_EQ(r["surfaces"], 3);
  EXPECT_EQ(r["t_dof"], 2);
  EXPECT_NEAR(r["g"].get<double>(), 0.6, 1e-15);
  const double se = 0.1 / std::sqrt(3.0);
  EXPECT_NEAR(r["g_stderr"].get<double>(), se, 1e-15);
  EXPECT_NEAR(r["g_stderr_rays"].get<double>(), 0.01, 1e-15);
  EXPECT_NEAR(r["area"].get<double>(), 1.2, 1e-15);
  // Nominal model: between-surface error, Student t with 2 dof: P(|T| > t) = 1 - t / sqrt(t^2 + 2).
  const double z = 0.05 / se;
  EXPECT_NEAR(r["z_nominal"].get<double>(), z, 1e-12);
  EXPECT_NEAR(r["rel_dev_nominal"].get<double>(), 0.05 / 0.55, 1e-12);
  EXPECT_NEAR(r["p_nominal"].get<double>(), 1 - z / std::sqrt(z * z + 2), 1e-12);
  // Model from each surface's facets (mean 0.5933...): the ray-count error.
  EXPECT_NEAR(r["z_facets"].get<double>(), (0.6 - (0.49 + 0.61 + 0.68) / 3) / 0.01, 1e-9);
  // Bins matched by key, in the first surface's order; bin 1 exists on two surfaces only.
  const Json& bins = r["bins"];
  ASSERT_EQ(bins.size(), 3u);
  EXPECT_EQ(bins[1]["key"], 1);
  EXPECT_EQ(bins[1]["surfaces"], 2);
  EXPECT_NEAR(bins[1]["g"].get<double>(), 1.55, 1e-12);
  EXPECT_NEAR(bins[1]["g_stderr"].get<double>(), 0.05, 1e-12);  // sd 0.0707 / sqrt(2)
  EXPECT_EQ(bins[2]["surfaces"], 3);
  EXPECT_NEAR(bins[2]["m"][2].get<double>(), 1.0, 1e-15);  // normalized sum of the directions
  EXPECT_FALSE(r.contains("not_merged"));
}

TEST(Table, NullModelGivesNullComparisonsAndEmptyColumnsStayNull) {
  Table a = one_surface(0.5, 0.01, 0.5, {0}), b = one_surface(0.6, 0.01, 0.6, {0});
  a.rows[0]["nominal"] = nullptr;
  a.rows[0]["area"] = nullptr;
  b.rows[0]["area"] = nullptr;
  const Json r = merge({&a, &b}).rows[0];
  EXPECT_TRUE(r["z_nominal"].is_null());
  EXPECT_TRUE(r["rel_dev_nominal"].is_null());
  EXPECT_TRUE(r["p_nominal"].is_null());
  EXPECT_TRUE(r["area"].is_null());  // no surface has a value: null, not a made-up 0
  EXPECT_TRUE(r["z_facets"].is_number());
}

TEST(Table, MergeRefusesTablesOfDifferentRows) {
  Table a = one_surface(0.5, 0.01, 0.5, {0}), b = one_surface(0.6, 0.01, 0.6, {0});
  b.rows.push_back(b.rows[0]);
  EXPECT_THROW(merge({&a, &b}), std::invalid_argument);
}

TEST(Table, ZScoreAndRelDevConventions) {
  EXPECT_DOUBLE_EQ(z_score(1.2, 1.0, 0.1), 2.0);
  EXPECT_EQ(z_score(1.0, 1.0, 0.0), 0.0);                 // exact agreement without error
  EXPECT_TRUE(std::isinf(z_score(1.1, 1.0, 0.0)));         // a difference without error
  EXPECT_EQ(z_json(1.1, 1.0, 0.0).dump(), "null");         // written as null
  EXPECT_DOUBLE_EQ(rel_dev(1.1, -2.0), 1.55);              // relative to |model|
  EXPECT_EQ(rel_dev(0.0, 0.0), 0.0);
}

// One binomial convention: the plain binomial error sqrt(p(1-p)/n) of k/n (exact for i.i.d.
// counts) with the floor of a proportion at 0 or 1, the error of (n + 1/2)/(n + 1): ~0.707/n.
TEST(Table, ProportionFloor) {
  EXPECT_NEAR(proportion_floor(1000), std::sqrt(0.5) / 1000, 1e-6);
  EXPECT_NEAR(proportion_floor(1000) * 1000, std::sqrt(1000.5 * 0.5 / 1001 / 1001 * 1000), 1e-12);
  EXPECT_EQ(proportion_floor(0), 0.0);
  EXPECT_EQ(binomial_estimate(1000, 1000).stderr_, 0.0);  // why the floor exists
}

// Student t against closed forms: dof 1 (Cauchy) P(|T| > t) = 1 - 2 atan(t) / pi, dof 2
// 1 - t / sqrt(t^2 + 2); the 97.5% quantile for dof 2 is 4.302653 (tables); Sidak's t tends
// to Sidak's z as dof grows.
TEST(Table, StudentTClosedForms) {
  for (double t : {0.1, 1.0, 2.5, 10.0}) {
    EXPECT_NEAR(student_t_two_sided_p(t, 1), 1 - 2 * std::atan(t) / kPi, 1e-12);
    EXPECT_NEAR(student_t_two_sided_p(t, 2), 1 - t / std::sqrt(t * t + 2), 1e-12);
  }
  EXPECT_NEAR(student_t_quantile(0.975, 2), 4.302653, 1e-6);
  EXPECT_NEAR(student_t_quantile(0.975, 4), 2.776445, 1e-6);
  EXPECT_NEAR(sidak_t(0.05, 10, 1e7), sidak_z(0.05, 10), 1e-5);
  EXPECT_GT(sidak_t(0.05, 10, 3), sidak_z(0.05, 10) + 1);  // K = 4 surfaces: much wider
  const SampleMean m = sample_mean({1.0, 2.0, 4.0});
  EXPECT_NEAR(m.mean, 7.0 / 3, 1e-15);
  EXPECT_NEAR(m.stderr_, std::sqrt((16.0 / 9 + 1.0 / 9 + 25.0 / 9) / 2 / 3), 1e-15);
}

// Calibration of the comparison rule: 4000 simulated ensembles of K = 4 surfaces whose true
// values scatter by sigma_s = 0.05 about the nominal model, each measured with ray noise
// sigma_r = 0.005. The nominal z (between-surface error) crosses the Student t threshold at
// alpha = 5% as often as it should (binomial tolerance, 4.5 sigma). Power checks: the same z
// against the normal quantile, the same data with the ray-count error, and a model off by
// one sigma_s all fail that rate.
TEST(Table, NominalComparisonIsCalibratedAndWrongErrorsFail) {
  const int trials = 4000, K = 4;
  const double alpha = 0.05, sigma_s = 0.05, sigma_r = 0.005;
  std::mt19937_64 rng(12345);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double t_crit = student_t_quantile(1 - alpha / 2, K - 1), z_crit = sidak_z(alpha, 1);
  int over_t = 0, over_z = 0, over_rays = 0, over_shifted = 0;
  for (int n = 0; n < trials; ++n) {
    std::vector<Table> tables(K);
    std::vector<const Table*> parts;
    for (int k = 0; k < K; ++k) {
      const double zs = normal(rng), zr = normal(rng);  // named: operand order is unspecified
      const double g = 0.6 + sigma_s * zs + sigma_r * zr;
      tables[k] = one_surface(g, sigma_r, g, {0});
      tables[k].rows[0]["nominal"] = 0.6;
      parts.push_back(&tables[k]);
    }
    const Json r = merge(parts).rows[0];
    const double z = r["z_nominal"].get<double>();
    over_t += std::abs(z) > t_crit;
    over_z += std::abs(z) > z_crit;
    over_rays += std::abs((r["g"].get<double>() - 0.6) / r["g_stderr_rays"].get<double>()) > t_crit;
    over_shifted += std::abs(z_score(r["g"].get<double>(), 0.6 + sigma_s, r["g_stderr"].get<double>())) > t_crit;
    // The p-value says the same as the threshold.
    EXPECT_EQ(r["p_nominal"].get<double>() < alpha, std::abs(z) > t_crit);
  }
  const double tol = 4.5 * std::sqrt(alpha * (1 - alpha) * trials);
  EXPECT_NEAR(over_t, alpha * trials, tol);
  EXPECT_GT(over_z, alpha * trials + tol);        // normal quantile with K - 1 = 3 dof: too many
  EXPECT_GT(over_rays, 0.5 * trials);             // ray-count error for a nominal model: nonsense
  EXPECT_GT(over_shifted, alpha * trials + tol);  // a wrong model is seen
}

// Merge::Sharpest: a Monte Carlo model run beside every surface; the merged row takes the value and the error
// of the surface whose error is smallest (not the first surface's, which Copy would take).
TEST(Table, SharpestTakesTheModelRunWithTheSmallestError) {
  auto table = [](double model, double model_se) {
    Table t;
    t.spec.columns = {{"theta_deg", Merge::Copy}, {"walk", Merge::Sharpest}, {"walk_stderr", Merge::Sharpest}};
    t.rows.push_back({{"theta_deg", 30.0}, {"walk", model}, {"walk_stderr", model_se}});
    return t;
  };
  const Table a = table(0.50, 0.004), b = table(0.51, 0.001), c = table(0.49, 0.002);
  const Table m = merge({&a, &b, &c});
  EXPECT_EQ(m.rows[0]["walk"].get<double>(), 0.51);
  EXPECT_EQ(m.rows[0]["walk_stderr"].get<double>(), 0.001);
  // a tie keeps the first surface's run; a surface without an error is never preferred
  const Table d = table(0.52, 0.004);
  Table e = table(0.53, 0.0);
  e.rows[0].erase("walk_stderr");
  const Table tie = merge({&a, &d, &e});
  EXPECT_EQ(tie.rows[0]["walk"].get<double>(), 0.50);
  EXPECT_STREQ(merge_name(Merge::Sharpest), "sharpest");
}
