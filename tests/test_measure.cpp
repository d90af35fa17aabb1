// Estimators: exact geometric cases (flat plane, V-groove), agreement of the two G1 estimators,
// Smith with the surface's own facets, D against Beckmann, thread-count invariance, and honest
// standard errors.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "microsim/measure/stats.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/ndf_measure.hpp"
#include "microsim/models/ndf.hpp"
#include "microsim/measure/facet_table.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/trace/facet_plane.hpp"
#include "microsim/trace/ray_pipeline.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;

namespace {
using microsim::sidak_z;  // microsim/measure/stats.hpp

G1Options opts(std::uint64_t rays, std::uint64_t seed = 1) {
  G1Options o;
  o.rays = rays;
  o.seed = seed;
  return o;
}

// [Heitz14, eq. 24]: V-cavity masking of facet m seen from v, both in the cross-section plane.
double vgroove_g1(double theta_o, double theta_m_signed) {
  if (std::cos(theta_o - theta_m_signed) <= 0) return 0.0;
  return std::min(1.0, 2 * std::cos(theta_m_signed) * std::cos(theta_o) /
                           std::cos(theta_o - theta_m_signed));
}
}  // namespace

TEST(SidakHelper, KnownValues) {
  EXPECT_NEAR(sidak_z(0.05, 1), 1.95996, 1e-4);
  EXPECT_GT(sidak_z(0.01, 100), 3.4);
}

TEST(NdfMeasure, FlatPlaneIsADeltaAtTheNormal) {
  Microsurface s = flat_heightfield(32);
  NdfResult r = measure_ndf(s, NdfOptions{});
  EXPECT_NEAR(r.ring_d[0], 1.0 / r.bins.solid_angle_of_ring(0), 1e-9);
  for (std::size_t k = 1; k < r.ring_d.size(); ++k) EXPECT_EQ(r.ring_d[k], 0.0);
  EXPECT_NEAR(r.ring_d_stderr[0], 0.0, 1e-9);
}

TEST(NdfMeasure, BeckmannTileMatchesNominalDWithinBlockErrors) {
  GaussianParams p;
  p.resolution = 256;
  p.correlation_length = 4.0 / 256;  // 4 cells per l
  p.alpha_x = p.alpha_y = 0.5;
  p.seed = 3;
  Microsurface s = generate_gaussian(p);
  NdfResult r = measure_ndf(s, NdfOptions{});
  // z of each theta ring against a model's ring average. Rings holding under 1% of the area
  // have too few independent regions for a block standard error (most blocks hold none).
  auto ring_z = [&](const models::Ndf& ndf) {
    std::vector<double> zs;
    for (int it = 0; it < r.bins.n_theta(); ++it) {
      double model = 0;
      for (int ip = 0; ip < r.bins.n_phi(); ++ip)
        model += r.bins.bin_average(r.bins.index(it, ip), [&](const Vec3& m) { return ndf.D(m); });
      model /= r.bins.n_phi();
      if (model * r.bins.solid_angle_of_ring(it) < 0.01) continue;
      zs.push_back((r.ring_d[it] - model) / r.ring_d_stderr[it]);
    }
    return zs;
  };
  std::vector<double> zs = ring_z(*s.nominal);
  ASSERT_GT(zs.size(), 20u);
  double zmax = sidak_z(0.01, static_cast<int>(zs.size()));
  for (double z : zs) EXPECT_LT(std::abs(z), zmax);
  // The same data against a 10% wrong roughness must fail (the test has power).
  int rejected = 0;
  for (double z : ring_z(models::Ndf::beckmann(0.55, 0.55))) rejected += std::abs(z) > zmax;
  EXPECT_GT(rejected, 0);
}

TEST(G1Measure, FlatPlaneIsNeverMasked) {
  Microsurface s = flat_heightfield(16);
  Tracer tracer(s);
  for (double theta : {0.0, 45.0, 85.0, 89.0}) {
    G1Result r = measure_g1(tracer, direction_from_angles(rad(theta), 0.3), opts(20000));
    EXPECT_EQ(r.sample_visible, r.sample_rays) << theta;
    // Facet areas are tabulated in float: 1e-6 relative.
    EXPECT_NEAR(r.g1_raycast().mean, 1.0, 1e-6) << theta;
    EXPECT_NEAR(r.visible_area_ratio().mean, 1.0, 1e-12) << theta;
    EXPECT_NEAR(r.lambda_numeric, 0.0, 1e-12);
    EXPECT_EQ(r.counters.lost_below + r.counters.unresolved + r.counters.backface_hits, 0u);
  }
}

