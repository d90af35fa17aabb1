// Tests of the Smith walk model column at the measurement's accuracy (measure/smith_walk_budget.hpp):
// expected escapes tally the same means per order as drawn escapes (with a power check), the shifted-Sobol
// replicates give the same tallies for any thread count, and the number of walks meets the error target.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/smith_walk_budget.hpp"
#include "microsim/models/smith_random_walk.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"

using namespace microsim;
namespace mm = microsim::models;

namespace {

struct Rng {
  CounterRng c;
  double uniform() { return c.uniform(); }
};

// Per-order albedo means and standard errors of n independent walks: slot k = 0 .. K-2 the orders, K-1 the
// orders K and above, per side; `expected`: expected escapes at orders 1 .. K - 1 (times `bias`: a deliberately
// wrong weight for the power check).
struct OrderMeans {
  std::vector<double> mean, se;  // [side * K + k]
};
// `forced`: forced continuation through the orders 1 .. K - 1 (walk_with_forced_continuation) instead.
OrderMeans order_means(const mm::SmithRandomWalk& walk, const Vec3& wi, int K, std::uint64_t n, bool expected,
                       std::uint64_t stream, double bias = 1.0, bool forced = false) {
  std::vector<double> sum(2 * K, 0.0), sum2(2 * K, 0.0), x(2 * K);
  for (std::uint64_t i = 0; i < n; ++i) {
    Rng rng{CounterRng(7, stream, i)};
    std::fill(x.begin(), x.end(), 0.0);
    auto slot = [&](bool reflected, int order) { return (reflected ? 0 : K) + std::min(order, K) - 1; };
    auto tally = [&](const mm::WalkEscape& s) { x[slot(s.reflected, s.order)] += bias * s.weight; };
    const mm::WalkExit e =
        forced ? walk.walk_with_forced_continuation(wi, rng, [](const mm::WalkVertex&) {}, K - 1, tally)
               : walk.walk_with_expected_escapes(wi, rng, [](const mm::WalkVertex&) {}, expected ? K - 1 : 0, tally);
    if (!e.lost && e.order >= 1 && (!expected || e.order >= K)) x[slot(e.reflected, e.order)] += e.weight;
    for (int k = 0; k < 2 * K; ++k) {
      sum[k] += x[k];
      sum2[k] += x[k] * x[k];
    }
  }
  OrderMeans m;
  for (int k = 0; k < 2 * K; ++k) {
    const double mu = sum[k] / n;
    m.mean.push_back(mu);
    m.se.push_back(std::sqrt(std::max(0.0, sum2[k] / n - mu * mu) / (n - 1)));
  }
  return m;
}

// Largest |difference| / combined standard error over the slots.
double largest_z(const OrderMeans& a, const OrderMeans& b) {
  double z = 0.0;
  for (std::size_t k = 0; k < a.mean.size(); ++k) {
    const double se = std::hypot(a.se[k], b.se[k]);
    if (se > 0.0) z = std::max(z, std::abs(a.mean[k] - b.mean[k]) / se);
  }
  return z;
}

// 3 materials x 2 roughnesses x 2 incidences x 8 slots: a Sidak bound for 96 z at 1e-3 overall is ~4.4.
constexpr double kZ = 4.5;

}  // namespace

