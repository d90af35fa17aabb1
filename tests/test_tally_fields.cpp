// Every tally field survives a split run: for every estimator (G1 with both of its estimators,
// G2, VNDF, BSDF; the BSDF also spectral, and spectral and polarized) on every kind of scene (a
// periodic tile, a non-periodic heightmap window, a finite object, a V-cavity; spectral and
// polarized runs refuse V-cavities), the record of `--shard 1/2` + `--shard 2/2` + `merge`, and of
// `mpirun -n 2` when built with MPI, equals the single run's bit for bit apart from timings, and
// every record carries every trace counter. The counters' names are listed here on their own,
// not taken from the declaration (TraceCounters::for_each_field), so that a field dropped from
// the declaration fails here. Spectral and polarized records are compared whole (every
// wavelength's albedo, every Mueller matrix, degree of polarization and per-bin f; a spectral
// run on the tile also its .bsdf table, made from every wavelength's hemisphere maps), after a
// check that those fields hold data: a sum dropped from its declaration (SpectralTally,
// MuellerUnit) arrives as zeros after the split and fails the comparison.
#include <gtest/gtest.h>

#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_helpers.hpp"
#include "record_helpers.hpp"
#include "microsim/measure/polarized_walk.hpp"
#include "microsim/measure/shards.hpp"
#include "microsim/measure/spectral_tally.hpp"
#include "microsim/tally_fields.hpp"
#include "microsim/trace/tracer.hpp"

namespace {
using namespace microsim::testing;
using nlohmann::json;

std::string tmp(const std::string& name) { return temp_path("tally", name); }

// The trace counters every record carries (TraceCounters).
const std::set<std::string> kCounters = {"rays",       "border_crossings", "lost_below",  "backface_hits",
                                         "unresolved", "side_exits",       "side_entries"};

// The differences between two records as a JSON patch (paths and values), for failure messages.
std::string differences(const json& from, const json& to) {
  const std::string d = json::diff(from, to).dump();
  return d.size() > 2000 ? d.substr(0, 2000) + "..." : d;
}

// Every `trace_counters` object in the record (rows of G1, G2, VNDF; the BSDF record itself).
void collect_counters(const json& j, std::vector<json>& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (it.key() == "trace_counters") out.push_back(it.value());
      else collect_counters(it.value(), out);
    }
  } else if (j.is_array()) {
    for (const auto& e : j) collect_counters(e, out);
  }
}

struct Case {
  const char* estimator;
  const char* scene;
};
std::ostream& operator<<(std::ostream& os, const Case& c) { return os << c.estimator << "_" << c.scene; }

// Grazing directions, so that windows meet their side walls and tiles wrap around.
std::string command(const std::string& estimator, const std::string& surface) {
  if (estimator == "g1") return "measure g1 " + surface + " --theta 40,89 --rays 4000 --seed 3";
  if (estimator == "g2")
    return "measure g2 " + surface + " --theta-o 30,85 --theta-i 80 --phi-i 180 --rays 4000 --seed 3";
  if (estimator == "vndf") return "measure vndf " + surface + " --theta 30,88 --rays 20001 --sampler-samples 0";
  const std::string bsdf = "measure bsdf " + surface + " --theta-i 80 --rays 4000 --resolution 8 --seed 3";
  if (estimator == "bsdf_spectral") return bsdf + " --material conductor --metal Au --wavelengths 450,550,650";
  if (estimator == "bsdf_polarized")
    return bsdf + " --material conductor --metal Au --wavelengths 450,550,650 --polarized";
  return bsdf + " --material conductor --eta 0.2 --k 3";
}

// What a case writes: a spectral run on the tile writes the renderer table (.bsdf, from the f of
// every wavelength, of which the record holds the first wavelength's) and its record beside it
// (.json); the other cases write the record alone (a polarized record holds every Mueller sum).
std::string output_extension(const std::string& estimator, const std::string& scene) {
  return estimator == "bsdf_spectral" && scene == "tile" ? "bsdf" : "json";
}
// The record of an output (OUT.bsdf: OUT.json beside it).
std::string record_of(const std::string& output) { return output.substr(0, output.rfind('.')) + ".json"; }

// The numbers of a JSON value (nested arrays and objects), in order.
void numbers_of(const json& j, std::vector<double>& out) {
  if (j.is_number()) out.push_back(j.get<double>());
  else if (j.is_array() || j.is_object())
    for (const auto& e : j) numbers_of(e, out);
}
bool any_nonzero(const json& j) {
  std::vector<double> v;
  numbers_of(j, v);
  for (double x : v)
    if (x != 0.0) return true;
  return false;
}

