// One run split over processes: shards merged (microsim merge) and MPI ranks (mpirun, when built
// with MPI) must write the record of a single run at the same seed, apart from timing fields
// (and the `ranks` field of an MPI record); incomplete, duplicated or foreign parts are refused.
#include <gtest/gtest.h>

#include <cstdio>
#include <set>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_helpers.hpp"
#include "record_helpers.hpp"
#include "microsim/measure/shards.hpp"

namespace {
using namespace microsim;
using namespace microsim::testing;
using nlohmann::json;

std::string tmp(const std::string& name) { return temp_path("shards", name); }

class Shards : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    surface_ = tmp("s.exr");
    other_ = tmp("t.exr");
    for (const auto& [path, seed] : {std::pair{surface_, 2}, std::pair{other_, 3}}) {
      const Result r = run_microsim("generate gaussian --resolution 48 --alpha 0.5 --seed " +
                                    std::to_string(seed) + " -q -o " + path);
      ASSERT_EQ(r.code, 0) << r.err;
    }
  }
  // Runs `command -o OUT` once, then as n shards merged into OUT2; returns both records.
  static std::pair<json, json> single_and_merged(const std::string& command, const std::string& name,
                                                 int n, const std::string& ext = "json") {
    const std::string one = tmp(name + "_one." + ext), merged = tmp(name + "_merged." + ext),
                      part = tmp(name + "_part." + ext);
    Result r = run_microsim(command + " --threads 1 -q -o " + one);
    EXPECT_EQ(r.code, 0) << r.err;
    std::string parts;
    for (int k = 1; k <= n; ++k) {
      r = run_microsim(command + " -q --shard " + std::to_string(k) + "/" + std::to_string(n) + " -o " + part);
      EXPECT_EQ(r.code, 0) << r.err;
      EXPECT_FALSE(exists(part)) << "a shard writes only its partial record";
      parts += " " + part + ".shard-" + std::to_string(k) + "-of-" + std::to_string(n) + ".json";
    }
    r = run_microsim("merge" + parts + " --threads 1 -q -o " + merged);
    EXPECT_EQ(r.code, 0) << r.err;
    const std::string js = ext == "json" ? "" : ".json";
    const auto record = [&](const std::string& p) {
      return ext == "json" ? read_record(p) : read_record(p.substr(0, p.size() - ext.size()) + "json");
    };
    (void)js;
    return {record(one), record(merged)};
  }
  static std::string surface_, other_;
};
std::string Shards::surface_, Shards::other_;

}  // namespace

// --- the split itself -----------------------------------------------------------------------

TEST(ShardRange, SharesTileTheUnitsExactlyOnce) {
  for (std::uint64_t units : {0ull, 1ull, 5ull, 32ull, 33ull, 1000003ull})
    for (int n : {1, 2, 3, 4, 7, 32, 64}) {
      std::uint64_t at = 0, biggest = 0, smallest = ~0ull;
      for (int k = 0; k < n; ++k) {
        const UnitRange r = shard_range(units, k, n);
        EXPECT_EQ(r.first, at) << units << " " << k << "/" << n;
        at = r.end;
        biggest = std::max(biggest, r.size());
        smallest = std::min(smallest, r.size());
      }
      EXPECT_EQ(at, units);
      EXPECT_LE(biggest - smallest, 1u) << "balanced shares";
    }
}

TEST(ShardParse, AcceptsKOverNOnly) {
  EXPECT_EQ(parse_shard("3/4"), std::make_pair(3, 4));
  for (const char* bad : {"0/4", "5/4", "4", "a/b", "1/0", "-1/2", "1/4/2", ""})
    EXPECT_THROW(parse_shard(bad), UsageError) << bad;
}