TEST(SmithWalkExpectedEscapes, SameMeanPerOrderAsDrawnEscapes) {
  const int K = 4;
  const std::uint64_t n = 60000;
  double worst = 0.0;
  for (const mm::Material& mat :
       {mm::Material::mirror(), mm::Material::conductor(0.47, 2.4), mm::Material::dielectric(1.5)})
    for (double alpha : {0.3, 0.8})
      for (double theta : {0.0, 60.0}) {
        const mm::SmithRandomWalk walk(mm::Ndf::beckmann(alpha, alpha), mat);
        const Vec3 wi = direction_from_angles(rad(theta), 0.0);
        const OrderMeans drawn = order_means(walk, wi, K, n, false, 1);
        const OrderMeans expected = order_means(walk, wi, K, n, true, 2);
        const double z = largest_z(drawn, expected);
        worst = std::max(worst, z);
        EXPECT_LT(z, kZ) << to_string(mat.kind) << " alpha " << alpha << " theta " << theta;
        // The expected escapes' error of order 1 is smaller (the point of the estimator).
        EXPECT_LT(expected.se[0], drawn.se[0]) << to_string(mat.kind) << " alpha " << alpha << " theta " << theta;
      }
  RecordProperty("largest_z", std::to_string(worst));
}

TEST(SmithWalkExpectedEscapes, WrongWeightIsDetected) {
  // Power: the expected escapes tallied 5% too heavy are rejected at the same threshold.
  const int K = 4;
  const mm::SmithRandomWalk walk(mm::Ndf::beckmann(0.5, 0.5), mm::Material::mirror());
  const Vec3 wi = direction_from_angles(rad(30.0), 0.0);
  const OrderMeans drawn = order_means(walk, wi, K, 60000, false, 1);
  const OrderMeans wrong = order_means(walk, wi, K, 60000, true, 2, 1.05);
  EXPECT_GT(largest_z(drawn, wrong), kZ);
}

TEST(SmithWalkForcedContinuation, SameMeanPerOrderAsDrawnEscapes) {
  const int K = 4;
  const std::uint64_t n = 60000;
  double worst = 0.0;
  for (const mm::Material& mat :
       {mm::Material::mirror(), mm::Material::conductor(0.47, 2.4), mm::Material::dielectric(1.5)})
    for (double alpha : {0.3, 0.8})
      for (double theta : {0.0, 60.0}) {
        const mm::SmithRandomWalk walk(mm::Ndf::beckmann(alpha, alpha), mat);
        const Vec3 wi = direction_from_angles(rad(theta), 0.0);
        const OrderMeans drawn = order_means(walk, wi, K, n, false, 1);
        const OrderMeans forced = order_means(walk, wi, K, n, true, 3, 1.0, true);
        const double z = largest_z(drawn, forced);
        worst = std::max(worst, z);
        EXPECT_LT(z, kZ) << to_string(mat.kind) << " alpha " << alpha << " theta " << theta;
        // Every walk reaches order 3: the reflected order 3's error is smaller (the point of the estimator; a
        // dielectric's reflected order 3 also needs the drawn refractions, its error is about the same).
        if (mat.kind != mm::MaterialKind::Dielectric && drawn.se[2] > 0.0) {
          EXPECT_LT(forced.se[2], drawn.se[2]) << to_string(mat.kind) << " alpha " << alpha << " theta " << theta;
        }
      }
  RecordProperty("largest_z", std::to_string(worst));
}

TEST(SmithWalkForcedContinuation, WrongWeightIsDetected) {
  // Power: the forced escapes tallied 3% too heavy are rejected at the same threshold.
  const int K = 4;
  const mm::SmithRandomWalk walk(mm::Ndf::beckmann(0.5, 0.5), mm::Material::mirror());
  const Vec3 wi = direction_from_angles(rad(30.0), 0.0);
  const OrderMeans drawn = order_means(walk, wi, K, 60000, false, 1);
  const OrderMeans wrong = order_means(walk, wi, K, 60000, true, 2, 1.03, true);
  EXPECT_GT(largest_z(drawn, wrong), kZ);
}