// A spectral run's per-wavelength albedo and a polarized run's Mueller fields hold data for every
// wavelength (the comparison of records that were all zeros there would prove nothing).
void expect_spectral_and_mueller_data(const json& rec, const std::string& estimator, const std::string& cmd) {
  if (estimator != "bsdf_spectral" && estimator != "bsdf_polarized") return;
  const json& total = rec.at("spectral").at("albedo").at("reflected").at("total");
  ASSERT_EQ(total.size(), 3u) << cmd;
  for (const json& a : total) EXPECT_GT(a.get<double>(), 0.0) << cmd;
  EXPECT_NE(total[0], total[2]) << cmd << ": gold's albedo depends on the wavelength";
  if (estimator != "bsdf_polarized") return;
  const json& p = rec.at("polarization");
  for (const char* part : {"mueller", "mueller_stderr", "resolved_degree_of_polarization", "degree_of_polarization"})
    for (std::size_t l = 0; l < 3; ++l)
      EXPECT_TRUE(any_nonzero(p.at("reflected").at("total").at(l).at(part))) << cmd << ": " << part << " " << l;
  for (std::size_t l = 0; l < 3; ++l) {
    EXPECT_TRUE(any_nonzero(p.at("bins").at("f").at(l))) << cmd << ": bins, wavelength " << l;
    EXPECT_TRUE(any_nonzero(p.at("in_plane").at("total").at("f").at(l))) << cmd << ": in_plane, wavelength " << l;
  }
}

class TallyFields : public ::testing::TestWithParam<Case> {
 protected:
  static void SetUpTestSuite() {
    const auto run = [](const std::string& args) {
      const Result r = run_microsim(args + " -q");
      ASSERT_EQ(r.code, 0) << args << "\n" << r.err;
    };
    run("generate gaussian --resolution 32 --alpha 0.8 --seed 2 -o " + tmp("tile.exr"));
    // A measured patch: the same kind of heights imported as a non-periodic window.
    run("generate gaussian --resolution 32 --alpha 0.8 --seed 5 -o " + tmp("scan.exr"));
    run("generate heightmap --input " + tmp("scan.exr") + " --pixel-size 0.03125 --guard 2 -o " + tmp("window.exr"));
    run("generate tiled-boxes --tiles 2 -o " + tmp("boxes.ply"));
    run("generate vcavity --grooves 32 -o " + tmp("vcavity.ply"));
  }
  static std::string surface(const std::string& scene) {
    if (scene == "tile") return tmp("tile.exr");
    if (scene == "window") return tmp("window.exr");
    if (scene == "boxes") return tmp("boxes.ply");
    return tmp("vcavity.ply");
  }
};

