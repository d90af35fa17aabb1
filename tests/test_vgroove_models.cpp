// Tests of the closed-form V-groove multiple scattering and the V-cavity multiple-scattering
// model (models/vgroove_multiple.hpp).
//
// Independent route: a small exact 2D tracer of the groove's cross-section (reflect at the wall
// segments until the ray leaves through the aperture), lifted to 3D by keeping the along-groove
// component. With N entry points at the midpoints of N equal parts of the aperture, every share
// is exact up to the cells cut by a beam boundary: at most one per boundary (three boundaries
// between four beams), so |closed form - trace| <= 3/N per order. Directions and reflectances
// are exact per beam. The V-cavity average is checked against an independent Monte Carlo average
// over grooves drawn from the Beckmann slope distribution (z-test against its own error).
#include <gtest/gtest.h>

#include "microsim/measure/stats.hpp"

#include <microsim/common.hpp>
#include <microsim/models/vgroove_multiple.hpp>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <vector>

namespace {

namespace mm = microsim::models;
using mm::Material;
using mm::Vec3;

constexpr double kPi = 3.14159265358979323846;
double rad(double d) { return d * kPi / 180.0; }
Vec3 dir(double theta, double phi) {
  return Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
}

struct TracedOrder {
  double fraction = 0, weight = 0;
  Vec3 direction = Vec3::Zero();
  double max_direction_spread = 0;
};

// Exact 2D trace of a groove of half-width 1/2 and facet angle tf lit from l (groove frame).
std::map<int, TracedOrder> trace_groove(double tf, const Vec3& l, const Material& mat, int N) {
  const double w = 0.5, h = w * std::tan(tf), lp = std::hypot(l.x(), l.z());
  // Walls: bottom (0, 0) to (+-w, h); inward normals (-+sin tf, cos tf).
  const double wx[2] = {w, -w};
  const double nx[2] = {-std::sin(tf), std::sin(tf)}, nz = std::cos(tf);
  std::map<int, TracedOrder> out;
  for (int i = 0; i < N; ++i) {
    double px = -w + 2 * w * (i + 0.5) / N, pz = h;
    double dx = -l.x() / lp, dz = -l.z() / lp;
    int bounces = 0, last = -1;
    double weight = 1.0;
    for (;;) {
      // Nearest wall crossing: p + s d = u (wx, h), u in [0, 1], s > 0.
      double best = 1e300;
      int wall = -1;
      for (int k = 0; k < 2; ++k) {
        if (k == last) continue;
        // Cramer on [dx, -wx; dz, -h] (s, u) = (-px, -pz).
        const double det = -dx * h + wx[k] * dz;
        if (std::abs(det) < 1e-300) continue;
        const double s = (px * h - wx[k] * pz) / det;
        const double u = (-dx * pz + dz * px) / det;
        if (s > 1e-12 && u >= 0 && u <= 1 && s < best) {
          best = s;
          wall = k;
        }
      }
      if (wall < 0) break;  // leaves through the aperture
      px += best * dx;
      pz += best * dz;
      const double dn = dx * nx[wall] + dz * nz;
      weight *= mat.reflectance(std::min(1.0, lp * std::abs(dn)), true);
      dx -= 2 * dn * nx[wall];
      dz -= 2 * dn * nz;
      last = wall;
      ++bounces;
    }
    EXPECT_GT(dz, 0.0);
    TracedOrder& t = out[bounces];
    const Vec3 o(lp * dx, -l.y(), lp * dz);
    if (t.fraction > 0) t.max_direction_spread = std::max(t.max_direction_spread, (o - t.direction).norm());
    else t.direction = o;
    t.fraction += 1.0 / N;
    t.weight += weight / N;
  }
  return out;
}

// Sum of the closed form's beams per bounce count.
std::map<int, TracedOrder> closed_form(double tf, const Vec3& l, const Material& mat) {
  std::map<int, TracedOrder> out;
  for (const auto& b : mm::vgroove_beams(tf, l, mat)) {
    TracedOrder& t = out[b.bounces];
    t.fraction += b.fraction;
    t.weight += b.fraction * b.reflectance;
    t.direction = b.direction;
  }
  return out;
}

TEST(VGrooveClosedForm, KnownSharesAtSeventyDegrees) {
  // tf = 70, theta_i = 20 deg: orders 3 and 4, shares 1 - sin 20 / sin 40 and sin 20 / sin 40.
  const auto beams = closed_form(rad(70), dir(rad(20), 0.0), Material::mirror());
  ASSERT_EQ(beams.size(), 2u);
  EXPECT_NEAR(beams.at(3).fraction, 1 - std::sin(rad(20)) / std::sin(rad(40)), 1e-12);
  EXPECT_NEAR(beams.at(4).fraction, std::sin(rad(20)) / std::sin(rad(40)), 1e-12);
  EXPECT_NEAR(beams.at(3).fraction, 0.4679, 5e-5);
  // Order 4 leaves straight up; order 3 toward the light side at 40 deg.
  EXPECT_NEAR((beams.at(4).direction - Vec3(0, 0, 1)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((beams.at(3).direction - dir(rad(40), 0.0)).norm(), 0.0, 1e-12);
}

TEST(VGrooveClosedForm, ShallowGrooveIsAMirror) {
  const Vec3 l = dir(rad(30), rad(20));
  const auto beams = closed_form(rad(5), l, Material::mirror());
  ASSERT_TRUE(beams.count(1));
  // A 5 deg groove lit at 30 deg: single bounces except a thin share near the far wall.
  EXPECT_GT(beams.at(1).fraction, 0.8);
}

TEST(VGrooveClosedForm, EqualsExact2DTracePerOrder) {
  const int N = 20000;
  const double tol_share = 3.0 / N;
  const Material materials[2] = {Material::mirror(), Material::conductor(0.2, 3.0)};
  int cases = 0;
  for (double tf : {30.0, 45.0, 60.0, 70.0, 85.0})
    for (double th : {0.0, 20.0, 40.0, 60.0, 80.0})
      for (double ph : {0.0, 75.0, 200.0})
        for (const Material& mat : materials) {
          const Vec3 l = dir(rad(th), rad(ph));
          const auto cf = closed_form(rad(tf), l, mat);
          const auto tr = trace_groove(rad(tf), l, mat, N);
          double sum = 0;
          for (const auto& [n, t] : cf) sum += t.fraction;
          EXPECT_NEAR(sum, 1.0, 1e-12) << tf << " " << th << " " << ph;
          for (const auto& [n, t] : tr) {
            SCOPED_TRACE("tf " + std::to_string(tf) + " theta " + std::to_string(th) + " phi " +
                         std::to_string(ph) + " order " + std::to_string(n));
            const bool there = cf.count(n) > 0;
            const double share = there ? cf.at(n).fraction : 0.0;
            EXPECT_NEAR(t.fraction, share, tol_share);
            EXPECT_NEAR(t.weight, there ? cf.at(n).weight : 0.0, tol_share);
            // All rays of one order leave in one direction (one family per order, or two
            // mirror families with the same count; compare with the closed form's beams).
            if (there && t.fraction > 10.0 / N) {
              bool match = false;
              for (const auto& b : mm::vgroove_beams(rad(tf), l, mat))
                if (b.bounces == n && (b.direction - t.direction).norm() < 1e-9) match = true;
              EXPECT_TRUE(match);
            }
          }
          for (const auto& [n, t] : cf)
            if (t.fraction > tol_share) {
              EXPECT_TRUE(tr.count(n)) << "order " << n << " not traced";
            }
          ++cases;
        }
  EXPECT_EQ(cases, 150);
}

TEST(VGrooveClosedForm, WrongFacetAngleFailsTheComparison) {
  // Power: the closed form of a groove 0.5 deg steeper differs from the trace beyond tolerance.
  const int N = 20000;
  int failures = 0;
  for (double th : {0.0, 20.0, 40.0}) {
    const Vec3 l = dir(rad(th), 0.0);
    const auto cf = closed_form(rad(70.5), l, Material::mirror());
    const auto tr = trace_groove(rad(70), l, Material::mirror(), N);
    for (const auto& [n, t] : tr)
      if (std::abs(t.fraction - (cf.count(n) ? cf.at(n).fraction : 0.0)) > 3.0 / N) ++failures;
  }
  EXPECT_GT(failures, 0);
}

TEST(VCavityMultiple, MirrorEnsembleConservesEnergy) {
  const auto a = mm::vcavity_multiple_albedo(mm::Ndf::beckmann(0.5, 0.5), dir(rad(60), 0.3),
                                             Material::mirror(), 4);
  EXPECT_NEAR(a[4], 1.0, 1e-12);
  double sum = 0;
  for (int k = 0; k < 4; ++k) sum += a[k];
  EXPECT_NEAR(sum, 1.0, 1e-12);
}

TEST(VCavityMultiple, QuadratureEqualsMonteCarloOverGrooves) {
  // Independent route: grooves from the Beckmann slope distribution (Gaussian slopes of
  // variance alpha^2 / 2 per axis: P22(s) ds = (n.m) D(m) dm, [Heitz14, App. A]), plain Monte Carlo.
  const mm::Ndf ndf = mm::Ndf::beckmann(0.5, 0.5);
  const Material mat = Material::conductor(0.2, 3.0);
  const int K = 4, M = 200000;
  for (double th : {20.0, 70.0}) {
    const Vec3 l = dir(rad(th), rad(40));
    const auto q = mm::vcavity_multiple_albedo(ndf, l, mat, K);
    std::mt19937_64 gen(7);
    std::normal_distribution<double> g(0.0, 0.5 / std::sqrt(2.0));
    std::vector<double> s(K + 1, 0.0), s2(K + 1, 0.0);
    for (int i = 0; i < M; ++i) {
      const double sx = g(gen), sy = g(gen);  // named: argument evaluation order is unspecified
      const Vec3 m = Vec3(-sx, -sy, 1.0).normalized();
      const mm::GrooveFrame f(m);
      const auto a = mm::vgroove_albedo(f.facet_angle, f.to_local(l), mat, K);
      for (int k = 0; k <= K; ++k) {
        s[k] += a[k];
        s2[k] += a[k] * a[k];
      }
    }
    const double zc = microsim::sidak_z(0.001, 2 * (K + 1));
    for (int k = 0; k <= K; ++k) {
      const double mean = s[k] / M, se = std::sqrt(std::max(0.0, s2[k] / M - mean * mean) / (M - 1));
      SCOPED_TRACE("theta " + std::to_string(th) + " slot " + std::to_string(k));
      if (se > 0) {
        EXPECT_LT(std::abs(mean - q[k]) / se, zc);
      } else {
        EXPECT_NEAR(mean, q[k], 1e-6);
      }
      // Power: a 2% change of any non-negligible slot is seen.
      if (q[k] > 0.01 && se > 0) { EXPECT_GT(std::abs(mean - 1.02 * q[k]) / se, zc); }
    }
  }
}

}  // namespace

// --- The validation rows built on these models (validate/bsdf_object_rows.hpp) ---------------

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/validate/bsdf_object_rows.hpp"

namespace {

microsim::BsdfResult mirror_bsdf(const microsim::Microsurface& s, double theta_deg, std::uint64_t rays,
                                 std::uint64_t seed = 1) {
  microsim::Tracer tracer(s);
  microsim::BsdfOptions o;
  o.theta_i = rad(theta_deg);
  o.rays = rays;
  o.resolution = 8;
  o.seed = seed;
  return microsim::measure_bsdf(tracer, o);
}

}  // namespace

TEST(BsdfObjectRows, BoxTotalAgainstVisibleAreaRatio) {
  using namespace microsim;
  BoxParams p;
  p.height = 0.5;
  Microsurface s = generate_box(p);
  const BsdfResult r = mirror_bsdf(s, 45.0, 60000);
  std::vector<validation::Row> rows;
  append_bsdf_object_rows(r, s, validation::Row{}, "theta 45", "box", Json::object(), rows);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].model_name, "visible_area_ratio");
  EXPECT_NEAR(*rows[0].model, 1.5, 1e-12);
  EXPECT_LT(std::abs(rows[0].measured - *rows[0].model) / *rows[0].stderr_, 3.5);
  EXPECT_FALSE(validation::mirror_total_is_one(s));
  // Power: the same rays against a box declared 10% taller are rejected.
  Microsurface taller = s;
  taller.description["height"] = 0.55;
  rows.clear();
  append_bsdf_object_rows(r, taller, validation::Row{}, "theta 45", "box", Json::object(), rows);
  EXPECT_GT(std::abs(rows[0].measured - *rows[0].model) / *rows[0].stderr_, 10.0);
}