TEST(SmithWalkForcedContinuation, MirrorWalkAddsUpToOne) {
  // The weights telescope: the forced escapes of orders 1 .. K - 1 and the drawn exit of order K or above
  // add up to 1 for every mirror walk.
  const int K = 4;
  const mm::SmithRandomWalk walk(mm::Ndf::beckmann(0.5, 0.5), mm::Material::mirror());
  for (double theta : {0.0, 45.0, 85.0}) {
    const Vec3 wi = direction_from_angles(rad(theta), 0.7);
    for (std::uint64_t i = 0; i < 3000; ++i) {
      Rng rng{CounterRng(9, 4, i)};
      double sum = 0.0;
      int escapes = 0;
      const mm::WalkExit e = walk.walk_with_forced_continuation(
          wi, rng, [](const mm::WalkVertex&) {}, K - 1, [&](const mm::WalkEscape& s) {
            sum += s.weight;
            ++escapes;
          });
      ASSERT_FALSE(e.lost);
      if (e.order >= K) {
        sum += e.weight;
        EXPECT_LE(escapes, K - 1);  // one per upward leg (a leg may point down)
      }
      EXPECT_NEAR(sum, 1.0, 1e-12) << "theta " << theta << " walk " << i;
    }
  }
}

namespace {
// Per-order means of n walks with the weight window [low, high] (walk_with_weight_window; order-0 corrections
// left out: they belong to the total); `total`: per walk the sum of all its tallies with the corrections.
OrderMeans window_means(const mm::SmithRandomWalk& walk, const Vec3& wi, int K, std::uint64_t n, double low,
                        double high, std::uint64_t stream, std::vector<double>* total = nullptr, double bias = 1.0) {
  std::vector<double> sum(2 * K, 0.0), sum2(2 * K, 0.0), x(2 * K);
  for (std::uint64_t i = 0; i < n; ++i) {
    Rng rng{CounterRng(7, stream, i)};
    std::fill(x.begin(), x.end(), 0.0);
    double all = 0.0;
    walk.walk_with_weight_window(wi, rng, K - 1, low, high, [&](const mm::WalkEscape& s) {
      all += s.weight;
      if (s.order >= 1) x[(s.reflected ? 0 : K) + std::min(s.order, K) - 1] += (s.order < K ? bias : 1.0) * s.weight;
    });
    if (total) total->push_back(all);
    for (int k = 0; k < 2 * K; ++k) {
      sum[k] += x[k];
      sum2[k] += x[k] * x[k];
    }
  }
  OrderMeans m;
  for (int k = 0; k < 2 * K; ++k) {
    const double mu = sum[k] / n;
    m.mean.push_back(mu);
    m.se.push_back(std::sqrt(std::max(0.0, sum2[k] / n - mu * mu) / (n - 1)));
  }
  return m;
}
}  // namespace

TEST(SmithWalkWeightWindow, SameMeanPerOrderAsDrawnEscapes) {
  // Splitting and roulette keep every order's mean (a window around 0.1, so that both act on every walk);
  // power: the forced escapes 3% too heavy are rejected.
  const int K = 4;
  const std::uint64_t n = 60000;
  double worst = 0.0;
  for (const mm::Material& mat :
       {mm::Material::mirror(), mm::Material::conductor(0.47, 2.4), mm::Material::dielectric(1.5)})
    for (double alpha : {0.3, 0.8})
      for (double theta : {0.0, 60.0}) {
        const mm::SmithRandomWalk walk = mm::SmithRandomWalk(mm::Ndf::beckmann(alpha, alpha), mat).with_fast_slope_sampler();
        const Vec3 wi = direction_from_angles(rad(theta), 0.0);
        const OrderMeans drawn = order_means(walk, wi, K, n, false, 1);
        const OrderMeans window = window_means(walk, wi, K, n, 0.025, 0.2, 5);
        const double z = largest_z(drawn, window);
        worst = std::max(worst, z);
        EXPECT_LT(z, kZ) << to_string(mat.kind) << " alpha " << alpha << " theta " << theta;
      }
  RecordProperty("largest_z", std::to_string(worst));
  const mm::SmithRandomWalk walk(mm::Ndf::beckmann(0.5, 0.5), mm::Material::mirror());
  const Vec3 wi = direction_from_angles(rad(30.0), 0.0);
  const OrderMeans drawn = order_means(walk, wi, K, n, false, 1);
  EXPECT_GT(largest_z(drawn, window_means(walk, wi, K, n, 0.025, 0.2, 5, nullptr, 1.03)), kZ);
}