TEST_P(TallyFields, ShardsMergedAndMpiRanksEqualOneRunWithEveryCounter) {
  const Case c = GetParam();
  const std::string name = std::string(c.estimator) + "_" + c.scene;
  const std::string cmd = command(c.estimator, surface(c.scene));
  const std::string ext = output_extension(c.estimator, c.scene);
  const std::string one = tmp(name + "_one." + ext), part = tmp(name + "_part." + ext),
                    merged = tmp(name + "_merged." + ext);
  Result r = run_microsim(cmd + " --threads 1 -q -o " + one);
  ASSERT_EQ(r.code, 0) << cmd << "\n" << r.err;
  for (int k = 1; k <= 2; ++k) {
    r = run_microsim(cmd + " --threads 2 -q --shard " + std::to_string(k) + "/2 -o " + part);
    ASSERT_EQ(r.code, 0) << cmd << "\n" << r.err;
  }
  r = run_microsim("merge " + part + ".shard-1-of-2.json " + part + ".shard-2-of-2.json --threads 1 -q -o " +
                   merged);
  ASSERT_EQ(r.code, 0) << r.err;
  const json single = read_record(record_of(one));

  // Every record holds every counter, under its name.
  std::vector<json> counters;
  collect_counters(single, counters);
  ASSERT_FALSE(counters.empty()) << cmd;
  for (const json& tc : counters) {
    std::set<std::string> keys;
    for (auto it = tc.begin(); it != tc.end(); ++it) keys.insert(it.key());
    EXPECT_EQ(keys, kCounters) << cmd << ": " << tc.dump();
    EXPECT_GT(tc.value("rays", 0ull), 0u) << cmd;
  }
  // The counters that the scene makes non-zero are non-zero (a merge that dropped them would
  // give zeros, and equal zeros would prove nothing).
  std::uint64_t side_exits = 0, side_entries = 0, crossings = 0, below = 0;
  for (const json& tc : counters) {
    side_exits += tc.value("side_exits", 0ull);
    side_entries += tc.value("side_entries", 0ull);
    crossings += tc.value("border_crossings", 0ull);
    below += tc.value("lost_below", 0ull);
  }
  const std::string scene = c.scene, estimator = c.estimator;
  const bool bsdf = estimator.rfind("bsdf", 0) == 0;
  if (scene == "window" && !bsdf) {
    EXPECT_GT(side_exits, 0u) << cmd;
    if (estimator == "g1" || estimator == "vndf") {
      EXPECT_GT(side_entries, 0u) << cmd;
    }
  }
  if (scene == "tile") {
    EXPECT_GT(crossings, 0u) << cmd;
  }
  if (scene == "boxes" && estimator != "g2") {
    EXPECT_GT(below, 0u) << cmd;  // rays beside the object
  }

  expect_spectral_and_mueller_data(single, estimator, cmd);
  const json a = record_without_timings(single), b = record_without_timings(read_record(record_of(merged)));
  EXPECT_TRUE(a == b) << cmd << "\nmerged shards differ from one run: " << differences(a, b);
  if (ext != "json") {
    EXPECT_TRUE(slurp(one) == slurp(merged)) << cmd << "\nmerged shards' ." << ext << " differs";
  }

#ifdef MICROSIM_MPIEXEC
  const std::string two = tmp(name + "_mpi." + ext);
  r = run_microsim(cmd + " --threads 1 -q -o " + two, std::string(MICROSIM_MPIEXEC) +
                                                          " -n 2 --allow-run-as-root --oversubscribe --bind-to none");
  ASSERT_EQ(r.code, 0) << cmd << "\n" << r.err;
  const json ranks = read_record(record_of(two));
  EXPECT_EQ(ranks.value("ranks", 0), 2) << cmd;
  const json m = record_without_timings(ranks);
  EXPECT_TRUE(a == m) << cmd << "\nmpirun -n 2 differs from one run: " << differences(a, m);
  if (ext != "json") {
    EXPECT_TRUE(slurp(one) == slurp(two)) << cmd << "\nmpirun -n 2's ." << ext << " differs";
  }
#endif
}

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  for (const char* e : {"g1", "g2", "vndf", "bsdf"})
    for (const char* s : {"tile", "window", "boxes", "vcavity"}) cases.push_back({e, s});
  for (const char* e : {"bsdf_spectral", "bsdf_polarized"})
    for (const char* s : {"tile", "window", "boxes"}) cases.push_back({e, s});
  return cases;
}

INSTANTIATE_TEST_SUITE_P(EveryEstimatorAndScene, TallyFields, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return std::string(info.param.estimator) + "_" + info.param.scene;
                         });

// The declaration itself: the counters' sum, their packing for the exchange and their record
// fields visit every field, in declaration order.
TEST(TallyFieldsDeclaration, TraceCountersSumPackAndRecordEveryField) {
  microsim::TraceCounters a;
  std::uint64_t v = 1;
  microsim::TraceCounters::for_each_field([&](const char*, auto m) { a.*m = v++; });
  microsim::TraceCounters b = a;
  b += a;
  std::vector<std::uint64_t> packed(microsim::scalar_field_count<microsim::TraceCounters>());
  EXPECT_EQ(packed.size(), kCounters.size());
  microsim::pack_fields(b, packed.data());
  for (std::size_t k = 0; k < packed.size(); ++k) EXPECT_EQ(packed[k], 2 * (k + 1));
  microsim::TraceCounters c;
  microsim::unpack_fields(c, packed.data());
  const json j = json::parse(microsim::fields_json(c).dump());
  EXPECT_EQ(j.size(), kCounters.size());
  for (const std::string& k : kCounters) EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j["side_entries"], 2 * kCounters.size());
  EXPECT_EQ(j["rays"], 2u);
}

