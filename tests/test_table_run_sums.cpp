// The turned runs of an azimuth-averaged renderer table kept as first-moment sums only
// (measure/table_run_sums.hpp, BsdfTableOptions::turned_runs): the table's entries (f per
// wavelength, the Mueller bins) are the same bit for bit as when every run keeps everything,
// and the runs hold only what the table reads.
#include <gtest/gtest.h>

#include <vector>

#include "microsim/io/pbsdf.hpp"
#include "microsim/measure/bsdf_table.hpp"
#include "microsim/measure/table_run_sums.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;
namespace mm = microsim::models;
using Turned = BsdfTableOptions::TurnedRuns;

namespace {

// Gold-like indices at three wavelengths (a spectral run) or the first alone.
BsdfTableOptions table_options(bool spectral, bool polarized, Turned turned) {
  BsdfTableOptions o;
  const std::vector<mm::Material> gold = {mm::Material::conductor(1.5, 1.9), mm::Material::conductor(0.42, 2.47),
                                          mm::Material::conductor(0.17, 3.6)};
  o.base.material = gold[0];
  if (spectral) {
    o.base.spectral = gold;
    o.base.wavelengths_nm = {450, 550, 650};
  }
  o.base.orders = 3;
  // 2 replicates of 2 x 9000 paths per azimuth: each replicate spans several work units (8192
  // paths a chunk), so a replicate's sum and the run's sum are different additions.
  o.base.rays = 2 * 2 * 9000;
  o.base.replicates = 2;
  o.base.resolution = 12;
  o.base.seed = 3;
  o.base.models = false;
  o.base.polarized = polarized;
  o.theta_i = {rad(20.0), rad(60.0)};
  o.phi_i = {0.0};
  o.table_azimuths = 2;
  o.turned_runs = turned;
  return o;
}

BsdfTable measure(const Microsurface& s, const BsdfTableOptions& o) { return measure_bsdf_table(Tracer(s), o); }

// Outgoing directions over the upper hemisphere, off the pixel centres.
std::vector<Vec3> directions() {
  std::vector<Vec3> out;
  const HemisphereMap map(7);
  for (int j = 0; j < 7; ++j)
    for (int i = 0; i < 7; ++i) out.push_back(map.from_square(-1 + (i + 0.3) * 2.0 / 7, -1 + (j + 0.6) * 2.0 / 7));
  return out;
}

void expect_same_table_f(const BsdfTable& full, const BsdfTable& kept, int wavelengths) {
  const int K = full.results[0].options.orders;
  for (int t = 0; t < static_cast<int>(full.theta_i.size()); ++t) {
    EXPECT_EQ(full.paths(0, t), kept.paths(0, t));
    // A spectral table is read per wavelength, a single index's through `measured` (-1).
    for (const Vec3& wo : directions())
      for (int l = wavelengths > 0 ? 0 : -1; l < std::max(wavelengths, 0); ++l)
        EXPECT_EQ(table_f(full, 0, t, 0, K, wo, l), table_f(kept, 0, t, 0, K, wo, l)) << "theta " << t << " l " << l;
  }
}

}  // namespace

TEST(TableRunSums, SingleIndexTableFIsTheSameBitForBit) {
  const Microsurface s = beckmann_tile(48, 2, 0.6);
  const BsdfTable full = measure(s, table_options(false, false, Turned::Everything));
  const BsdfTable kept = measure(s, table_options(false, false, Turned::TableF));
  expect_same_table_f(full, kept, 0);
  // The turned runs keep the reflected total's pixel sums alone: no second moments, no other
  // slot, no in-plane sums; another slot is refused, not read from the wrong sums.
  const BsdfTally& m = kept.turned[0][0].measured;
  EXPECT_TRUE(m.pix2.empty() && m.albedo2.empty() && m.plane.empty());
  EXPECT_EQ(m.pix.size(), static_cast<std::size_t>(m.pixels));
  EXPECT_FALSE(full.turned[0][0].measured.pix2.empty());
  EXPECT_THROW(f_pixel_mean(kept.turned[0][0], 0, 0, 5), std::logic_error);
  EXPECT_EQ(f_pixel_mean(kept.turned[0][0], 0, m.orders, 5), full.turned[0][0].f_pixel(0, m.orders, 5).mean);
}

