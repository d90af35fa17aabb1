// Masking-shadowing G2 ([GeomBSDF24, eq. 16], [Heitz14, Sec. 5]): exact square-wave values, the properties of
// [GeomBSDF24, eq. 16b] on explicit surfaces, the Smith forms, and the measure g2 command.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sys/stat.h>
#include <sys/wait.h>

#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/measure/stats.hpp"
#include "microsim/models/g2_forms.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;

namespace {

G2Options opts(std::uint64_t rays, std::uint64_t seed = 1) {
  G2Options o;
  o.rays = rays;
  o.seed = seed;
  return o;
}

Vec3 dir(double theta_deg, double phi_deg) { return direction_from_angles(rad(theta_deg), rad(phi_deg)); }

// The generator's square wave (surface/generators.hpp): ridges of width `top` and height `h`,
// trenches of width period - top between them, vertical walls.
struct SquareWave {
  double period = 1.0, top = 0.5, h = 0.25;
  double bottom() const { return period - top; }
};
Microsurface square_wave_mesh(const SquareWave& w) {
  SquareWaveParams p;
  p.period = w.period;
  p.duty = w.top / w.period;
  p.height = w.h;
  return generate_square_wave(p);
}

// Exact visibility on the square wave [GeomBSDF24, after eq. 16c], for directions o, i (z > 0); only
// their x components matter. For direction d the shift s_d = h d_x / d_z is the horizontal run
// of a ray rising over the wall height.
struct SquareWaveExact {
  double g2 = 0, g1_o = 0, g1_i = 0;
};
// Normal-n area (tops and bottoms): tops are always visible; a bottom point at x in the trench
// [a, a + b] is seen along d iff a + max(0, -s_d) <= x <= a + b - max(0, s_d).
SquareWaveExact square_wave_exact_n(const SquareWave& w, const Vec3& o, const Vec3& i) {
  const double so = w.h * o.x() / o.z(), si = w.h * i.x() / i.z(), b = w.bottom();
  auto seen = [&](double lo, double hi) { return std::max(0.0, b - lo - hi); };
  SquareWaveExact e;
  const double total = w.top + b;
  e.g1_o = (w.top + seen(std::max(0.0, -so), std::max(0.0, so))) / total;
  e.g1_i = (w.top + seen(std::max(0.0, -si), std::max(0.0, si))) / total;
  e.g2 = (w.top + seen(std::max({0.0, -so, -si}), std::max({0.0, so, si}))) / total;
  return e;
}
// A wall with normal (sign, 0, 0): faces d iff sign d_x > 0; a point at height z is seen along
// d iff z >= h - b d_z / |d_x| (the ray clears the opposite wall of the trench).
SquareWaveExact square_wave_exact_wall(const SquareWave& w, double sign, const Vec3& o, const Vec3& i) {
  auto seen = [&](const Vec3& d) {
    if (!(sign * d.x() > 0)) return 0.0;
    return std::min(w.h, w.bottom() * d.z() / std::abs(d.x())) / w.h;
  };
  SquareWaveExact e;
  e.g1_o = seen(o);
  e.g1_i = seen(i);
  e.g2 = std::min(e.g1_o, e.g1_i);  // both visible iff above the higher of the two limits
  return e;
}


// Bins of a run whose facets face both directions and were sampled.
std::vector<int> sampled_bins(const G2Result& r, std::uint64_t min_samples = 1) {
  std::vector<int> out;
  for (int b = 0; b < r.binning.size(); ++b)
    if (r.bins[b].front_area > 0 && r.bins[b].samples >= min_samples) out.push_back(b);
  return out;
}

}  // namespace

TEST(G2Forms, LambdaFormsAgreeWithTheNdfForms) {
  for (auto ndf : {models::Ndf::beckmann(0.5, 0.5), models::Ndf::ggx(0.3, 0.7)})
    for (auto [o, i] : {std::pair{dir(60, 0), dir(70, 180)}, std::pair{dir(30, 10), dir(80, 95)},
                        std::pair{dir(75, 40), dir(75, 40)}, std::pair{dir(0, 0), dir(45, 200)}}) {
      const Vec3 m(0, 0, 1);
      const models::G2Forms f = models::g2_forms_from_lambda(ndf.Lambda(o), ndf.Lambda(i),
                                                             models::azimuth_difference(o, i));
      EXPECT_NEAR(f.separable, models::G2_separable(ndf, o, i, m), 1e-14);
      EXPECT_NEAR(f.height_correlated, models::G2_height_correlated(ndf, o, i, m), 1e-14);
      EXPECT_NEAR(f.direction_correlated, models::G2_direction_correlated(ndf, o, i, m), 1e-14);
      EXPECT_NEAR(f.height_direction_correlated,
                  models::G2_height_direction_correlated(ndf, o, i, m), 1e-14);
    }
}

