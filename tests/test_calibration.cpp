// Calibration of the reported standard errors (docs/theory/error-bars.md: "over many seeds the spread of the
// estimate equals the reported error", checked two-sided). For every estimator: one fixed
// surface, 100 fixed ray seeds (the seed changes only the ray stream, so what is calibrated is
// the ray-count error of one surface, not the spread between surfaces). The sample standard
// deviation of the estimate over the seeds, divided by the root mean square of the reported
// errors, must lie in the two-sided 99% interval of sqrt(chi2_99 / 99) (the reported errors,
// each from 32 replicates, average to their expectation over 100 runs). Power: the same data
// with errors scaled by 1.5 or by 1/1.5 must fall outside that interval.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <string>

#include "test_helpers.hpp"
#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/measure/stats.hpp"
#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/measure/vndf_measure.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"

using namespace microsim;
using namespace microsim::testing;

namespace {

constexpr int kSeeds = 100;


Vec3 dir(double theta_deg, double phi_deg) { return direction_from_angles(rad(theta_deg), rad(phi_deg)); }

struct Calibration {
  double ratio = 0;      // sd over seeds / rms reported error
  RatioInterval interval;
};

// `run(seed)` returns one estimate with its reported error.
Calibration calibrate(const std::string& name, const std::function<Estimate(std::uint64_t)>& run) {
  std::vector<double> x(kSeeds);
  double mean = 0, se2 = 0;
  for (int k = 0; k < kSeeds; ++k) {
    const Estimate e = run(1000 + 7 * k);
    x[k] = e.mean;
    mean += e.mean / kSeeds;
    se2 += e.stderr_ * e.stderr_ / kSeeds;
  }
  double var = 0;
  for (double v : x) var += (v - mean) * (v - mean) / (kSeeds - 1);
  Calibration c;
  c.ratio = std::sqrt(var / se2);
  c.interval = sd_ratio_interval(kSeeds - 1, 0.01);
  std::printf("[ calibration ] %-40s mean %.6g  rms stderr %.3g  spread/stderr %.3f  99%% [%.3f, %.3f]\n",
              name.c_str(), mean, std::sqrt(se2), c.ratio, c.interval.lo, c.interval.hi);
  return c;
}

void expect_calibrated(const Calibration& c) {
  EXPECT_TRUE(c.interval.contains(c.ratio)) << c.ratio;
  // Power: errors 1.5 times too large, or too small, would be rejected by the same data.
  EXPECT_FALSE(c.interval.contains(c.ratio / 1.5)) << "errors too large by 1.5 would pass";
  EXPECT_FALSE(c.interval.contains(c.ratio * 1.5)) << "errors too small by 1.5 would pass";
}

}  // namespace

TEST(Chi2Quantile, MatchesTabulatedValues) {
  // Tabulated chi-square quantiles (Abramowitz & Stegun table 26.8 and exact forms).
  EXPECT_NEAR(chi2_quantile(0.95, 1), 3.841459, 1e-5);
  EXPECT_NEAR(chi2_quantile(0.05, 1), 0.00393214, 1e-7);
  EXPECT_NEAR(chi2_quantile(0.5, 2), 2 * std::log(2.0), 1e-10);  // exponential: -2 ln(1-p)
  EXPECT_NEAR(chi2_quantile(0.99, 2), -2 * std::log(0.01), 1e-9);
  EXPECT_NEAR(chi2_quantile(0.975, 10), 20.4832, 1e-3);
  EXPECT_NEAR(chi2_quantile(0.005, 49), 27.2493, 2e-3);
  EXPECT_NEAR(chi2_quantile(0.995, 49), 78.2307, 2e-3);
  EXPECT_NEAR(chi2_quantile(0.995, 100), 140.169, 2e-3);
  EXPECT_NEAR(chi2_quantile(0.005, 100), 67.3276, 2e-3);
  // The quantile inverts the tail: P(X >= q) = 1 - p.
  for (double p : {0.001, 0.1, 0.5, 0.9, 0.999})
    for (int dof : {1, 3, 49, 99, 400}) EXPECT_NEAR(chi2_p_value(chi2_quantile(p, dof), dof), 1 - p, 1e-9);
  const RatioInterval ci = sd_ratio_interval(49, 0.01);
  EXPECT_NEAR(ci.lo, 0.7457, 1e-3);
  EXPECT_NEAR(ci.hi, 1.2635, 1e-3);
}

