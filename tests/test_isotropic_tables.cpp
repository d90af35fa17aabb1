// Isotropic renderer tables averaged over incidence azimuths (measure/bsdf_table.hpp,
// BsdfTableOptions::table_azimuths): the runs' outgoing directions are turned into the frame of
// the nominal incidence, the rays are split evenly, and a surface that is isotropic exactly
// keeps its table.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "microsim/api/bsdf_resolve.hpp"
#include "microsim/measure/bsdf_record.hpp"
#include "microsim/measure/bsdf_table.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;
namespace mm = microsim::models;

namespace {

BsdfTable measure(const Microsurface& s, const mm::Material& m, double theta_deg, std::uint64_t rays,
                  int azimuths, int res = 32) {
  const Tracer tracer(s);
  BsdfTableOptions o;
  o.base.material = m;
  o.base.orders = 3;
  o.base.rays = rays;
  o.base.resolution = res;
  o.base.seed = 5;
  o.base.models = false;
  o.theta_i = {rad(theta_deg)};
  o.phi_i = {0.0};
  o.table_azimuths = azimuths;
  return measure_bsdf_table(tracer, o);
}

Vec3 reflect(const Vec3& wi, const Vec3& n) { return 2.0 * wi.dot(n) * n - wi; }

// int table_f cos(theta_o) d omega over the upper hemisphere: a midpoint rule on the
// equal-area square (every cell subtends the same solid angle), `n` cells per side.
double table_albedo(const BsdfTable& t, int n = 256) {
  const HemisphereMap map(n);
  const int K = t.results[0].options.orders;
  double sum = 0.0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Vec3 wo = map.from_square(-1 + (i + 0.5) * 2.0 / n, -1 + (j + 0.5) * 2.0 / n);
      sum += table_f(t, 0, 0, 0, K, wo) * wo.z();
    }
  return sum * map.pixel_solid_angle();
}

// The same table with every azimuth offset of opposite sign: a wrong turn into the table frame.
BsdfTable with_turns_reversed(BsdfTable t) {
  for (double& d : t.turns) d = -d;
  return t;
}

}  // namespace

TEST(IsotropicTable, RaysSplitEvenlyOverTheAzimuths) {
  const Microsurface flat = flat_heightfield();
  const BsdfTable t = measure(flat, mm::Material::mirror(), 30, 1003, 8, 8);
  ASSERT_EQ(t.azimuths(), 8);
  ASSERT_EQ(t.turned.size(), 1u);
  ASSERT_EQ(t.turned[0].size(), 7u);
  // 1003 = 8 * 125 + 3: the first three get one more (each run then rounds up to whole replicates).
  std::uint64_t asked = t.at(0, 0).options.rays, walked = t.at(0, 0).measured.paths;
  EXPECT_EQ(t.at(0, 0).options.rays, 126u);
  EXPECT_EQ(t.turned[0][1].options.rays, 126u);
  EXPECT_EQ(t.turned[0][2].options.rays, 125u);
  for (const BsdfResult& r : t.turned[0]) asked += r.options.rays, walked += r.measured.paths;
  EXPECT_EQ(asked, 1003u);
  EXPECT_EQ(t.paths(0, 0), walked);
  EXPECT_DOUBLE_EQ(t.at(0, 0).options.phi_i, 0.0);  // the record's rows: the nominal azimuth
  for (int a = 1; a < 8; ++a) EXPECT_NEAR(t.turned[0][a - 1].options.phi_i, 2 * kPi * a / 8, 1e-15);
  // One azimuth: the table is the nominal run alone, with every ray.
  const BsdfTable one = measure(flat, mm::Material::mirror(), 30, 1003, 1, 8);
  EXPECT_EQ(one.azimuths(), 1);
  EXPECT_TRUE(one.turned.empty());
  EXPECT_EQ(one.at(0, 0).options.rays, 1003u);
}