TEST(SmithWalkWeightWindow, MirrorTotalIsOneAndHigherOrdersAreSharper) {
  // With the roulette's corrections a mirror walk's tallies still add up to 1; against plain forced
  // continuation ([0, inf]) the window lowers the order-3 error at fewer events per walk.
  const int K = 4;
  const mm::SmithRandomWalk walk(mm::Ndf::beckmann(0.5, 0.5), mm::Material::mirror());
  const Vec3 wi = direction_from_angles(rad(0.0), 0.0);
  std::vector<double> total;
  const OrderMeans window = window_means(walk, wi, K, 40000, 0.015, 0.12, 6, &total);
  for (double x : total) ASSERT_NEAR(x, 1.0, 1e-12);
  const OrderMeans forced = window_means(walk, wi, K, 40000, 0.0, std::numeric_limits<double>::infinity(), 6);
  EXPECT_LT(1.5 * window.se[2], forced.se[2]);
}

TEST(SmithWalkExpectedEscapes, NoExpectedOrdersIsTheDrawnWalk) {
  // expected_orders = 0: the same draws and exits as walk().
  const mm::SmithRandomWalk walk(mm::Ndf::beckmann(0.6, 0.6), mm::Material::dielectric(1.5));
  const Vec3 wi = direction_from_angles(rad(50.0), 0.0);
  for (std::uint64_t i = 0; i < 2000; ++i) {
    Rng a{CounterRng(3, 9, i)}, b{CounterRng(3, 9, i)};
    const mm::WalkExit x = walk.walk(wi, a);
    int calls = 0;
    const mm::WalkExit y = walk.walk_with_expected_escapes(
        wi, b, [](const mm::WalkVertex&) {}, 0, [&](const mm::WalkEscape&) { ++calls; });
    EXPECT_EQ(calls, 0);
    EXPECT_EQ(x.order, y.order);
    EXPECT_EQ(x.reflected, y.reflected);
    EXPECT_EQ(x.direction, y.direction);
  }
}

namespace {
Microsurface gaussian_tile(double alpha, std::uint64_t seed) {
  GaussianParams gp;
  gp.alpha_x = gp.alpha_y = alpha;
  gp.resolution = 64;
  gp.seed = seed;
  return generate_gaussian(gp);
}
BsdfOptions walk_options(const mm::Material& m, double theta_deg, std::uint64_t rays) {
  BsdfOptions o;
  o.material = m;
  o.theta_i = rad(theta_deg);
  o.rays = rays;
  o.resolution = 8;
  o.model_walks = rays;
  return o;
}
// The Smith walk of a Beckmann alpha 0.5 mirror with the fast slope sampler, as the measurement runs it.
mm::SmithRandomWalk beckmann_mirror_walk() {
  return mm::SmithRandomWalk(mm::Ndf::beckmann(0.5, 0.5), mm::Material::mirror(), mm::HeightDistribution::Uniform, 1000)
      .with_fast_slope_sampler();
}
// A result to walk into: 4 orders, an 8x8 hemisphere map and 8 in-plane bins, incidence theta_deg.
BsdfResult four_order_result(double theta_deg) {
  BsdfResult r;
  r.options.orders = 4;
  r.map = HemisphereMap(8);
  r.plane = InPlaneBins(0.0, 8);
  r.wi = direction_from_angles(rad(theta_deg), 0.0);
  return r;
}
}  // namespace

