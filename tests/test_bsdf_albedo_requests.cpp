// The library's measure bsdf and measure albedo requests (microsim/api/bsdf_request.hpp,
// albedo_request.hpp): check() refuses each out-of-range field with a message naming that
// parameter ("{rays}: ..."), which the front ends spell as their option or keyword; the records
// are measured on the request's angles sorted and without repeats; a request resolves into the
// measurement's options field by field (api/albedo_resolve.hpp) and its record keeps the
// request's parameters before the measured part.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "microsim/api/albedo_resolve.hpp"
#include "microsim/api/albedo_run.hpp"
#include "microsim/api/bsdf_run.hpp"
#include "microsim/common.hpp"
#include "test_helpers.hpp"

namespace {
using namespace microsim;
using microsim::testing::flat_heightfield;

// Python's spelling: the keyword of the same name.
std::string keyword(std::string_view parameter) { return std::string(parameter); }

// The message of the UsageError f throws ("" when it throws none).
std::string usage_message(const std::function<void()>& f) {
  try {
    f();
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

BsdfRequest mirror_bsdf() {
  BsdfRequest r;
  r.material = "mirror";
  r.theta_i_deg = {30};
  r.rays = 2000;
  r.resolution = 8;
  return r;
}

struct BsdfCase {
  const char* name;
  std::function<void(BsdfRequest&)> change;
  const char* message;
};

TEST(BsdfRequestChecks, EachFieldOutOfRangeIsNamed) {
  ASSERT_EQ(usage_message([] { mirror_bsdf().check(); }), "");  // the cases differ from it in one field
  const BsdfCase cases[] = {
      {"rays", [](BsdfRequest& r) { r.rays = 0; }, "{rays}: must be an integer in [1, 1000000000000] (got '0')"},
      {"replicates", [](BsdfRequest& r) { r.replicates = 1; }, "{replicates}: must be an integer in [2, 65536] (got '1')"},
      {"orders", [](BsdfRequest& r) { r.orders = 17; }, "{orders}: must be an integer in [1, 16] (got '17')"},
      {"resolution", [](BsdfRequest& r) { r.resolution = 0; }, "{resolution}: must be an integer in [1, 1024] (got '0')"},
      {"table_resolution", [](BsdfRequest& r) { r.table_resolution = 1; },
       "{table_resolution}: must be an integer in [2, 512] (got '1')"},
      {"table_azimuths", [](BsdfRequest& r) { r.table_azimuths = 0; },
       "{table_azimuths}: must be an integer in [1, 360] (got '0')"},
      {"theta_i", [](BsdfRequest& r) { r.theta_i_deg = {95, -5}; }, "{theta_i} must be in [0, 90) degrees (got -5.00)"},
      {"no theta_i", [](BsdfRequest& r) { r.theta_i_deg.clear(); }, "{theta_i} is required"},
      {"phi_i", [](BsdfRequest& r) { r.phi_i_deg = {4000}; }, "{phi_i} must be finite angles in degrees, |phi| <= 3600"},
      {"material", [](BsdfRequest& r) { r.material = "gold"; },
       "{material} must be mirror, conductor or dielectric (got 'gold')"},
      {"eta of a mirror", [](BsdfRequest& r) { r.eta = 1.5; },
       "{eta} and {k} apply to {material} conductor or dielectric, not mirror"},
      {"wavelengths", [](BsdfRequest& r) { r.wavelengths_nm = {500}; }, "{wavelengths} needs {metal} or {ior_file}"},
      {"pbsdf", [](BsdfRequest& r) { r.format = "pbsdf"; }, "{output} .pbsdf holds Mueller matrices: give {polarized}"},
      {"binary", [](BsdfRequest& r) { r.format = "binary", r.phi_i_deg = {0, 10}; },
       "{output} .binary: MERL tables are isotropic; give one {phi_i} (got 2 azimuths)"},
      {"table rays", [](BsdfRequest& r) { r.format = "bsdf", r.rays = 10; },
       "{table_azimuths} 16 splits {rays} over as many azimuths: give at least that many rays (got 10)"},
  };
  for (const BsdfCase& c : cases) {
    BsdfRequest r = mirror_bsdf();
    c.change(r);
    EXPECT_EQ(usage_message([&] { r.check(); }), c.message) << c.name;
  }
  // Spelled for Python: the keywords.
  BsdfRequest r = mirror_bsdf();
  r.rays = 0;
  try {
    r.check();
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_EQ(spelled_message(e, keyword), "rays: must be an integer in [1, 1000000000000] (got '0')");
  }
}

TEST(BsdfRequestChecks, RunNeedsASurfaceAndMeasuresSortedAngles) {
  BsdfRequest r = mirror_bsdf();
  EXPECT_EQ(usage_message([&] { run_bsdf_request(r, RunContext()); }), "no surface given");
  r.surface = surface_held("flat", std::make_shared<const Microsurface>(flat_heightfield()));
  r.theta_i_deg = {60, 30, 30};
  r.check();  // checks a copy: the request keeps its order
  EXPECT_EQ(r.theta_i_deg, (std::vector<double>{60, 30, 30}));
  const Json j = measure_bsdf_record(r, RunContext());
  EXPECT_EQ(j["command"], "measure bsdf");
  EXPECT_EQ(j["file"], "flat");
  EXPECT_EQ(j["parameters"]["theta_i_deg"], Json({30.0, 60.0}));
  ASSERT_EQ(j["incidences"].size(), 2u);
  // A flat mirror reflects every path once.
  for (const Json& inc : j["incidences"]) EXPECT_EQ(inc["albedo"]["reflected"]["order_1"], 1.0);
}

TEST(BsdfRequestChecks, RecordPathIsBesideTheTable) {
  EXPECT_EQ(bsdf_record_path("out/t.exr"), "out/t.json");
  EXPECT_EQ(bsdf_record_path("t.json"), "t.json");
  EXPECT_EQ(bsdf_record_path("a.b/t"), "a.b/t.json");
}

AlbedoRequest mirror_albedo() {
  AlbedoRequest r;
  r.material = "mirror";
  r.mu_nodes = 3;
  r.rays = 2000;
  return r;
}

struct AlbedoCase {
  const char* name;
  std::function<void(AlbedoRequest&)> change;
  const char* message;
};

TEST(AlbedoRequestChecks, EachFieldOutOfRangeIsNamed) {
  ASSERT_EQ(usage_message([] { mirror_albedo().check(); }), "");
  const AlbedoCase cases[] = {
      {"theta_i", [](AlbedoRequest& r) { r.theta_i_deg = {30, 95}; }, "{theta_i} must be in [0, 90) degrees (got 95.00)"},
      {"mu_nodes", [](AlbedoRequest& r) { r.mu_nodes = 1; }, "{mu_nodes}: must be an integer in [2, 64] (got '1')"},
      {"azimuths", [](AlbedoRequest& r) { r.azimuths = -1; }, "{azimuths}: must be an integer in [0, 360] (got '-1')"},
      {"orders", [](AlbedoRequest& r) { r.orders = 0; }, "{orders}: must be an integer in [1, 16] (got '0')"},
      {"phi_i", [](AlbedoRequest& r) { r.phi_i_deg = 1e9; }, "{phi_i} must be a finite angle in degrees, |phi| <= 3600"},
      {"rays", [](AlbedoRequest& r) { r.rays = 10; },
       "{rays} must be at least {replicates} per azimuth (32 here; got 10)"},
      {"replicates", [](AlbedoRequest& r) { r.replicates = 1; },
       "{replicates}: must be an integer in [2, 65536] (got '1')"},
      {"metal", [](AlbedoRequest& r) { r.metal = "Au"; }, "{metal} applies to {material} conductor only"},
      {"conductor", [](AlbedoRequest& r) { r.material = "conductor"; },
       "{material} conductor needs {eta} E and {k} K (complex index eta + ik)"},
      {"format", [](AlbedoRequest& r) { r.format = "txt"; }, "the output must be .json, .csv or .exr (got .txt)"},
  };
  for (const AlbedoCase& c : cases) {
    AlbedoRequest r = mirror_albedo();
    c.change(r);
    EXPECT_EQ(usage_message([&] { r.check(); }), c.message) << c.name;
  }
  // Given incidences replace the Gauss-Legendre nodes: mu_nodes is not looked at.
  AlbedoRequest r = mirror_albedo();
  r.mu_nodes = 1;
  r.theta_i_deg = {30};
  EXPECT_EQ(usage_message([&] { r.check(); }), "");
}

TEST(AlbedoRequestChecks, RunNeedsSurfacesAndMeasuresSortedAngles) {
  AlbedoRequest r = mirror_albedo();
  EXPECT_EQ(usage_message([&] { run_albedo_request(r, RunContext()); }), "no surface given");
  r.surfaces = {surface_held("flat", std::make_shared<const Microsurface>(flat_heightfield()))};
  r.theta_i_deg = {60, 30, 30};
  const Json j = measure_albedo_record(r, RunContext());
  EXPECT_EQ(j["command"], "measure albedo");
  EXPECT_EQ(j["file"], Json({"flat"}));
  EXPECT_EQ(j["quadrature"]["nodes"], 2);
  ASSERT_EQ(j["rows"].size(), 2u);
  for (const Json& row : j["rows"]) EXPECT_EQ(row["albedo"], 1.0);  // a flat mirror: every path leaves
}

// The positions of `keys` among the record's keys, in the record's order (-1: missing).
std::vector<long> key_positions(const Json& record, const std::vector<std::string>& keys) {
  std::vector<std::string> order;
  for (auto it = record.begin(); it != record.end(); ++it) order.push_back(it.key());
  std::vector<long> out;
  for (const std::string& k : keys) {
    const auto at = std::find(order.begin(), order.end(), k);
    out.push_back(at == order.end() ? -1 : static_cast<long>(at - order.begin()));
  }
  return out;
}

// Every key present and in the given order.
bool in_order(const std::vector<long>& positions) {
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (positions[i] < 0 || (i > 0 && positions[i] <= positions[i - 1])) return false;
  return true;
}

TEST(AlbedoRequestResolve, OptionsCarryEveryFieldOfTheRequest) {
  AlbedoRequest r;  // every field away from AlbedoOptions' defaults
  r.material = "conductor";
  r.eta = 0.5;
  r.k = 2.5;
  r.mu_nodes = 5;
  r.phi_i_deg = 20;
  r.azimuths = 3;
  r.orders = 6;
  r.rays = 12345;
  r.seed = 9;
  r.replicates = 7;
  r.max_events = 77;
  const AlbedoOptions o = albedo_options(r);
  EXPECT_EQ(o.material.kind, models::MaterialKind::Conductor);
  EXPECT_EQ(o.material.eta, 0.5);
  EXPECT_EQ(o.material.k, 2.5);
  EXPECT_EQ(o.quadrature.rule, "gauss-legendre");
  EXPECT_EQ(o.quadrature.mu, gauss_legendre_mu(5).mu);
  EXPECT_EQ(o.phi_i_deg, 20);
  EXPECT_EQ(o.azimuths, 3);
  EXPECT_EQ(o.orders, 6);
  EXPECT_EQ(o.rays, 12345);
  EXPECT_EQ(o.seed, 9u);
  EXPECT_EQ(o.replicates, 7);
  EXPECT_EQ(o.max_events, 77);
  // Given incidences: the trapezoid rule on their cosines, increasing in mu.
  r.theta_i_deg = {60, 0};
  const MuQuadrature q = albedo_options(r).quadrature;
  EXPECT_EQ(q.rule, "trapezoid");
  ASSERT_EQ(q.mu.size(), 2u);
  EXPECT_NEAR(q.mu[0], 0.5, 1e-15);
  EXPECT_EQ(q.mu[1], 1.0);
}

TEST(AlbedoRequestChecks, RecordHasTheParametersBeforeTheMeasuredPart) {
  AlbedoRequest r = mirror_albedo();
  r.surfaces = {surface_held("flat", std::make_shared<const Microsurface>(flat_heightfield()))};
  const Json j = measure_albedo_record(r, RunContext());
  const std::vector<long> at =
      key_positions(j, {"command", "file", "parameters", "quadrature", "definitions", "surfaces", "rows", "averages"});
  EXPECT_TRUE(in_order(at)) << j.dump().substr(0, 200);
  // Power: the same keys in another order are refused.
  EXPECT_FALSE(in_order(key_positions(j, {"file", "quadrature", "parameters"})));
}

TEST(BsdfRequestChecks, RecordHasTheParametersBeforeTheMeasuredPart) {
  BsdfRequest r = mirror_bsdf();
  r.surface = surface_held("flat", std::make_shared<const Microsurface>(flat_heightfield()));
  const Json j = measure_bsdf_record(r, RunContext());
  EXPECT_TRUE(in_order(key_positions(j, {"command", "file", "surface", "parameters", "definitions", "albedo",
                                         "rows", "in_plane", "incidences"})));
  EXPECT_FALSE(in_order(key_positions(j, {"definitions", "parameters"})));  // power: the order is seen
  EXPECT_EQ(j["parameters"]["material"], "mirror");
  EXPECT_FALSE(j["definitions"].contains("polarization"));  // not a polarized request
}

}  // namespace