// A flat conductor is isotropic exactly: its averaged table reflects the Fresnel reflectance,
// as the single-azimuth table does (the midpoint rule on the bilinear reconstruction of one
// lit pixel: within 2 %), and puts its peak at the nominal specular direction.
TEST(IsotropicTable, FlatConductorKeepsItsTable) {
  const Microsurface flat = flat_heightfield();
  const mm::Material gold = mm::Material::conductor(0.47, 2.4);
  const double theta = 40;
  const BsdfTable single = measure(flat, gold, theta, 4000, 1);
  const BsdfTable averaged = measure(flat, gold, theta, 4000, 8);
  const double F = single.at(0, 0).albedo(0, single.at(0, 0).options.orders).mean;
  EXPECT_GT(F, 0.5);
  EXPECT_NEAR(table_albedo(single) / F, 1.0, 0.02);
  EXPECT_NEAR(table_albedo(averaged) / F, 1.0, 0.02);
  // The wrong turn scatters the light of the turned runs away from the specular direction, and
  // the table's albedo stays: the albedo alone cannot see the turn, the peak does.
  const Vec3 wi = direction_from_angles(rad(theta), 0.0);
  const Vec3 spec = reflect(wi, Vec3(0, 0, 1));
  const int K = 3;
  const double peak_single = table_f(single, 0, 0, 0, K, spec);
  EXPECT_NEAR(table_f(averaged, 0, 0, 0, K, spec) / peak_single, 1.0, 0.35);
  EXPECT_LT(table_f(with_turns_reversed(averaged), 0, 0, 0, K, spec) / peak_single, 0.4);
}

// V-grooves along y (facet normals (+-sin tm, 0, cos tm)) under a mirror: the run at azimuth
// phi_k reflects once into wo_k = reflect(wi_k, n+), a lobe whose place depends on phi_k in
// closed form. Turned into the table frame it sits at Rz(-phi_k) wo_k, and there the table
// holds at least that run's share of it; turned the wrong way the place is dark.
TEST(IsotropicTable, TurnIntoTheTableFrameFollowsTheLobe) {
  const double tm = rad(15.0);
  const Microsurface grooves = vgroove_heightfield(8, 4, tm);
  const int N = 8;
  const double theta = 35;
  const BsdfTable t = measure(grooves, mm::Material::mirror(), theta, 80000, N);
  const BsdfTable wrong = with_turns_reversed(t);
  const int K = t.results[0].options.orders;
  const Vec3 n_plus(std::sin(tm), 0.0, std::cos(tm));
  int checked = 0;
  for (int k = 1; k < N; ++k) {
    const double d = t.turns[k];
    if (std::abs(std::sin(d)) < 0.1) continue;  // a half turn is its own reverse
    const Vec3 wi_k = direction_from_angles(rad(theta), d);
    const Vec3 wo_k = reflect(wi_k, n_plus);
    if (wo_k.z() < 0.3) continue;
    const BsdfResult& run = t.turned[0][k - 1];
    const double lobe = interpolate_f(run, 0, K, wo_k);
    // The closed-form direction is where the run's light went: far above the run's mean f.
    double mean_f = 0.0;
    for (int px = 0; px < run.map.size(); ++px) mean_f += run.f_pixel(0, K, px).mean / run.map.size();
    ASSERT_GT(lobe, 10 * mean_f) << "azimuth " << deg(d);
    const Vec3 in_table = turn_about_normal(wo_k, -d);
    const double share = static_cast<double>(run.measured.paths) / t.paths(0, 0);
    EXPECT_GE(table_f(t, 0, 0, 0, K, in_table), 0.999 * share * lobe) << "azimuth " << deg(d);
    EXPECT_LT(table_f(wrong, 0, 0, 0, K, in_table), 0.5 * share * lobe) << "azimuth " << deg(d);
    ++checked;
  }
  EXPECT_GE(checked, 4);
}

// --table-azimuths applies to the isotropic renderer tables only.
TEST(IsotropicTable, RequestAveragesRendererTablesOnly) {
  const Microsurface flat = flat_heightfield();
  BsdfRequest r;
  r.material = "mirror";
  r.theta_i_deg = {30};
  r.phi_i_deg = {0};
  r.table_azimuths = 16;
  for (const char* fmt : {"bsdf", "binary"}) {
    r.format = fmt;
    EXPECT_EQ(bsdf_table_options(r, flat, nullptr).table_azimuths, 16) << fmt;
  }
  for (const char* fmt : {"json", "exr"}) {
    r.format = fmt;
    EXPECT_EQ(bsdf_table_options(r, flat, nullptr).table_azimuths, 1) << fmt;
  }
  r.format = "bsdf";
  r.phi_i_deg = {-180, 0, 180};
  EXPECT_EQ(bsdf_table_options(r, flat, nullptr).table_azimuths, 1);
  EXPECT_EQ(BsdfRequest().table_azimuths, kDefaultTableAzimuths);
}