TEST(SmithWalkBudget, IndependentOfThreadCount) {
  const Microsurface s = gaussian_tile(0.5, 2);
  Tracer tracer(s);
  const BsdfOptions o = walk_options(mm::Material::dielectric(1.5), 40.0, 40000);
  BsdfResult a, b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a = measure_bsdf(tracer, o);
  }
  b = measure_bsdf(tracer, o);
  ASSERT_TRUE(a.smith_walk && b.smith_walk);
  EXPECT_GT(a.smith_walk->replicates, 1);
  EXPECT_EQ(a.smith_walk->paths, b.smith_walk->paths);
  EXPECT_EQ(a.smith_walk->albedo, b.smith_walk->albedo);  // bitwise
  EXPECT_EQ(a.smith_walk->albedo2, b.smith_walk->albedo2);
  EXPECT_EQ(a.smith_walk->plane, b.smith_walk->plane);
  EXPECT_EQ(a.smith_walk->pix2, b.smith_walk->pix2);
}

TEST(SmithWalkBudget, ErrorTargetMetBelowTheCap) {
  // Where the cap (model_walks) is not reached, every albedo slot's walk error is at most the
  // measurement's (the pilot margin and the re-checked runs cover the pilot's own uncertainty); a target
  // half as large needs more walks (power: the rule follows the target): 4x where the error falls like
  // 1 / sqrt(m), 2x where the Sobol points make it fall like 1 / m.
  const Microsurface s = gaussian_tile(0.5, 3);
  Tracer tracer(s);
  int checked = 0;
  for (const mm::Material& mat : {mm::Material::mirror(), mm::Material::conductor(0.47, 2.4), mm::Material::dielectric(1.5)})
    for (double theta : {20.0, 70.0}) {
      BsdfOptions o = walk_options(mat, theta, 20000);
      o.model_walks = 2000000;  // a cap far above the need
      const BsdfResult r = measure_bsdf(tracer, o);
      ASSERT_TRUE(r.smith_walk);
      ASSERT_LT(r.smith_walk->paths, o.model_walks * kWalkCapFactor);
      EXPECT_LE(smith_walk_error_ratio(r), 1.0) << to_string(mat.kind) << " theta " << theta;
      o.model_error_fraction = 0.5;
      const BsdfResult tight = measure_bsdf(tracer, o);
      EXPECT_GT(tight.smith_walk->paths, 3 * r.smith_walk->paths / 2) << to_string(mat.kind) << " theta " << theta;
      if (tight.smith_walk->paths < o.model_walks * kWalkCapFactor) {
        EXPECT_LE(smith_walk_error_ratio(tight), 0.5) << to_string(mat.kind) << " theta " << theta;
      }
      ++checked;
    }
  EXPECT_EQ(checked, 6);
}