TEST(G1Measure, VGroovePerFacetG1IsExact) {
  // [Heitz14, eq. 24] is exact for a V-groove viewed in its cross-section plane; both estimators
  // must reproduce it per facet within 3 standard errors, with standard errors <= 1e-3.
  const double tm = rad(35);
  Microsurface s = vgroove_heightfield(16, 8, tm);
  Tracer tracer(s);
  for (double theta_deg : {30.0, 70.0, 80.0}) {
    const double to = rad(theta_deg);
    G1Result r = measure_g1(tracer, direction_from_angles(to, 0.0), opts(2500000, 5));
    for (int b = 0; b < r.binning.size(); ++b) {
      if (r.bins[b].front_projected <= 0) continue;
      // Signed facet angle in the cross-section: +tm for normal toward +x (facing v).
      double signed_tm = r.bins[b].mean_normal.x() > 0 ? tm : -tm;
      double exact = vgroove_g1(to, signed_tm);
      Estimate a = r.bin_g1_raycast(b), e = r.bin_g1_area_sampling(b);
      EXPECT_LE(e.stderr_, 1e-3);
      EXPECT_LE(a.stderr_, 1e-3);
      EXPECT_LT(std::abs(e.mean - exact), 3 * std::max(e.stderr_, 1e-6))
          << "area sampling, theta " << theta_deg << " facet " << signed_tm;
      EXPECT_LT(std::abs(a.mean - exact), 3 * std::max(a.stderr_, 1e-6))
          << "ray casting, theta " << theta_deg << " facet " << signed_tm;
    }
    EXPECT_NEAR(r.visible_area_ratio().mean, 1.0, 1e-12);
  }
}

TEST(G1Measure, BeckmannTileEstimatorsAgreeAndMatchSmithFromFacets) {
  GaussianParams p;
  p.resolution = 256;
  p.correlation_length = 4.0 / 256;  // 4 cells per l
  p.alpha_x = p.alpha_y = 0.5;
  p.seed = 9;
  Microsurface s = generate_gaussian(p);
  Tracer tracer(s);
  const std::vector<double> thetas = {0, 30, 60, 70, 80, 85};
  int comparisons = 0;
  std::vector<double> zbins, zsmith;
  for (double t : thetas) {
    G1Result r = measure_g1(tracer, direction_from_angles(rad(t), 0.0), opts(200000, 2));
    for (int b = 0; b < r.binning.size(); ++b) {
      if (r.bins[b].samples < 100 || r.bins[b].front_projected <= 0) continue;
      Estimate a = r.bin_g1_raycast(b), e = r.bin_g1_area_sampling(b);
      double se = std::hypot(a.stderr_, e.stderr_);
      if (se == 0) {
        EXPECT_DOUBLE_EQ(a.mean, e.mean);
        continue;
      }
      zbins.push_back((a.mean - e.mean) / se);
      ++comparisons;
    }
    // Averaged G1 by area sampling vs 1/(1 + Lambda from the facets) (not an identity: it
    // checks occlusion rays against the exact facet sums).
    Estimate g = r.g1_area_sampling();
    double smith_numeric = 1 / (1 + r.lambda_numeric);
    if (g.stderr_ > 0) zsmith.push_back((g.mean - smith_numeric) / g.stderr_);
    else EXPECT_NEAR(g.mean, smith_numeric, 1e-12);
    EXPECT_EQ(r.counters.lost_below + r.counters.unresolved, 0u);
  }
  double zb = sidak_z(0.01, comparisons);
  for (double z : zbins) EXPECT_LT(std::abs(z), zb);
  double zs = sidak_z(0.01, static_cast<int>(thetas.size()));
  for (double z : zsmith) EXPECT_LT(std::abs(z), zs);
}