TEST(G2Forms, HotspotAndOppositeLimits) {
  // o = i (phi = 0): van Ginneken lambda = 0, so eq. 22 and 23 reduce to G1 [GeomBSDF24, eq. 16b].
  const double lo = 0.37;
  const models::G2Forms f = models::g2_forms_from_lambda(lo, lo, 0.0);
  EXPECT_DOUBLE_EQ(f.direction_correlated, 1 / (1 + lo));
  EXPECT_DOUBLE_EQ(f.height_direction_correlated, 1 / (1 + lo));
  EXPECT_DOUBLE_EQ(f.height_correlated, 1 / (1 + 2 * lo));
  // Opposite azimuths: lambda(pi) = 4.41 pi / (4.41 pi + 1).
  const models::G2Forms g = models::g2_forms_from_lambda(0.2, 0.5, kPi);
  const double l = 4.41 * kPi / (4.41 * kPi + 1);
  EXPECT_NEAR(g.height_direction_correlated, 1 / (1 + 0.5 + l * 0.2), 1e-15);
}

TEST(G2Measure, FlatPlaneIsNeverOccluded) {
  Microsurface s = flat_heightfield(16);
  Tracer tracer(s);
  G2Result r = measure_g2(tracer, dir(85, 0), dir(80, 200), opts(20000));
  EXPECT_EQ(r.visible_both, r.samples);
  EXPECT_EQ(r.visible_o, r.samples);
  EXPECT_NEAR(r.lambda_o, 0, 1e-12);
  EXPECT_NEAR(r.vcavity, 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(r.smith_numeric().height_correlated, 1.0);
}

TEST(G2Measure, SquareWaveMatchesExactGeometryPerNormal) {
  // [GeomBSDF24, after eq. 16c]: for the normal-n area at shallow angles G2 -> 1/2 while G1 G1 -> 1/4.
  // Every bin (n area, +x wall, -x wall) against its exact geometric value.
  SquareWave w;
  Microsurface s = square_wave_mesh(w);
  Tracer tracer(s);
  struct Pair { double to, po, ti, pi; };
  const std::vector<Pair> pairs = {{80, 0, 80, 180}, {80, 0, 75, 0}, {30, 0, 40, 180},
                                   {20, 0, 50, 0},   {60, 30, 45, 200}, {70, 180, 70, 180}};
  struct Cmp { double est, se, exact; std::string what; };
  std::vector<Cmp> cmps;
  for (const Pair& p : pairs) {
    const Vec3 o = dir(p.to, p.po), i = dir(p.ti, p.pi);
    G2Result r = measure_g2(tracer, o, i, opts(400000, 3));
    EXPECT_EQ(r.counters.lost_below + r.counters.unresolved, 0u);
    for (int b : sampled_bins(r)) {
      const Vec3 m = r.bins[b].mean_normal;
      SquareWaveExact e;
      if (m.z() > 0.99) e = square_wave_exact_n(w, o, i);
      else if (m.x() > 0.99) e = square_wave_exact_wall(w, +1, o, i);
      else if (m.x() < -0.99) e = square_wave_exact_wall(w, -1, o, i);
      else FAIL() << "unexpected normal " << m.transpose();
      const std::string what = "pair " + std::to_string(p.to) + "/" + std::to_string(p.po) + " -> " +
                               std::to_string(p.ti) + "/" + std::to_string(p.pi) + " m " +
                               std::to_string(m.x()) + "," + std::to_string(m.z());
      cmps.push_back({r.bin_g2(b).mean, r.bin_g2(b).stderr_, e.g2, what + " g2"});
      cmps.push_back({r.bin_g1_o(b).mean, r.bin_g1_o(b).stderr_, e.g1_o, what + " g1_o"});
      cmps.push_back({r.bin_g1_i(b).mean, r.bin_g1_i(b).stderr_, e.g1_i, what + " g1_i"});
    }
  }
  const double zmax = sidak_z(0.0027, static_cast<int>(cmps.size()));
  for (const Cmp& c : cmps) {
    if (c.se == 0) EXPECT_NEAR(c.est, c.exact, 1e-12) << c.what;
    else EXPECT_LT(std::abs(c.est - c.exact) / c.se, zmax) << c.what << " est " << c.est << " exact " << c.exact;
  }
  // The example of [GeomBSDF24, after eq. 16c] itself, with its numbers: shallow angles on both sides.
  const Vec3 o = dir(80, 0), i = dir(80, 180);
  G2Result r = measure_g2(tracer, o, i, opts(400000, 4));
  for (int b : sampled_bins(r))
    if (r.bins[b].mean_normal.z() > 0.99) {
      EXPECT_NEAR(r.bin_g2(b).mean, 0.5, 3 * r.bin_g2(b).stderr_);
      EXPECT_NEAR(r.bin_g1_o(b).mean * r.bin_g1_i(b).mean, 0.25, 0.01);
      EXPECT_GT(r.bin_g2(b).mean - r.bin_g1_o(b).mean * r.bin_g1_i(b).mean, 0.2);
    }
}

TEST(G2Measure, SquareWaveTestHasPower) {
  // The separable product G1(o,n) G1(i,n) as "exact" value must be rejected.
  SquareWave w;
  Microsurface s = square_wave_mesh(w);
  Tracer tracer(s);
  const Vec3 o = dir(30, 0), i = dir(40, 180);
  G2Result r = measure_g2(tracer, o, i, opts(400000, 3));
  for (int b : sampled_bins(r))
    if (r.bins[b].mean_normal.z() > 0.99) {
      const SquareWaveExact e = square_wave_exact_n(w, o, i);
      EXPECT_GT(std::abs(r.bin_g2(b).mean - e.g1_o * e.g1_i), 10 * r.bin_g2(b).stderr_);
    }
}

TEST(G2Properties, SymmetryHoldsSampleForSample) {
  // [GeomBSDF24, eq. 16b], directional symmetry: the points depend on the unordered pair {o, i}.
  Microsurface s = beckmann_tile(128, 5);
  Tracer tracer(s);
  const Vec3 o = dir(70, 10), i = dir(55, 160);
  G2Result a = measure_g2(tracer, o, i, opts(50000, 7)), b = measure_g2(tracer, i, o, opts(50000, 7));
  EXPECT_EQ(a.visible_both, b.visible_both);
  EXPECT_EQ(a.visible_o, b.visible_i);
  EXPECT_EQ(a.visible_i, b.visible_o);
  for (int k = 0; k < a.binning.size(); ++k) {
    EXPECT_EQ(a.bins[k].visible_both, b.bins[k].visible_both);
    EXPECT_EQ(a.bins[k].samples, b.bins[k].samples);
  }
  EXPECT_DOUBLE_EQ(a.vcavity, b.vcavity);
}

TEST(G2Properties, SymmetryHoldsBetweenIndependentRuns) {
  // The same property with independent points (different seeds): per bin z-tests.
  Microsurface s = beckmann_tile(128, 6);
  Tracer tracer(s);
  const Vec3 o = dir(75, 0), i = dir(50, 120);
  G2Result a = measure_g2(tracer, o, i, opts(200000, 1)), b = measure_g2(tracer, i, o, opts(200000, 2));
  std::vector<double> zs;
  for (int k : sampled_bins(a, 200)) {
    Estimate ea = a.bin_g2(k), eb = b.bin_g2(k);
    const double se = std::hypot(ea.stderr_, eb.stderr_);
    if (se > 0) zs.push_back((ea.mean - eb.mean) / se);
  }
  ASSERT_GT(zs.size(), 10u);
  const double zmax = sidak_z(0.01, static_cast<int>(zs.size()));
  for (double z : zs) EXPECT_LT(std::abs(z), zmax);
}

TEST(G2Properties, HeightCorrelationOnAHeightfieldIsExact) {
  // [GeomBSDF24, eq. 16b]: G2(v, m, n) = G1(v, m) on heightfields: nothing above a point of a heightfield
  // blocks the vertical ray, so every point visible from v is visible from both.
  Microsurface s = beckmann_tile(128, 8);
  Tracer tracer(s);
  for (double t : {40.0, 80.0}) {
    G2Result r = measure_g2(tracer, dir(t, 30), Vec3(0, 0, 1), opts(100000, 2));
    EXPECT_EQ(r.visible_i, r.samples) << t;
    EXPECT_EQ(r.visible_both, r.visible_o) << t;
    for (int b = 0; b < r.binning.size(); ++b) EXPECT_EQ(r.bins[b].visible_both, r.bins[b].visible_o);
    EXPECT_LT(r.visible_o, r.samples);  // and v itself does mask
  }
}

TEST(G2Properties, CoincidentDirectionsGiveTheIndependentlyMeasuredG1) {
  // [GeomBSDF24, eq. 16], G2(v, m, v) = G1(v, m), bin by bin and on average, against independent G1 runs
  // of measure_g1 on the same tile: its ray-casting estimator (first hits along -v, a different
  // route) per bin and its area-sampling estimator (other seed) on average. Tolerances from both
  // runs' replicate errors; power: G2(v, m, l) with l != v is not G1(v, m).
  Microsurface s = beckmann_tile(64, 10);
  Tracer tracer(s);
  const Vec3 v = dir(75, 20);
  const G2Options go = opts(200000, 3);
  const G2Result r = measure_g2(tracer, v, v, go);
  EXPECT_EQ(r.visible_both, r.visible_o);  // the two rays of a point agree
  G1Options o1;
  o1.rays = 200000;
  o1.seed = 99;
  const G1Result g = measure_g1(tracer, v, o1);
  ASSERT_EQ(g.binning.size(), r.binning.size());
  const G2Result other = measure_g2(tracer, v, dir(60, 200), go);
  std::vector<double> zs, zs_wrong;
  for (int b : sampled_bins(r, 500)) {
    const Estimate e = r.bin_g2(b), g1 = g.bin_g1_raycast(b);
    zs.push_back((e.mean - g1.mean) / std::hypot(e.stderr_, g1.stderr_));
    if (other.bins[b].samples > 500)
      zs_wrong.push_back((other.bin_g2(b).mean - g1.mean) /
                         std::hypot(other.bin_g2(b).stderr_, g1.stderr_));
  }
  ASSERT_GT(zs.size(), 10u);
  const double zmax = sidak_z(0.01, static_cast<int>(zs.size()));
  for (double z : zs) EXPECT_LT(std::abs(z), zmax);
  double worst = 0;
  for (double z : zs_wrong) worst = std::max(worst, std::abs(z));
  EXPECT_GT(worst, zmax);
  // On average: g2 against the area-sampling G1 of the other run (z within 3), and the plain
  // area weight of the old definition (sum A_f V_f / sum A_f over the facets facing v, from
  // the same counts reweighted) is rejected.
  const Estimate g2 = r.g2(), ga = g.g1_area_sampling();
  const double se = std::hypot(g2.stderr_, ga.stderr_);
  EXPECT_LT(std::abs(g2.mean - ga.mean), 3 * se) << g2.mean << " vs " << ga.mean;
  double plain = 0, area = 0;
  for (int b = 0; b < r.binning.size(); ++b)
    if (r.bins[b].samples > 0) {
      plain += r.bins[b].front_area * r.bin_g2(b).mean;
      area += r.bins[b].front_area;
    }
  EXPECT_GT(std::abs(plain / area - ga.mean), 3 * se) << plain / area << " vs " << ga.mean;
}

TEST(G2Measure, WallsPressedAgainstANeighbourAreHiddenFromBothDirections) {
  // Touching walls of tiled boxes [GeomBSDF24, Fig. 6] and of leaning parallelepipeds [GeomBSDF24, Fig. 3]
  // coincide with an opposite-facing twin: only the last column's walls facing +x are seen, so
  // G2(o, m, i) = 1/N for that bin at o = i (= G1(v, m), [GeomBSDF24, eq. 16]) and for o != i on the
  // same side. Tolerance from the replicate error; power: 10 % off 1/N, and the value 1 that
  // occlusion rays leaving a buried wall report, are rejected.
  BoxParams bp;
  bp.tiles = 4;
  ParallelepipedParams pp;
  pp.tiles = 3;
  const std::vector<std::pair<Microsurface, int>> cases = {{generate_tiled_boxes(bp), 4},
                                                           {generate_parallelepiped(pp), 3}};
  const double zmax = sidak_z(0.0027, 4);
  for (const auto& [s, n] : cases) {
    Tracer tracer(s);
    for (const Vec3& i : {dir(60, 0), dir(40, 0)}) {
      const G2Result r = measure_g2(tracer, dir(60, 0), i, opts(100000, 5));
      int tested = 0;
      for (int b : sampled_bins(r, 1000)) {
        if (r.bins[b].mean_normal.x() < 0.85) continue;  // the walls facing +x
        const Estimate e = r.bin_g2(b);
        const double exact = 1.0 / n;
        ASSERT_GT(e.stderr_, 0);
        EXPECT_LT(std::abs(e.mean - exact) / e.stderr_, zmax) << n << " " << e.mean;
        EXPECT_GT(std::abs(e.mean - 1.1 * exact) / e.stderr_, zmax) << n;
        EXPECT_GT(std::abs(e.mean - 1.0) / e.stderr_, zmax) << n;
        ++tested;
      }
      EXPECT_EQ(tested, 1) << n;
    }
  }
}

TEST(G2Measure, BeckmannTileHeightCorrelatedBeatsSeparableAtOppositeAzimuths) {
  // [Heitz14, Sec. 5]: with the directions on opposite sides the two visibilities of a point correlate
  // through its height (eq. 21); the separable form (eq. 20) ignores it. The forms are built in
  // each normal bin from the bin's measured G1(o, m), G1(i, m), so that only the correlation
  // assumption is tested (Smith's G1 itself depends on m on a real surface, which would confound
  // the comparison at grazing angles).
  Microsurface s = beckmann_tile(256, 11);
  Tracer tracer(s);
  for (double t : {60.0, 75.0}) {
    G2Result r = measure_g2(tracer, dir(t, 0), dir(t, 180), opts(400000, 5));
    const G2Result::FormsFromG1 f = r.forms_from_g1();
    const double se = std::max(f.diff_stderr.separable, f.diff_stderr.height_correlated);
    EXPECT_GT(f.diff.separable, 5 * f.diff_stderr.separable) << t;  // G2 > G1 G1: correlated
    EXPECT_GT(std::abs(f.diff.separable) - std::abs(f.diff.height_correlated), 5 * se) << t;
  }
  // Hotspot: Delta phi = 0, theta_o = theta_i: G2 = G1, which the direction-correlated forms
  // give and the separable and height-correlated ones do not.
  G2Result h = measure_g2(tracer, dir(70, 0), dir(70, 0), opts(400000, 6));
  EXPECT_EQ(h.visible_both, h.visible_o);
  const G2Result::FormsFromG1 f = h.forms_from_g1();
  EXPECT_NEAR(f.diff.direction_correlated, 0.0, 1e-12);
  EXPECT_NEAR(f.diff.height_direction_correlated, 0.0, 1e-12);
  EXPECT_GT(f.diff.separable, 10 * f.diff_stderr.separable);
  EXPECT_GT(f.diff.height_correlated, 10 * f.diff_stderr.height_correlated);
  const models::G2Forms sm = h.smith_numeric();
  EXPECT_NEAR(sm.direction_correlated, 1 / (1 + h.lambda_o), 1e-12);
}

// The standard errors of g2, its bins and *_from_g1_diff are checked two-sided against the
// seed-to-seed spread in test_calibration.cpp.

TEST(G2Measure, ResultsDoNotDependOnThreadCount) {
  Microsurface s = beckmann_tile(64, 2);
  Tracer tracer(s);
  auto run = [&](int threads) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
    return measure_g2(tracer, dir(70, 0), dir(60, 150), opts(60000, 3));
  };
  G2Result a = run(1), b = run(2);
  EXPECT_EQ(a.visible_both, b.visible_both);
  EXPECT_EQ(a.visible_o, b.visible_o);
  EXPECT_EQ(a.lambda_o, b.lambda_o);
  EXPECT_EQ(a.vcavity, b.vcavity);
  for (int k = 0; k < a.binning.size(); ++k) {
    EXPECT_EQ(a.bins[k].visible_both, b.bins[k].visible_both);
    EXPECT_EQ(a.bins[k].visible_both_r, b.bins[k].visible_both_r);  // every replicate
  }
  EXPECT_EQ(a.g2().stderr_, b.g2().stderr_);
  EXPECT_EQ(a.forms_from_g1().diff_stderr.separable, b.forms_from_g1().diff_stderr.separable);
}