TEST(SmithWalkBudget, WalksFromThePilotRule) {
  // smith_walk_budget: m = m_pilot (margin * se_pilot / (fraction * se_measured))^2 for the slot that needs the
  // most, clamped to [m_pilot, cap]; here constructed tallies with known errors.
  BsdfResult r;
  r.options.orders = 2;
  r.measured = BsdfTally(2, 1, 1);
  BsdfTally pilot(2, 1, 1);
  // Two replicates of 100 walks per slot: replicate means x1, x2 give sum = 100 (x1 + x2) and
  // squared deviations (x1 - x2)^2 / 2, so se = |x1 - x2| / 2.
  auto replicate = [](BsdfTally& t, int n, const std::vector<double>& means) {
    BsdfTally rep(2, 1, 1);
    rep.paths = static_cast<std::uint64_t>(n);
    for (std::size_t k = 0; k < means.size(); ++k) rep.albedo[k] = means[k] * n;
    t.add_replicate(rep);
  };
  // slots (side 0): order_1, order_2plus, total; side 1 all zero.
  replicate(r.measured, 1000, {0.50, 0.10, 0.60, 0, 0, 0});
  replicate(r.measured, 1000, {0.52, 0.11, 0.63, 0, 0, 0});  // se 0.01, 0.005, 0.015
  replicate(pilot, 100, {0.40, 0.20, 0.60, 0, 0, 0});
  replicate(pilot, 100, {0.48, 0.21, 0.69, 0, 0, 0});  // se 0.04, 0.005, 0.045
  const WalkBudget b = smith_walk_budget(pilot, r, 1.0, 1000000, 1.0);
  // order_1: (1.0 * 0.04 / 0.01)^2 = 16 -> 1600 walks per replicate; total: (1.0 * 3)^2 = 9 -> 900.
  EXPECT_EQ(b.limiting_side, 0);
  EXPECT_EQ(b.limiting_slot, 0);
  EXPECT_NEAR(static_cast<double>(b.walks), 2.0 * 1600, 2.0);
  // a margin divides the target: (1.25 * 4)^2 = 25 -> 2500
  EXPECT_NEAR(static_cast<double>(smith_walk_budget(pilot, r, 1.0, 1000000, 1.25).walks), 2.0 * 2500, 2.0);
  // the first run after the pilot (default margin kWalkPilotMargin = 1/sqrt(2)): half the estimate
  EXPECT_NEAR(static_cast<double>(smith_walk_budget(pilot, r, 1.0, 1000000).walks), 2.0 * 800, 2.0);
  EXPECT_EQ(smith_walk_budget(pilot, r, 1.0, 700).walks, 1400u);  // the cap
  EXPECT_EQ(smith_walk_budget(pilot, r, 100.0, 1000000).walks, 200u);  // at least the pilot
  // A run is kept when every slot's error is at most fraction x the measured: order_1's 0.04 against 0.01.
  EXPECT_FALSE(smith_walk_target_met(pilot, r, 1.0));
  EXPECT_FALSE(smith_walk_target_met(pilot, r, 3.99));
  EXPECT_TRUE(smith_walk_target_met(pilot, r, 4.01));
}

TEST(SmithWalkBudget, ReplicateAlbedosAreTheFullTallysAlbedos) {
  // replicate_albedos: the albedo slots of replicates added by add_replicate, without their cells (what the
  // budget and the target check read), equal bit for bit to those of the full tally.
  const int K = 3;
  std::vector<BsdfTally> reps;
  BsdfTally full(K, 4, 2);
  for (int q = 0; q < 5; ++q) {
    BsdfTally rep(K, 4, 2);
    rep.paths = 100;
    for (std::size_t k = 0; k < rep.albedo.size(); ++k) rep.albedo[k] = 10.0 + q * (0.3 + k) + 0.01 * q * q;
    rep.pix[3] = 7.0 * q;
    full.add_replicate(rep);
    reps.push_back(rep);
  }
  const BsdfTally a = replicate_albedos(reps);
  EXPECT_EQ(a.replicates, full.replicates);
  EXPECT_EQ(a.paths, full.paths);
  EXPECT_EQ(a.albedo, full.albedo);
  EXPECT_EQ(a.albedo2, full.albedo2);
  EXPECT_TRUE(a.pix.empty());
  // Power: one replicate fewer changes the spread.
  reps.pop_back();
  EXPECT_NE(replicate_albedos(reps).albedo2, full.albedo2);
}

TEST(SmithWalkBudget, TallyWithoutCellsHasTheSameAlbedos) {
  // A tally without cells (no pixels, no in-plane bins) gets the same albedo slots from the same walks as a full one.
  const mm::SmithRandomWalk walk = beckmann_mirror_walk();
  const BsdfResult r = four_order_result(40.0);
  const WalkNet net = walk_net(3, 5, 0, 500);
  const WalkWindow window = walk_window(walk, r.wi, 4, 3, 5);
  BsdfTally full(4, r.map.size(), r.plane.size()), bare(4, 0, 0);
  for (std::uint64_t j = 0; j < 500; ++j) {
    smith_walk_expected_path(walk, r.wi, 3, 5, j, net, r, full, window);
    smith_walk_expected_path(walk, r.wi, 3, 5, j, net, r, bare, window);
  }
  EXPECT_EQ(bare.albedo, full.albedo);
  EXPECT_EQ(bare.albedo2, full.albedo2);
  EXPECT_EQ(bare.paths, full.paths);
  EXPECT_GT(full.albedo[full.a_index(0, 1)], 0.0);  // order 2 was reached
  double cells = 0.0;
  for (double x : full.pix) cells += x;
  EXPECT_GT(cells, 0.0);  // the full tally binned the same escapes
}