TEST(TableRunSums, SpectralPolarizedTableFIsTheSameBitForBit) {
  const Microsurface s = beckmann_tile(48, 2, 0.6);
  const BsdfTable full = measure(s, table_options(true, true, Turned::Everything));
  const BsdfTable kept = measure(s, table_options(true, true, Turned::TableF));
  expect_same_table_f(full, kept, 3);
  // A .bsdf reads no Mueller sums of the turned runs: none walked; the nominal runs keep theirs.
  EXPECT_FALSE(kept.turned[1][0].polarization.has_value());
  ASSERT_TRUE(kept.results[1].polarization.has_value());
  EXPECT_EQ(kept.results[1].polarization->bins_stderr, full.results[1].polarization->bins_stderr);
  // `measured` of a spectral turned run: the counts alone (the wavelengths' tallies hold f).
  EXPECT_TRUE(kept.turned[1][0].measured.pix.empty());
  EXPECT_EQ(kept.turned[1][0].measured.paths, full.turned[1][0].measured.paths);
}

TEST(TableRunSums, MuellerBinsAreTheSameBitForBit) {
  const Microsurface s = beckmann_tile(48, 2, 0.6);
  const BsdfTable full = measure(s, table_options(true, true, Turned::Everything));
  const BsdfTable kept = measure(s, table_options(true, true, Turned::TableMueller));
  for (std::size_t t = 0; t < full.theta_i.size(); ++t) {
    const PolarizationTally& a = *full.turned[t][0].polarization;
    const PolarizationTally& b = *kept.turned[t][0].polarization;
    EXPECT_EQ(a.paths, b.paths);
    EXPECT_EQ(a.bins_total, b.bins_total);
    // Only the bins' sums were kept, and the per-replicate sums never allocated.
    EXPECT_TRUE(b.replicate.empty() && b.map_total.empty() && b.plane_total.empty() && b.bins_stderr.empty());
    EXPECT_TRUE(kept.turned[t][0].spectral[0].pix.empty());
  }
  for (double theta : {15.0, 40.0, 70.0})
    for (const Vec3& view : directions()) {
      const Vec3 light = direction_from_angles(rad(theta), rad(30.0));
      for (int l = 0; l < 3; ++l) {
        const mm::Mueller a = measured_mueller(full, light, view, l), b = measured_mueller(kept, light, view, l);
        for (int i = 0; i < 16; ++i) EXPECT_EQ(a(i / 4, i % 4), b(i / 4, i % 4)) << "element " << i;
      }
    }
}

TEST(TableRunSums, FirstMomentsAreAddReplicatesSums) {
  // Replicates with zero and nonzero cells: the sums agree with add_replicate's bit for bit, the
  // counts too, and the second moments stay untouched.
  BsdfTally a(2, 3, 2), b(2, 3, 2);
  for (int q = 0; q < 3; ++q) {
    BsdfTally rep(2, 3, 2);
    rep.paths = 10;
    rep.add_exit(0, 1 + q % 2, 0.1 * (q + 1) + 1e-17, q == 1 ? -1 : q, q);
    rep.add_exit(0, 2, 1.0 / 3.0, 2, -1);
    a.add_replicate(rep);
    add_replicate_first_moments(b, rep);
  }
  EXPECT_EQ(a.albedo, b.albedo);
  EXPECT_EQ(a.pix, b.pix);
  EXPECT_EQ(a.plane, b.plane);
  EXPECT_EQ(a.paths, b.paths);
  EXPECT_EQ(a.replicates, b.replicates);
  EXPECT_EQ(b.pix2, std::vector<double>(b.pix2.size(), 0.0));
}

TEST(TableRunSums, BinsOnlyUnitsAddTheirChunks) {
  // A work unit of several chunks adds its chunks' Mueller sums: a bins_only unit (no albedo,
  // map or in-plane sums) too, and its paths.
  PolarizedSumsSetup su;
  su.wi = direction_from_angles(rad(30.0), 0.0);
  su.replicates = 2;
  su.orders = 2;
  su.material = mm::Material::conductor(0.42, 2.47);
  su.resolution = 4;
  su.bins_only = true;
  const PolarizedSums sums(su);
  MuellerUnit a = sums.make_unit(), b = sums.make_unit();
  ASSERT_TRUE(a.sums.empty());
  ASSERT_EQ(a.bins.size(), 4u * 4 * 16);
  a.bins[3] = 0.25, a.paths = 7;
  b.bins[3] = 0.5, b.bins[17] = 1.0, b.paths = 5;
  a += b;
  EXPECT_EQ(a.bins[3], 0.75);
  EXPECT_EQ(a.bins[17], 1.0);
  EXPECT_EQ(a.paths, 12u);
  MuellerUnit identity;
  identity += a;
  EXPECT_EQ(identity.bins, a.bins);
  EXPECT_EQ(identity.paths, 12u);
}