TEST(G2Measure, RejectsDirectionsBelowTheHorizon) {
  Microsurface s = flat_heightfield(8);
  Tracer tracer(s);
  EXPECT_THROW(measure_g2(tracer, Vec3(1, 0, 0), Vec3(0, 0, 1), opts(10)), UsageError);
  EXPECT_THROW(measure_g2(tracer, Vec3(0, 0, 1), Vec3(1, 0, -0.1), opts(10)), UsageError);
  EXPECT_THROW(measure_g2(tracer, Vec3(0, 0, 1), Vec3(0, 0, 1), opts(0)), UsageError);
}

// ---------------------------------------------------------------------------------------------
// The command line
// ---------------------------------------------------------------------------------------------
namespace {
struct CliRun {
  int code;
  std::string err;
};
std::string tmp(const std::string& name) { return ::testing::TempDir() + "microsim_g2_" + name; }
CliRun run(const std::string& args) {
  const std::string err = tmp("stderr.txt");
  const std::string cmd = std::string(MICROSIM_BINARY) + " " + args + " >/dev/null 2>" + err;
  const int status = std::system(cmd.c_str());
  std::ifstream f(err);
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text};
}
bool exists(const std::string& p) {
  struct stat st;
  return stat(p.c_str(), &st) == 0;
}
}  // namespace