TEST(BsdfObjectRows, VGrooveOrdersAgainstTheClosedForm) {
  using namespace microsim;
  VGrooveParams vp;
  vp.facet_angle_deg = 70.0;
  Microsurface s = generate_vgroove(vp);
  const BsdfResult r = mirror_bsdf(s, 20.0, 40000);
  std::vector<validation::Row> rows;
  append_bsdf_object_rows(r, s, validation::Row{}, "theta 20", "vg", Json::object(), rows);
  int tested = 0;
  for (const auto& row : rows) {
    EXPECT_EQ(row.model_name, "vgroove_multiple");
    EXPECT_EQ(row.kind, validation::Kind::Identity);
    if (row.quantity == "albedo_order_3") { EXPECT_NEAR(*row.model, 0.4679, 1e-4); }
    if (*row.stderr_ > 0) {
      EXPECT_LT(std::abs(row.measured - *row.model) / *row.stderr_, 3.5) << row.quantity;
      if (row.quantity == "albedo_order_3" || row.quantity == "albedo_order_4plus") ++tested;
    }
  }
  // Orders 3 and 4+ carry a replicate error; an empty order carries one only when a
  // rounding-level path (a ray grazing a ridge) lands in it, and is then z-tested like the rest.
  EXPECT_EQ(tested, 2);
}