TEST(SmithWalkBudget, FirstMomentReplicatesGiveTheFullReplicatesResult) {
  // The model's replicates are tallies of first moments (BsdfTally::first_moments): the same walks give the
  // same first moments and counts as full tallies, and add_replicate of them the same result bit for bit.
  const mm::SmithRandomWalk walk = beckmann_mirror_walk();
  const BsdfResult r = four_order_result(30.0);
  const WalkWindow window = walk_window(walk, r.wi, 4, 3, 5);
  BsdfTally from_full(4, r.map.size(), r.plane.size()), from_first(4, r.map.size(), r.plane.size());
  for (int q = 0; q < 4; ++q) {
    const WalkNet net = walk_net(3, 5 + q, 0, 200);
    BsdfTally full(4, r.map.size(), r.plane.size());
    BsdfTally first = BsdfTally::first_moments(4, r.map.size(), r.plane.size());
    for (std::uint64_t j = 0; j < 200; ++j) {
      smith_walk_expected_path(walk, r.wi, 3, 5 + q, j, net, r, full, window);
      smith_walk_expected_path(walk, r.wi, 3, 5 + q, j, net, r, first, window);
    }
    EXPECT_FALSE(first.has_second_moments());
    EXPECT_TRUE(first.pix2.empty());
    EXPECT_EQ(first.pix, full.pix);
    EXPECT_EQ(first.plane, full.plane);
    EXPECT_EQ(first.albedo, full.albedo);
    from_full.add_replicate(full);
    from_first.add_replicate(first);
  }
  EXPECT_EQ(from_first.pix, from_full.pix);
  EXPECT_EQ(from_first.pix2, from_full.pix2);
  EXPECT_EQ(from_first.albedo2, from_full.albedo2);
  EXPECT_EQ(from_first.plane2, from_full.plane2);
  EXPECT_EQ(from_first.both2, from_full.both2);
  EXPECT_EQ(from_first.paths, from_full.paths);
  double spread = 0.0;
  for (double x : from_full.pix2) spread += x;
  EXPECT_GT(spread, 0.0);  // the replicates differ: the comparison of the spreads has power
  // Tallies of other moments do not add.
  BsdfTally a = BsdfTally::first_moments(4, 8, 2);
  EXPECT_THROW(a += BsdfTally(4, 8, 2), std::logic_error);
}

TEST(SmithWalkBudget, WalkWindowIsTheSerialMeanOfTheWeightAfterTheFirstEvent) {
  // walk_window runs its walks on TBB's threads and sums them in walk order: the serial sum, bit for bit.
  const mm::SmithRandomWalk walk = beckmann_mirror_walk();
  const Vec3 wi = direction_from_angles(rad(50.0), 0.0);
  struct Rng {
    CounterRng c;
    double uniform() { return c.uniform(); }
  };
  double continuing = 0.0;
  for (std::uint64_t j = 0; j < kWindowWalks; ++j) {
    Rng rng{CounterRng(3, 5 ^ 0x3D1A0C0000000000ull, j)};
    double first = 0.0;
    walk.walk_with_weight_window(wi, rng, 3, 0.0, std::numeric_limits<double>::infinity(), [&](const mm::WalkEscape& e) {
      if (e.order == 1) first += e.weight;
    });
    continuing += 1.0 - first;
  }
  const double w = continuing / static_cast<double>(kWindowWalks);
  const WalkWindow window = walk_window(walk, wi, 4, 3, 5);
  EXPECT_EQ(window.low, kWindowLow * w);
  EXPECT_EQ(window.high, kWindowHigh * w);
  EXPECT_GT(w, 0.01);  // the walks go on after the first event
}