TEST(G2Cli, WritesRowsWithModelsAndBinsAndEnsembles) {
  const std::string s1 = tmp("a.exr"), s2 = tmp("b.exr"), out = tmp("g2.json"), out2 = tmp("g2e.json");
  ASSERT_EQ(run("generate gaussian --resolution 64 --seed 1 -o " + s1).code, 0);
  ASSERT_EQ(run("generate gaussian --resolution 64 --seed 2 -o " + s2).code, 0);
  CliRun r = run("measure g2 " + s1 + " --theta-o 60,70 --phi-o 0 --theta-i 50 --phi-i 0:180:180 "
              "--rays 5000 -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream f(out);
  Json j = Json::parse(f);
  ASSERT_EQ(j["rows"].size(), 4u);
  for (const char* k : {"theta_o_deg", "phi_o_deg", "theta_i_deg", "phi_i_deg", "g2", "g2_stderr",
                        "g1_o", "g1_i", "smith_separable", "smith_height_correlated",
                        "smith_direction_correlated", "smith_height_direction_correlated",
                        "vcavity", "smith_height_correlated_nominal", "bins"})
    EXPECT_TRUE(j["rows"][0].contains(k)) << k;
  for (const char* k : {"m", "area_fraction", "g2", "g2_stderr"})
    EXPECT_TRUE(j["rows"][0]["bins"][0].contains(k)) << k;
  EXPECT_EQ(j["rows"][3]["phi_i_deg"].get<double>(), 180.0);
  EXPECT_EQ(j["rows"][0]["replicates"].get<int>(), 32);  // errors from 32 replicates
  r = run("measure g2 " + s1 + " " + s2 + " --theta-o 60 --theta-i 60 --phi-i 180 --rays 5000 -o " + out2);
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream f2(out2);
  Json e = Json::parse(f2);
  EXPECT_EQ(e["rows"][0]["surfaces"].get<int>(), 2);
  EXPECT_TRUE(e["rows"][0].contains("g2_stderr_rays"));
  EXPECT_EQ(e["rows"][0]["replicates"].get<int>(), 32);
  EXPECT_TRUE(e["rows"][0]["z_height_correlated_nominal"].is_number());
  EXPECT_EQ(e["per_surface"].size(), 2u);
}

TEST(G2Cli, BadInputIsOneLineExitTwoAndNoFile) {
  const std::string s1 = tmp("c.exr"), out = tmp("bad.json");
  ASSERT_EQ(run("generate gaussian --resolution 32 -o " + s1).code, 0);
  for (const std::string args :
       {"--theta-o 90 --theta-i 10", "--theta-o 10 --theta-i -5", "--theta-o 10 --theta-i 10 --rays 0",
        "--theta-o x --theta-i 10", "--theta-o 10 --theta-i 10 --replicates 1"}) {
    std::remove(out.c_str());
    CliRun r = run("measure g2 " + s1 + " " + args + " -o " + out);
    EXPECT_EQ(r.code, 2) << args << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(exists(out));
  }
}