TEST(Calibration, G1AreaSamplingAveraged) {
  Microsurface s = beckmann_tile(32, 5);
  Tracer tracer(s);
  G1Options o;
  o.rays = 4096;
  expect_calibrated(calibrate("g1 area sampling, 80 deg", [&](std::uint64_t seed) {
    o.seed = seed;
    return measure_g1(tracer, dir(80, 0), o).g1_area_sampling();
  }));
}

TEST(Calibration, G1RaycastPerBin) {
  // The averaged ray-cast G1 of a periodic heightfield is 1/(1+Lambda) identically (every ray
  // hits once): its replicate error and its spread are both zero up to lost rays. Per normal
  // bin it is a real estimate: a well filled bin and a sparse one.
  Microsurface s = beckmann_tile(32, 5);
  Tracer tracer(s);
  G1Options o;
  o.rays = 4096;
  o.seed = 1;
  const Vec3 v = dir(80, 0);
  const G1Result ref = measure_g1(tracer, v, o);
  EXPECT_LT(ref.g1_raycast().stderr_, 1e-12);
  int full = 0, sparse = -1;
  for (int b = 0; b < ref.binning.size(); ++b)
    if (ref.bins[b].raycast_hits > ref.bins[full].raycast_hits) full = b;
  for (int b = 0; b < ref.binning.size(); ++b) {
    const double f = static_cast<double>(ref.bins[b].raycast_hits) / ref.raycast_rays;
    if (f > 0.01 && f < 0.04) sparse = b;
  }
  ASSERT_GE(sparse, 0);
  for (int b : {full, sparse})
    expect_calibrated(calibrate("g1 raycast, bin " + std::to_string(b), [&](std::uint64_t seed) {
      o.seed = seed;
      return measure_g1(tracer, v, o).bin_g1_raycast(b);
    }));
}

TEST(Calibration, G1AreaSamplingPerBin) {
  Microsurface s = beckmann_tile(32, 5);
  Tracer tracer(s);
  G1Options o;
  o.rays = 4096;
  const Vec3 v = dir(70, 0);
  int b = -1;
  {
    o.seed = 1;
    const G1Result ref = measure_g1(tracer, v, o);
    for (int k = 0; k < ref.binning.size(); ++k)
      if (b < 0 || ref.bins[k].samples > ref.bins[b].samples) b = k;
  }
  expect_calibrated(calibrate("g1 area sampling, bin " + std::to_string(b), [&](std::uint64_t seed) {
    o.seed = seed;
    return measure_g1(tracer, v, o).bin_g1_area_sampling(b);
  }));
}

TEST(Calibration, G2AveragedAndPerBinAndForms) {
  Microsurface s = beckmann_tile(32, 6);
  Tracer tracer(s);
  G2Options o;
  o.rays = 4096;
  const Vec3 vo = dir(70, 0), vi = dir(60, 150);
  int b = -1;
  {
    o.seed = 1;
    const G2Result ref = measure_g2(tracer, vo, vi, o);
    for (int k = 0; k < ref.binning.size(); ++k)
      if (b < 0 || ref.bins[k].samples > ref.bins[b].samples) b = k;
  }
  expect_calibrated(calibrate("g2 averaged", [&](std::uint64_t seed) {
    o.seed = seed;
    return measure_g2(tracer, vo, vi, o).g2();
  }));
  expect_calibrated(calibrate("g2 bin " + std::to_string(b), [&](std::uint64_t seed) {
    o.seed = seed;
    return measure_g2(tracer, vo, vi, o).bin_g2(b);
  }));
  expect_calibrated(calibrate("g2 - height-correlated form from g1", [&](std::uint64_t seed) {
    o.seed = seed;
    const G2Result::FormsFromG1 f = measure_g2(tracer, dir(75, 0), dir(65, 180), o).forms_from_g1();
    return Estimate{f.diff.height_correlated, f.diff_stderr.height_correlated, 0};
  }));
}