TEST(G1Measure, PerNormalG1ShowsFacetsTiltedTowardTheViewerAreLessMasked) {
  // Smith says G1(v, m) does not depend on m; on a real surface it does (docs/theory/masking.md). Facets
  // tilted away from v (toward -x when v is at +x) are masked more.
  GaussianParams p;
  p.resolution = 256;
  p.correlation_length = 4.0 / 256;  // 4 cells per l
  p.seed = 4;
  Microsurface s = generate_gaussian(p);
  Tracer tracer(s);
  G1Result r = measure_g1(tracer, direction_from_angles(rad(80), 0.0), opts(200000));
  // Same theta ring (20-30 deg), phi sectors facing +x (0-45) and facing -x (180-225).
  int toward = r.binning.index(2, 0), away = r.binning.index(2, 4);
  Estimate gt = r.bin_g1_area_sampling(toward), ga = r.bin_g1_area_sampling(away);
  EXPECT_GT(gt.mean - ga.mean, 5 * std::hypot(gt.stderr_, ga.stderr_));
}

TEST(G1Measure, ResultsDoNotDependOnThreadCount) {
  GaussianParams p;
  p.resolution = 128;
  p.correlation_length = 4.0 / 128;  // 4 cells per l
  Microsurface s = generate_gaussian(p);
  Tracer tracer(s);
  auto run = [&](int threads) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
    return measure_g1(tracer, direction_from_angles(rad(75), 1.0), opts(100000, 3));
  };
  G1Result a = run(1), b = run(2);
  EXPECT_EQ(a.raycast_hits, b.raycast_hits);
  EXPECT_EQ(a.sample_visible, b.sample_visible);
  EXPECT_EQ(a.lambda_numeric, b.lambda_numeric);
  for (int k = 0; k < a.binning.size(); ++k) {
    EXPECT_EQ(a.bins[k].raycast_hits, b.bins[k].raycast_hits);
    EXPECT_EQ(a.bins[k].visible, b.bins[k].visible);
    EXPECT_EQ(a.bins[k].front_projected, b.bins[k].front_projected);
    EXPECT_EQ(a.bins[k].raycast_hits_r, b.bins[k].raycast_hits_r);  // every replicate
    EXPECT_EQ(a.bins[k].visible_r, b.bins[k].visible_r);
  }
}

TEST(G1Measure, SmallTileRaysTracedInBlocksCountTheSameHitsAsFirstHit) {
  // Below kAheadMinCells cells, estimator (a) traces ray j of every replicate as one block
  // (Tracer::front_facets: origins, queries, hits in turn). Its hits per normal bin and
  // replicate must equal, for 1 and 2 threads, those of a plain loop of first_hit over the same
  // rays (same streams, strata and window; a hit counts when its front face is met first), on
  // a rough periodic tile from the zenith to grazing views. Power: the plain loop with each hit
  // named by the other half of its cell (a decoding off by a diagonal) counts differently.
  const Microsurface s = beckmann_tile(48, 61, 1.0);
  const Tracer tracer(s);
  const G1Options o = opts(48000, 7);
  const FacetTable table = build_facet_table(s, g1_normal_binning(o));
  const std::size_t nf = s.num_facets();
  for (double theta : {0.0, 60.0, 85.0, 89.0}) {
    const Vec3 v = direction_from_angles(rad(theta), 0.4);
    auto measure = [&](int threads) {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
      return measure_g1(tracer, v, o, &table);
    };
    // Hits per normal bin and replicate; `flip`: each hit facet replaced by its cell's other half.
    auto plain = [&](bool flip) {
      const RayWindow w = make_ray_window(tracer, v);
      const ReplicatePlan plan(o.rays, o.replicates);
      const std::uint64_t key = direction_stream_key(v);
      std::vector<std::vector<std::uint64_t>> hits(g1_normal_binning(o).size(),
                                                   std::vector<std::uint64_t>(plan.replicates));
      TraceCounters c;
      for (int q = 0; q < plan.replicates; ++q)
        for (std::uint64_t j = 0; j < plan.per_replicate(); ++j) {
          CounterRng rng(o.seed, ReplicatePlan::stream(0xA000 + key, q), j);
          const Vec2 ab = plan.strata.point(j, rng);
          const TraceHit h = tracer.first_hit(w.origin0 + ab.x() * w.e1 + ab.y() * w.e2, -v, nullptr, c);
          if (!h.hit || h.backface || h.facet >= nf) continue;
          const int b = table.bin(flip ? h.facet ^ 1 : h.facet);
          if (b >= 0) ++hits[b][q];
        }
      return hits;
    };
    const G1Result a = measure(1), b = measure(2);
    const auto expected = plain(false), flipped = plain(true);
    ASSERT_EQ(static_cast<std::size_t>(a.binning.size()), expected.size());
    int differ = 0;
    for (int k = 0; k < a.binning.size(); ++k) {
      EXPECT_EQ(a.bins[k].raycast_hits_r, expected[k]) << "theta " << theta << " bin " << k;
      EXPECT_EQ(b.bins[k].raycast_hits_r, expected[k]) << "theta " << theta << " bin " << k;
      differ += flipped[k] != expected[k];
    }
    EXPECT_GT(differ, 5) << "theta " << theta;  // power: a decoding off by a half is seen
  }
}

