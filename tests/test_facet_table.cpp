// The facet table (normals, areas and bins derived from a heightfield's heights on demand) and
// the block sampler of facets by weight: both must reproduce the direct per-facet route.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "microsim/measure/facet_table.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/sampling.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;

namespace {
// Facet weights A_f max(0, v.m_f) of the view v (the area-sampling density of G1).
auto view_weight(const FacetTable& t, const Vec3& v) {
  return [&t, v](std::size_t k) {
    Vec3 m;
    double a;
    t.normal_area(k, m, a);
    return std::max(0.0, a * m.dot(v));
  };
}

// Every facet of the table equals Microsurface::facet's triangle (normal, area).
void expect_table_matches_triangles(const Microsurface& s, const FacetTable& t, const char* label) {
  ASSERT_EQ(t.size(), s.num_facets());
  for (std::size_t k = 0; k < s.num_facets(); ++k) {
    const Triangle f = s.facet(k);
    Vec3 m;
    double a;
    t.normal_area(k, m, a);
    ASSERT_NEAR((m - f.normal()).norm(), 0.0, 1e-12) << k << " " << label;
    ASSERT_NEAR(a, f.area(), 1e-12 * f.area()) << k << " " << label;
  }
}
}  // namespace

TEST(FacetTable, HeightfieldFacetsFromHeightsMatchTheTriangles) {
  const Microsurface s = beckmann_tile(64, 3);
  const DirectionBinning bins(18, 8, kPi);
  const FacetTable t = build_facet_table(s, bins);
  ASSERT_EQ(t.size(), s.num_facets());
  for (std::size_t k = 0; k < s.num_facets(); ++k) {
    const Triangle f = s.facet(k);
    Vec3 m;
    double a;
    t.normal_area(k, m, a);
    ASSERT_NEAR((m - f.normal()).norm(), 0.0, 1e-12) << k;
    ASSERT_NEAR(a, f.area(), 1e-12 * f.area()) << k;
    ASSERT_EQ(t.bin(k), bins.bin_of(f.normal())) << k;
  }
  // Only the bin index is stored per facet.
  EXPECT_EQ(t.bytes_per_facet(), 2.0);
}

TEST(FacetTable, SampleRegionFacetsMatchTheTriangles) {
  // A measured window's region (its facets numbered first) and a periodic tile restricted to
  // the same cells: the derived normals and areas follow Microsurface::facet's numbering.
  for (bool periodic : {true, false}) {
    Microsurface s = beckmann_tile(32, 4);
    s.set_sample_region(5, 21, 3, 30, periodic);
    const DirectionBinning bins(18, 8, kPi);
    const FacetTable t = build_facet_table(s, bins);
    ASSERT_EQ(t.size(), 2u * 16 * 27);
    expect_table_matches_triangles(s, t, periodic ? "periodic" : "window");
  }
}

TEST(FacetTable, HeightfieldTableKeepsTheExactFacetIdentities) {
  // [GeomBSDF24, eq. 1b/1c] from the derived normals and areas: sum A_f m_f = n A, sum A_f (n.m_f) = A,
  // to rounding (a wrong cross product, e.g. dx and dy swapped on a non-square tile, is far off).
  const Microsurface s = vgroove_heightfield(8, 16, 0.6, 8);
  const FacetTable t = build_facet_table(s, DirectionBinning(18, 8, kPi));
  Vec3 sum = Vec3::Zero();
  for (std::size_t k = 0; k < t.size(); ++k) {
    Vec3 m;
    double a;
    t.normal_area(k, m, a);
    sum += a * m;
  }
  const double A = s.macro().area;
  EXPECT_NEAR(sum.x() / A, 0.0, 1e-12);
  EXPECT_NEAR(sum.y() / A, 0.0, 1e-12);
  EXPECT_NEAR(sum.z() / A, 1.0, 1e-12);
}