TEST(BsdfObjectRows, AnOrderNoPathReachedHasTheErrorOfItsPathCount) {
  // A V-cavity ensemble at theta_i = 70 deg with few paths: order 3 has a closed-form albedo of
  // order 1/paths, so that some realizations land no path in it. Its error is then the
  // resolution of the path count (stats.hpp proportion_floor, ~0.7/n), not zero (which gave
  // z = -inf). The seeds are searched in order for the first realization with such an empty
  // order (bounded: about one realization in three has one, so 32 seeds all miss it with
  // probability ~1e-5 whatever the sampler's realizations). Power: the floor stays that small,
  // so a model 10/n away from the count is still rejected.
  using namespace microsim;
  VCavityParams vp;
  vp.grooves = 512;
  Microsurface s = generate_vcavity(vp);
  constexpr std::uint64_t kSeeds = 32;
  for (std::uint64_t seed = 1; seed <= kSeeds; ++seed) {
    const BsdfResult r = mirror_bsdf(s, 70.0, 25000, seed);
    std::vector<validation::Row> rows;
    append_bsdf_object_rows(r, s, validation::Row{}, "theta 70", "vc", Json::object(), rows);
    bool has_empty = false;
    for (const auto& row : rows)
      has_empty |= row.model_name == "vcavity_multiple_grooves" && row.measured == 0 && *row.model > 0;
    if (!has_empty) continue;
    const double floor = proportion_floor(r.measured.paths);
    ASSERT_GT(floor, 0);
    int empty = 0, tested = 0;
    for (const auto& row : rows) {
      if (row.model_name != "vcavity_multiple_grooves") continue;
      ASSERT_TRUE(row.stderr_.has_value());
      EXPECT_GE(*row.stderr_, floor) << row.quantity;
      const double z = (row.measured - *row.model) / *row.stderr_;
      EXPECT_LT(std::abs(z), 3.5) << row.quantity << " " << row.measured << " vs " << *row.model << " seed " << seed;
      ++tested;
      if (row.measured == 0 && *row.model > 0) {
        ++empty;
        EXPECT_GT(std::abs(row.measured - (*row.model + 10.0 / r.measured.paths)) / *row.stderr_, 3.5);
      }
    }
    EXPECT_GE(tested, 3);
    EXPECT_GE(empty, 1);
    std::printf("[ info ] seed %llu: %d empty order(s) among %d rows\n", static_cast<unsigned long long>(seed), empty, tested);
    return;
  }
  FAIL() << "no realization of seeds 1.." << kSeeds << " left an order empty";
}