namespace {
// A tile large enough for the estimators' look-ahead paths (from kAheadMinCells cells on), its
// tracer and facet table, a view and options: measure_g1 with a given number of threads, to
// compare with a plain loop over the same rays.
struct AheadCase {
  const Microsurface s;
  const Tracer tracer;
  const Vec3 v;
  const G1Options o;
  const FacetTable table;
  AheadCase(const Vec3& view, const G1Options& options)
      : s(generate_gaussian([] {
          GaussianParams p;
          p.resolution = 1536;
          p.correlation_length = 4.0 / 1536;
          return p;
        }())),
        tracer(s), v(view), o(options), table(build_facet_table(s, g1_normal_binning(o))) {}
  G1Result measure(int threads) const {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
    return measure_g1(tracer, v, o, &table);
  }
};
}  // namespace

TEST(G1Measure, LargeTileRaysTracedAheadCountTheSameHitsAsAPlainLoop) {
  // From kAheadMinCells cells on, estimator (a) sets its rays up ahead of tracing them
  // (trace/ray_pipeline.hpp): its hits must equal, ray for ray in total and for 1 and 2
  // threads, those of a plain loop of front_facet over the same rays (same streams, strata and
  // window). Power: the plain loop with another seed counts differently.
  const AheadCase t(direction_from_angles(rad(60), 0.5), opts(64000, 9));
  ASSERT_GE(double(t.s.nx()) * t.s.ny(), kAheadMinCells);
  // Hits per normal bin and replicate.
  auto plain = [&](std::uint64_t seed) {
    const RayWindow w = make_ray_window(t.tracer, t.v);
    const ReplicatePlan plan(t.o.rays, t.o.replicates);
    const DownwardRays down(t.tracer, t.v);
    const std::uint64_t key = direction_stream_key(t.v);
    std::vector<std::vector<std::uint64_t>> hits(g1_normal_binning(t.o).size(),
                                                 std::vector<std::uint64_t>(plan.replicates));
    TraceCounters c;
    for (int q = 0; q < plan.replicates; ++q)
      for (std::uint64_t j = 0; j < plan.per_replicate(); ++j) {
        CounterRng rng(seed, ReplicatePlan::stream(0xA000 + key, q), j);
        const Vec2 ab = plan.strata.point(j, rng);
        const std::size_t k = t.tracer.front_facet(down, w.origin0 + ab.x() * w.e1 + ab.y() * w.e2, c);
        if (k < t.s.num_facets()) ++hits[t.table.bin(k)][q];
      }
    return hits;
  };
  const G1Result a = t.measure(1), b = t.measure(2);
  const auto expected = plain(t.o.seed), other_seed = plain(t.o.seed + 1);
  ASSERT_EQ(static_cast<std::size_t>(a.binning.size()), expected.size());
  int differ = 0;
  for (int k = 0; k < a.binning.size(); ++k) {
    EXPECT_EQ(a.bins[k].raycast_hits_r, expected[k]) << "bin " << k;
    EXPECT_EQ(b.bins[k].raycast_hits_r, expected[k]) << "bin " << k;
    differ += other_seed[k] != expected[k];
  }
  EXPECT_GT(differ, a.binning.size() / 4);  // power: another seed's counts differ
}