namespace {
// Three shards of one fake run with a replicate-split entry (rows) and a ray-split one (tails).
std::vector<std::pair<std::string, Json>> fake_parts(int n, const std::string& command = "measure g1 x") {
  std::vector<std::pair<std::string, Json>> parts;
  RunIdentity run;
  run.command = {command, "-o", kOutputPlaceholder};
  run.output = "out.json";
  run.version = "test";
  for (int k = 1; k <= n; ++k) {
    ShardRecorder s(k, n);
    const UnitRange reps = s.share(10);
    Tallies rows("g1", 10, reps, 2, 1, kCounterValues, 0);
    for (std::uint64_t q = reps.first; q < reps.end; ++q) {
      rows.count_row(q)[0] = 100 + q;
      rows.count_row(q)[1] = 7 * q;
      rows.real_row(q)[0] = 0.1 * static_cast<double>(q) + 1.0 / 3.0;
    }
    rows.tail_counts[0] = reps.size() * 1000;
    s.exchange(rows);
    Tallies rays("vndf", 1000, s.share(1000), 0, 0, 3, 0);
    rays.tail_counts = {s.share(1000).size(), 1, static_cast<std::uint64_t>(k)};
    s.exchange(rays);
    parts.emplace_back("part" + std::to_string(k), Json::parse(partial_json(run, s, 1.0).dump()));
  }
  return parts;
}
std::string usage_message(const std::vector<std::pair<std::string, Json>>& parts) {
  try {
    merge_partials(parts);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(MergePartials, RowsPlacedTotalsSummedExactly) {
  const MergedRun m = merge_partials(fake_parts(3));
  ASSERT_EQ(m.shards, 3);
  ASSERT_EQ(m.entries.size(), 2u);
  Tallies rows = m.entries[0];
  for (std::uint64_t q = 0; q < 10; ++q) {
    EXPECT_EQ(rows.count_row(q)[0], 100 + q);
    EXPECT_EQ(rows.count_row(q)[1], 7 * q);
    // Reals arrive bit for bit through the partial record's JSON.
    EXPECT_EQ(rows.real_row(q)[0], 0.1 * static_cast<double>(q) + 1.0 / 3.0);
  }
  EXPECT_EQ(rows.tail_counts[0], 10000u);
  EXPECT_EQ(m.entries[1].tail_counts, (std::vector<std::uint64_t>{1000, 3, 6}));
  // Power: a merge that lost a shard's rows would not give these numbers.
  auto parts = fake_parts(3);
  parts[1].second["tallies"][0]["counts"][0] = 0;
  EXPECT_NE(merge_partials(parts).entries[0].counts, m.entries[0].counts);
}

TEST(MergePartials, RefusesMissingDuplicatedAndForeignParts) {
  auto parts = fake_parts(4);
  auto missing = parts;
  missing.erase(missing.begin() + 2);
  EXPECT_NE(usage_message(missing).find("shard 3/4 missing"), std::string::npos) << usage_message(missing);
  auto dup = parts;
  dup[3] = dup[0];
  dup[3].first = "again";
  EXPECT_NE(usage_message(dup).find("shard 1/4 is given twice (part1 and again)"), std::string::npos)
      << usage_message(dup);
  auto foreign = parts;
  foreign[2] = fake_parts(4, "measure g1 y")[2];
  EXPECT_NE(usage_message(foreign).find("part3 belongs to another run"), std::string::npos)
      << usage_message(foreign);
  auto mixed = parts;
  mixed[1] = fake_parts(2)[1];
  EXPECT_NE(usage_message(mixed).find("one of 4 shards"), std::string::npos) << usage_message(mixed);
  auto damaged = parts;
  damaged[0].second["run"]["command"][0] = "measure g2 x";
  EXPECT_NE(usage_message(damaged).find("damaged"), std::string::npos) << usage_message(damaged);
  auto overlap = parts;
  overlap[1].second["tallies"][0]["covered"] = {0, 5};
  overlap[1].second["tallies"][0]["counts"] = Json::array();
  for (int i = 0; i < 10; ++i) overlap[1].second["tallies"][0]["counts"].push_back(1);
  overlap[1].second["tallies"][0]["reals"] = {1, 1, 1, 1, 1};
  EXPECT_NE(usage_message(overlap).find("covered twice"), std::string::npos) << usage_message(overlap);
  EXPECT_EQ(usage_message(parts), "");
}

// --- shards of real runs merged: the single run's record ------------------------------------

TEST_F(Shards, G1FourShardsMergedEqualOneRun) {
  const auto [one, merged] = single_and_merged(
      "measure g1 " + surface_ + " --theta 0,40,75 --rays 6000 --seed 5", "g1", 4);
  EXPECT_EQ(record_without_timings(merged), record_without_timings(one));
  // Power: another seed is another record.
  const auto [other, unused] = single_and_merged(
      "measure g1 " + surface_ + " --theta 0,40,75 --rays 6000 --seed 6", "g1b", 1);
  EXPECT_NE(record_without_timings(other)["rows"], record_without_timings(one)["rows"]);
}

TEST_F(Shards, G1EnsembleOfTwoSurfacesMerged) {
  const auto [one, merged] =
      single_and_merged("measure g1 " + surface_ + " " + other_ + " --theta 60 --rays 4000", "g1e", 3);
  EXPECT_EQ(record_without_timings(merged), record_without_timings(one));
  EXPECT_TRUE(one.contains("per_surface"));
}

TEST_F(Shards, G2FourShardsMergedEqualOneRun) {
  const auto [one, merged] = single_and_merged("measure g2 " + surface_ +
                                                   " --theta-o 30,70 --theta-i 50 --phi-i 180 --rays 5000",
                                               "g2", 4);
  EXPECT_EQ(record_without_timings(merged), record_without_timings(one));
}

TEST_F(Shards, VndfFourShardsMergedEqualOneRun) {
  const auto [one, merged] =
      single_and_merged("measure vndf " + surface_ + " --theta 20,60 --rays 20001 --sampler-samples 2000",
                        "vndf", 4);
  EXPECT_EQ(record_without_timings(merged), record_without_timings(one));
}

TEST_F(Shards, BsdfMirrorFourShardsMergedEqualOneRun) {
  const auto [one, merged] = single_and_merged(
      "measure bsdf " + surface_ + " --material mirror --theta-i 50 --rays 8000 --resolution 8", "bm", 4);
  EXPECT_EQ(record_without_timings(merged), record_without_timings(one));
  EXPECT_TRUE(one.contains("albedo"));
}

TEST_F(Shards, BsdfDielectricAndConductorFourShardsMergedEqualOneRun) {
  // Conductor weights are real numbers: exact only because each replicate row comes from one shard.
  // (The Smith walk's batches are split in the mirror test above; here measured tallies only.)
  for (const std::string& material : {std::string("dielectric --eta 1.5"), std::string("conductor --eta 0.2 --k 3")}) {
    const auto [one, merged] = single_and_merged("measure bsdf " + surface_ + " --material " + material +
                                                     " --theta-i 30 --rays 8000 --resolution 8 --no-models",
                                                 "bd", 4, "exr");
    EXPECT_EQ(record_without_timings(merged), record_without_timings(one)) << material;
  }
}

TEST_F(Shards, ValidateThreeShardsMergedEqualOneRun) {
  const auto [one, merged] = single_and_merged("validate " + surface_ +
                                                   " --checks g1,g2,vndf,bsdf_albedo --theta 30,70 --rays 6000",
                                               "val", 3);
  EXPECT_EQ(record_without_timings(merged), record_without_timings(one));
  EXPECT_TRUE(one.contains("rows") || one.contains("checks")) << one.dump().substr(0, 300);
}

TEST_F(Shards, MergeRefusesMissingDuplicatedAndForeignShardsWithOneLine) {
  const std::string part = tmp("ref.json"), out = tmp("ref_merged.json");
  const std::string cmd = "measure g1 " + surface_ + " --theta 30 --rays 2000 -q -o " + part;
  for (int k = 1; k <= 3; ++k) ASSERT_EQ(run_microsim(cmd + " --shard " + std::to_string(k) + "/3").code, 0);
  ASSERT_EQ(run_microsim(cmd + " --seed 9 --shard 2/3").code, 0);  // overwrites shard 2 with a foreign run
  const auto p = [&](int k) { return " " + part + ".shard-" + std::to_string(k) + "-of-3.json"; };
  std::remove(out.c_str());
  for (const auto& [parts, needle] :
       {std::pair{p(1) + p(3), std::string("shard 2/3 missing")},
        std::pair{p(1) + p(1) + p(3), std::string("is given twice")},
        std::pair{p(1) + p(2) + p(3), std::string("belongs to another run")}}) {
    const Result r = run_microsim("merge" + parts + " -o " + out);
    EXPECT_EQ(r.code, 2) << parts << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
    EXPECT_FALSE(exists(out));
  }
  const Result bad = run_microsim("measure ndf " + surface_ + " --shard 1/2 -o " + out);
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--shard applies to"), std::string::npos) << bad.err;
  const Result bad_k = run_microsim(cmd + " --shard 5/4");
  EXPECT_EQ(bad_k.code, 2);
  EXPECT_EQ(lines(bad_k.err), 1) << bad_k.err;
}

TEST_F(Shards, MergeRefusesAChangedInput) {
  const std::string copy = tmp("copy.exr"), part = tmp("chg.json"), out = tmp("chg_merged.json");
  ASSERT_EQ(std::system(("cp " + surface_ + " " + copy).c_str()), 0);
  const std::string cmd = "measure g1 " + copy + " --theta 30 --rays 2000 -q -o " + part + " --shard ";
  ASSERT_EQ(run_microsim(cmd + "1/1").code, 0);
  ASSERT_EQ(std::system(("cp " + other_ + " " + copy).c_str()), 0);
  const Result r = run_microsim("merge " + part + ".shard-1-of-1.json -o " + out);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("changed since the shards ran"), std::string::npos) << r.err;
  EXPECT_FALSE(exists(out));
}

// --- MPI ------------------------------------------------------------------------------------

#ifdef MICROSIM_MPIEXEC
namespace {
Result mpirun(int n, const std::string& args) {
  return run_microsim(args, std::string(MICROSIM_MPIEXEC) + " -n " + std::to_string(n) +
                                " --allow-run-as-root --oversubscribe --bind-to none");
}
}  // namespace

TEST_F(Shards, MpiTwoRanksRecordsEqualOneProcess) {
  for (const std::string& cmd :
       {"measure g1 " + surface_ + " --theta 0,60 --rays 6000",
        "measure g2 " + surface_ + " --theta-o 40 --theta-i 60 --rays 4000",
        "measure vndf " + surface_ + " --theta 45 --rays 20000",
        "measure bsdf " + surface_ + " --material mirror --theta-i 50 --rays 6000 --resolution 8",
        "measure bsdf " + surface_ + " --material dielectric --eta 1.5 --theta-i 20 --rays 6000 --resolution 8",
        "validate " + surface_ + " --checks g1,g2,vndf,bsdf_albedo --theta 50 --rays 4000"}) {
    const std::string one = tmp("mpi_one.json"), two = tmp("mpi_two.json");
    std::remove(two.c_str());
    Result r = run_microsim(cmd + " --threads 1 -q -o " + one);
    ASSERT_EQ(r.code, 0) << r.err;
    r = mpirun(2, cmd + " --threads 1 -q -o " + two);
    ASSERT_EQ(r.code, 0) << cmd << "\n" << r.err;
    const json a = read_record(one), b = read_record(two);
    EXPECT_EQ(b.value("ranks", 0), 2) << cmd;
    EXPECT_FALSE(a.contains("ranks"));
    EXPECT_EQ(record_without_timings(b), record_without_timings(a)) << cmd;
  }
}

TEST_F(Shards, MpiBadInputOneLineExitTwoOnEveryRank) {
  const std::string out = tmp("mpi_bad.json");
  std::remove(out.c_str());
  const Result r = mpirun(2, "measure g1 " + surface_ + " --theta 95 -q -o " + out);
  EXPECT_EQ(r.code, 2) << r.err;
  std::size_t count = 0;
  for (std::size_t at = r.err.find("microsim: error"); at != std::string::npos; at = r.err.find("microsim: error", at + 1)) ++count;
  EXPECT_EQ(count, 1u) << r.err;
  EXPECT_FALSE(exists(out));
}
#endif

// A V-cavity ensemble is measured groove by groove; its replicates (G1, G2), rays (VNDF) and
// units of grooves (the BSDF walk) are shared out like those of a single surface, and the merged
// shards give the single run's record.
TEST_F(Shards, VcavityG1G2VndfBsdfAndValidateShardsMergedEqualOneRun) {
  const std::string vc = tmp("vc.ply");
  ASSERT_EQ(run_microsim("generate vcavity --grooves 128 -q -o " + vc).code, 0);
  const std::vector<std::tuple<std::string, std::string, int>> runs = {
      {"measure g1 " + vc + " --theta 40,80 --rays 6000", "vcg1", 3},
      {"measure g2 " + vc + " --theta-o 30,75 --theta-i 60 --phi-i 180 --rays 6000", "vcg2", 4},
      {"measure vndf " + vc + " --theta 20,70 --rays 20001 --sampler-samples 0", "vcvndf", 4},
      {"validate " + vc + " --checks g1,g2,vndf --theta 75 --rays 12000", "vcval", 2},
      {"measure bsdf " + vc + " --material conductor --eta 0.2 --k 3 --theta-i 60 --rays 6000 --resolution 8 "
       "--no-models", "vcbsdf", 4}};
  for (const auto& [command, name, n] : runs) {
    const auto [one, merged] = single_and_merged(command, name, n);
    EXPECT_EQ(record_without_timings(merged), record_without_timings(one)) << command;
    if (command.rfind("measure g2", 0) == 0 || command.rfind("measure vndf", 0) == 0) {
      EXPECT_TRUE(one.value("groove_by_groove", false)) << command;
    }
    // Power: every shard traced a share of each estimator call, not all of it (an estimator that
    // ignores the split exchanges no tallies).
    const json part = read_record(tmp(name + "_part.json") + ".shard-1-of-" + std::to_string(n) + ".json");
    EXPECT_FALSE(part["tallies"].empty()) << command;
    for (const auto& t : part["tallies"]) {
      const auto covered = t["covered"][1].get<std::uint64_t>() - t["covered"][0].get<std::uint64_t>();
      EXPECT_GT(covered, 0u) << command;
      EXPECT_LT(covered, t["units"].get<std::uint64_t>()) << command;
    }
  }
}