namespace {
// Per-order albedo means and standard errors of R replicates of m walks driven by shifted Sobol points
// (smith_walk_expected_path, walk_net), as the measurement runs them; `bias` scales the means (power check).
OrderMeans net_order_means(const mm::SmithRandomWalk& walk, const BsdfResult& r, int R, std::uint64_t m,
                           std::uint64_t seed, double bias = 1.0) {
  const int K = r.options.orders;
  const WalkWindow window = walk_window(walk, r.wi, K, seed, 11);
  BsdfTally all(K, 0, 0);
  for (int q = 0; q < R; ++q) {
    const WalkNet net = walk_net(seed, 100 + q, 0, m);
    BsdfTally rep(K, 0, 0);
    for (std::uint64_t j = 0; j < m; ++j) smith_walk_expected_path(walk, r.wi, seed, 100 + q, j, net, r, rep, window);
    all.add_replicate(rep);
  }
  OrderMeans out;  // slots as order_means: side * K + k, k = 0 .. K - 1 (the total left out)
  for (int sd = 0; sd < 2; ++sd)
    for (int k = 0; k < K; ++k) {
      const auto i = all.a_index(sd, k);
      const auto e = all.estimate(all.albedo[i], all.albedo2[i]);
      out.mean.push_back(bias * e.mean);
      out.se.push_back(e.stderr_);
    }
  return out;
}
}  // namespace

TEST(SmithWalkBudget, SobolWalksHaveTheIndependentWalksMeans) {
  // The walks driven by shifted Sobol points tally the same per-order means as independent walks, within their
  // errors (the net changes the spread, not the expectation), at three incidences; a mean 3% off is rejected.
  const mm::SmithRandomWalk walk = beckmann_mirror_walk();
  for (double theta : {0.0, 45.0, 75.0}) {
    const BsdfResult r = four_order_result(theta);
    const OrderMeans plain = order_means(walk, r.wi, 4, 100000, false, 5 + static_cast<std::uint64_t>(theta), 1.0, true);
    const OrderMeans net = net_order_means(walk, r, 32, 512, 3);
    EXPECT_LT(largest_z(plain, net), kZ) << "theta " << theta;
    EXPECT_GT(largest_z(plain, net_order_means(walk, r, 32, 512, 3, 1.03)), kZ) << "theta " << theta;
  }
}

TEST(SmithWalkBudget, SobolReplicateErrorsAreCalibrated) {
  // The standard error from the spread of independently shifted replicates is the spread of the whole
  // estimate: over 24 seeds, the variance of the order-1 and order-2 means against the mean squared standard
  // error (ratio ~ 1, +-0.3 at one sigma for 24 seeds). Replicates that shared one shift would spread less
  // than the estimate does.
  const mm::SmithRandomWalk walk = beckmann_mirror_walk();
  const BsdfResult r = four_order_result(30.0);
  const int seeds = 24;
  for (int k = 0; k < 2; ++k) {
    double sum = 0.0, sum2 = 0.0, se2 = 0.0;
    for (int s = 0; s < seeds; ++s) {
      const OrderMeans m = net_order_means(walk, r, 16, 256, 1000 + static_cast<std::uint64_t>(s));
      sum += m.mean[k];
      sum2 += m.mean[k] * m.mean[k];
      se2 += m.se[k] * m.se[k];
    }
    const double mean = sum / seeds, var = (sum2 - seeds * mean * mean) / (seeds - 1);
    const double ratio = var / (se2 / seeds);
    EXPECT_GT(ratio, 0.35) << "order " << k + 1;
    EXPECT_LT(ratio, 2.2) << "order " << k + 1;
  }
}