TEST(G1Measure, LargeTileAreaSamplesDrawnAheadCountTheSameAsAPlainLoop) {
  // From kAheadMinCells cells on, estimator (b) sets its draws up ahead of tracing them, with
  // the drawn block's data prefetched: its samples and visible counts per bin and replicate
  // must equal, for 1 and 2 threads, those of a plain loop of the same draws (same streams,
  // cumulative weights, sample points and occlusion rays). Power: another seed differs.
  const AheadCase t(direction_from_angles(rad(80), 2.0), opts(64000, 5));
  ASSERT_GE(double(t.s.nx()) * t.s.ny(), kAheadMinCells);
  const std::size_t nf = t.s.num_facets();
  const auto weights = [&](std::size_t k0, std::size_t k1, double* w) {
    t.table.for_each_cross(k0, k1, [&](std::size_t k, const Vec3& c) { w[k - k0] = std::max(0.0, 0.5 * c.dot(t.v)); });
  };
  const BlockFacetSampler sampler(nf, BlockFacetSampler::Blocks{}, weights);
  struct Counts {
    std::vector<std::vector<std::uint64_t>> samples, visible;  // [bin][replicate]
  };
  auto plain = [&](std::uint64_t seed) {
    const ReplicatePlan plan(t.o.rays, t.o.replicates);
    const std::uint64_t key = direction_stream_key(t.v), n = plan.per_replicate();
    const std::size_t nb = g1_normal_binning(t.o).size();
    Counts c{std::vector<std::vector<std::uint64_t>>(nb, std::vector<std::uint64_t>(plan.replicates)),
             std::vector<std::vector<std::uint64_t>>(nb, std::vector<std::uint64_t>(plan.replicates))};
    TraceCounters tc;
    for (int q = 0; q < plan.replicates; ++q)
      for (std::uint64_t j = 0; j < n; ++j) {
        CounterRng rng(seed, ReplicatePlan::stream(0xB000 + key, q), j);
        const double u = (static_cast<double>(j) + rng.uniform()) / n * sampler.total();
        // no search hint: the same facet
        const std::size_t k = sampler.draw(u, BlockFacetSampler::Blocks{}, weights);
        const Triangle f = facet_triangle(t.s, k);
        const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
        const SourcePlane plane = SourcePlane::of(f);
        ++c.samples[t.table.bin(k)][q];
        if (!t.tracer.occluded(f.point(r1 * (1 - r2), r1 * r2), t.v, &plane, tc)) ++c.visible[t.table.bin(k)][q];
      }
    return c;
  };
  const G1Result a = t.measure(1), b = t.measure(2);
  const Counts expected = plain(t.o.seed), other_seed = plain(t.o.seed + 1);
  ASSERT_EQ(static_cast<std::size_t>(a.binning.size()), expected.samples.size());
  int differ = 0;
  std::uint64_t occluded = 0;
  for (int k = 0; k < a.binning.size(); ++k) {
    EXPECT_EQ(a.bins[k].samples_r, expected.samples[k]) << "bin " << k;
    EXPECT_EQ(a.bins[k].visible_r, expected.visible[k]) << "bin " << k;
    EXPECT_EQ(b.bins[k].samples_r, expected.samples[k]) << "bin " << k;
    EXPECT_EQ(b.bins[k].visible_r, expected.visible[k]) << "bin " << k;
    differ += other_seed.visible[k] != expected.visible[k];
    occluded += a.bins[k].samples - a.bins[k].visible;
  }
  EXPECT_GT(occluded, 1000u);  // at 80 degrees the occlusion rays do meet the surface
  EXPECT_GT(differ, a.binning.size() / 4);  // power: another seed's counts differ
}

// The reported standard errors are checked two-sided against the seed-to-seed spread in
// test_calibration.cpp (one test per estimator).

TEST(G1Measure, RejectsDirectionsBelowTheHorizonAndZeroRays) {
  Microsurface s = flat_heightfield(8);
  Tracer tracer(s);
  EXPECT_THROW(measure_g1(tracer, Vec3(1, 0, 0), opts(10)), UsageError);
  EXPECT_THROW(measure_g1(tracer, Vec3(0, 0, 1), opts(0)), UsageError);
}