// The sums of a spectral replicate and a replicate's Mueller sums cross a split as rows of their
// declared fields (FieldRows): a replicate put into its row and read back keeps every member
// (listed here by hand, not taken from the declaration), and operator+= adds every member, so a
// member missing from SpectralTally::for_each_field or MuellerUnit::for_each_field fails here.
TEST(TallyFieldsDeclaration, SpectralRowsAndSumsCarryEveryMember) {
  using microsim::SpectralTally;
  SpectralTally s(3, 2, 4, 5);
  double x = 1;
  for (std::vector<double>* v : {&s.albedo, &s.pix, &s.plane})
    for (double& e : *v) e = x++;
  s.paths = 11;
  s.lost = 12;
  s.unterminated = 13;
  s.events = 14;
  s.counters.rays = 15;
  s.counters.side_entries = 16;
  microsim::ShardRecorder whole(1, 1);  // one process: the exchange leaves the rows as they are
  microsim::FieldRows<SpectralTally> rows("bsdf_spectral", 2, {0, 2}, SpectralTally(3, 2, 4, 5));
  rows.put(1, s);
  rows.exchange(whole);
  SpectralTally back(3, 2, 4, 5);
  rows.get(1, back);
  EXPECT_EQ(back.albedo, s.albedo);
  EXPECT_EQ(back.pix, s.pix);
  EXPECT_EQ(back.plane, s.plane);
  EXPECT_EQ(back.paths, 11u);
  EXPECT_EQ(back.lost, 12u);
  EXPECT_EQ(back.unterminated, 13u);
  EXPECT_EQ(back.events, 14u);
  EXPECT_EQ(back.counters.rays, 15u);
  EXPECT_EQ(back.counters.side_entries, 16u);
  rows.get(0, back);  // a row nobody put: zeros
  EXPECT_EQ(back.paths, 0u);
  EXPECT_EQ(back.pix, std::vector<double>(s.pix.size(), 0.0));
  SpectralTally twice(3, 2, 4, 5);
  twice += s;
  twice += s;
  for (std::size_t i = 0; i < s.pix.size(); ++i) EXPECT_EQ(twice.pix[i], 2 * s.pix[i]);
  EXPECT_EQ(twice.albedo[5], 2 * s.albedo[5]);
  EXPECT_EQ(twice.plane.back(), 2 * s.plane.back());
  EXPECT_EQ(twice.events, 28u);
  EXPECT_EQ(twice.counters.side_entries, 32u);
  // A replicate of another shape, or outside this process's share, is a programming error.
  EXPECT_THROW(rows.put(1, SpectralTally(2, 2, 4, 5)), std::logic_error);
  microsim::FieldRows<SpectralTally> half("bsdf_spectral", 2, {0, 1}, SpectralTally(3, 2, 4, 5));
  EXPECT_THROW(half.put(1, s), std::logic_error);
}

TEST(TallyFieldsDeclaration, MuellerRowsAndSumsCarryEveryMember) {
  using microsim::MuellerUnit;
  const auto shaped = [] {
    MuellerUnit u;
    u.sums.assign(2 * 16, 0.0);
    u.map.assign(2 * 4 * 16, 0.0);
    u.bins.assign(3 * 16, 0.0);
    u.plane.assign(2 * 5 * 16, 0.0);
    return u;
  };
  MuellerUnit m = shaped();
  double x = 1;
  for (std::vector<double>* v : {&m.sums, &m.map, &m.bins, &m.plane})
    for (double& e : *v) e = x++;
  m.paths = 7;
  microsim::ShardRecorder whole(1, 1);
  microsim::FieldRows<MuellerUnit> rows("bsdf_mueller", 1, {0, 1}, shaped());
  rows.put(0, m);
  rows.exchange(whole);
  MuellerUnit back = shaped();
  rows.get(0, back);
  EXPECT_EQ(back.sums, m.sums);
  EXPECT_EQ(back.map, m.map);
  EXPECT_EQ(back.bins, m.bins);
  EXPECT_EQ(back.plane, m.plane);
  EXPECT_EQ(back.paths, 7u);
  MuellerUnit twice = shaped();
  twice += m;
  twice += m;
  EXPECT_EQ(twice.sums[3], 2 * m.sums[3]);
  EXPECT_EQ(twice.map[9], 2 * m.map[9]);
  EXPECT_EQ(twice.bins[20], 2 * m.bins[20]);
  EXPECT_EQ(twice.plane.back(), 2 * m.plane.back());
  EXPECT_EQ(twice.paths, 14u);
}

}  // namespace