TEST(Calibration, VndfBin) {
  Microsurface s = beckmann_tile(32, 7);
  Tracer tracer(s);
  VndfOptions o;
  o.rays = 4000;
  const Vec3 v = dir(60, 0);
  int b = -1;
  {
    o.seed = 1;
    const VndfResult ref = measure_vndf(tracer, v, o);
    for (int k = 0; k < ref.binning.size(); ++k)
      if (b < 0 || ref.bin_hits[k] > ref.bin_hits[b]) b = k;
  }
  expect_calibrated(calibrate("vndf bin " + std::to_string(b), [&](std::uint64_t seed) {
    o.seed = seed;
    return measure_vndf(tracer, v, o).dv(b);
  }));
}

TEST(Calibration, BsdfAlbedoPerOrderAndInPlane) {
  Microsurface s = beckmann_tile(32, 8, 0.8);
  Tracer tracer(s);
  BsdfOptions o;
  o.rays = 4096;
  o.theta_i = rad(60);
  o.resolution = 8;
  o.material = models::Material::conductor(0.2, 3.0);
  for (int k : {0, 1}) {
    expect_calibrated(calibrate("bsdf albedo order " + std::to_string(k + 1), [&](std::uint64_t seed) {
      o.seed = seed;
      return measure_bsdf(tracer, o).albedo(0, k);
    }));
  }
  const int b = 5;  // in-plane bin on the specular side, theta_o 22.5..45 deg
  expect_calibrated(calibrate("bsdf in-plane f, total", [&](std::uint64_t seed) {
    o.seed = seed;
    return measure_bsdf(tracer, o).f_plane(0, o.orders, b);
  }));
}

TEST(Calibration, VcavityEnsemble) {
  VCavityParams p;
  p.grooves = 64;
  p.seed = 3;
  const Microsurface s = generate_vcavity(p);
  const SceneEnsemble grooves = vcavity_grooves(s, "test", GrooveFrames::StoredNormalOverHypot);
  G1Options o;
  o.rays = 4096;
  const std::vector<Vec3> views = {dir(70, 30)};
  int b = -1;
  {
    o.seed = 1;
    const G1Result ref = measure_g1(grooves, views, o)[0];
    for (int k = 0; k < ref.binning.size(); ++k)
      if (b < 0 || ref.bins[k].raycast_hits > ref.bins[b].raycast_hits) b = k;
  }
  expect_calibrated(calibrate("vcavity g1 area sampling", [&](std::uint64_t seed) {
    o.seed = seed;
    return measure_g1(grooves, views, o)[0].g1_area_sampling();
  }));
  expect_calibrated(calibrate("vcavity g1 raycast bin " + std::to_string(b), [&](std::uint64_t seed) {
    o.seed = seed;
    return measure_g1(grooves, views, o)[0].bin_g1_raycast(b);
  }));
}

TEST(Calibration, G1RaycastAveragedOnAFiniteObject) {
  // On a finite object (a box) the window's rays can miss: the averaged ray-cast G1 and the
  // visible area ratio are real estimates there (unlike on a periodic tile).
  BoxParams p;
  const Microsurface s = generate_box(p);
  Tracer tracer(s);
  G1Options o;
  o.rays = 4096;
  expect_calibrated(calibrate("box visible area ratio, 60 deg", [&](std::uint64_t seed) {
    o.seed = seed;
    return measure_g1(tracer, dir(60, 20), o).visible_area_ratio();
  }));
}