TEST(BlockFacetSampler, DrawsTheSameFacetsAsTheFullCdf) {
  // Against a plain per-facet CDF: the same facet for every u except where u falls within
  // rounding of a slice boundary; never a facet of zero weight.
  const Microsurface s = beckmann_tile(64, 5);
  const FacetTable t = build_facet_table(s, DirectionBinning(18, 8, kPi));
  const auto weight = view_weight(t, direction_from_angles(rad(75), rad(20)));
  const BlockFacetSampler sampler(t.size(), weight);
  std::vector<double> cdf(t.size());
  double acc = 0;
  for (std::size_t k = 0; k < t.size(); ++k) cdf[k] = acc += weight(k);
  EXPECT_NEAR(sampler.total(), acc, 1e-12 * acc);
  std::size_t zero = 0, mismatches = 0;
  const std::size_t n = 200000;
  for (std::size_t j = 0; j < n; ++j) {
    CounterRng rng(9, 1, j);
    const double u = rng.uniform() * sampler.total();
    const std::size_t k = sampler.draw(u, weight);
    std::size_t ref = std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin();
    ref = std::min(ref, cdf.size() - 1);
    while (ref > 0 && cdf[ref] == cdf[ref - 1]) --ref;
    zero += weight(k) <= 0;
    mismatches += k != ref;
  }
  EXPECT_EQ(zero, 0u);
  EXPECT_LE(mismatches, n / 10000);
  // Power: a sampler built on other weights (another view) draws other facets.
  const auto weight2 = view_weight(t, direction_from_angles(rad(60), rad(20)));
  const BlockFacetSampler other(t.size(), weight2);
  std::size_t differ = 0;
  for (std::size_t j = 0; j < 1000; ++j) {
    CounterRng rng(9, 1, j);
    const double u = rng.uniform();
    differ += other.draw(u * other.total(), weight2) != sampler.draw(u * sampler.total(), weight);
  }
  EXPECT_GT(differ, 100u);
}

TEST(BlockFacetSampler, G1IsIdenticalForAnyThreadCount) {
  const Microsurface s = beckmann_tile(128, 7);
  const Tracer tracer(s);
  G1Options o;
  o.rays = 40000;
  const Vec3 v = direction_from_angles(rad(70), rad(10));
  auto run = [&](int threads) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
    return measure_g1(tracer, v, o);
  };
  const G1Result a = run(1), b = run(2);
  EXPECT_EQ(a.sample_visible_r, b.sample_visible_r);
  EXPECT_EQ(a.raycast_hits_r, b.raycast_hits_r);
  EXPECT_EQ(a.front_projected, b.front_projected);
  EXPECT_EQ(a.lambda_numeric, b.lambda_numeric);
}

TEST(BlockFacetSampler, SearchFromThePreviousDrawAndBlockWeightsAreExact) {
  // The block-wise cross products equal cross(k) bit for bit (also across rows and in a
  // sample region), and draws that search forward from the previous draw's block return the
  // very facets of the full search, for increasing u (a stratified pass) and for u jumping back.
  Microsurface s = beckmann_tile(48, 6);
  for (int region = 0; region < 2; ++region) {
    if (region) s.set_sample_region(3, 40, 5, 33, true);
    const FacetTable t = build_facet_table(s, DirectionBinning(18, 8, kPi));
    std::size_t unequal = 0;
    t.for_each_cross(5, t.size(), [&](std::size_t k, const Vec3& c) { unequal += c != t.cross(k); });
    EXPECT_EQ(unequal, 0u) << region;
  }
  const FacetTable t = build_facet_table(s, DirectionBinning(18, 8, kPi));
  const Vec3 v = direction_from_angles(rad(70), rad(30));
  const auto weight = [&](std::size_t k) { return std::max(0.0, 0.5 * t.cross(k).dot(v)); };
  const auto blocks = [&](std::size_t k0, std::size_t k1, double* w) {
    t.for_each_cross(k0, k1, [&](std::size_t k, const Vec3& c) { w[k - k0] = std::max(0.0, 0.5 * c.dot(v)); });
  };
  const BlockFacetSampler sampler(t.size(), weight);
  const BlockFacetSampler by_blocks(t.size(), BlockFacetSampler::Blocks{}, blocks);
  EXPECT_EQ(sampler.total(), by_blocks.total());
  std::size_t hint = 0, differ = 0, moved = 0;
  const std::size_t n = 20000;
  for (std::size_t j = 0; j < n; ++j) {
    CounterRng rng(4, 2, j);
    // increasing strata, with every 500th draw jumping back to the start of the table
    const double u = (j % 500 == 499 ? rng.uniform() * 0.01 : (j + rng.uniform()) / n) * sampler.total();
    const std::size_t k = by_blocks.draw(u, BlockFacetSampler::Blocks{}, blocks, &hint);
    differ += k != sampler.draw(u, weight);
    // power: a draw at a slightly larger u moves to another facet now and then
    moved += k != sampler.draw(std::min(u + 5.0 * sampler.total() / n, 0.999 * sampler.total()), weight);
  }
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(moved, n / 4);
}
