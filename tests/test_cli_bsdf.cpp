// microsim measure bsdf as users and scripts see it: the output files and the documented
// fields, and bad input answered with one line on stderr, exit code 2 and no output file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <sys/stat.h>
#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include "cli_helpers.hpp"

#include "microsim/io/output.hpp"

namespace {
using namespace microsim::testing;
std::string tmp(const std::string& name) { return temp_path("cli_bsdf", name); }
Result run(const std::string& args) { return run_microsim(args); }

class CliBsdf : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    surface_ = tmp("s.exr");
    Result r = run("generate gaussian --resolution 64 --alpha 0.5 --seed 2 -o " + surface_);
    ASSERT_EQ(r.code, 0) << r.err;
  }
  static void expect_usage_error(const std::string& args, const std::string& output, const std::string& needle) {
    std::remove(output.c_str());
    Result r = run(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\n" << r.err;
    EXPECT_FALSE(exists(output)) << args;
  }
  static std::string surface_;
};
std::string CliBsdf::surface_;

}  // namespace

TEST_F(CliBsdf, ExrTableAndJsonSummaryWithTheDocumentedFields) {
  const std::string out = tmp("d.exr"), js = tmp("d.json");
  std::remove(out.c_str());
  std::remove(js.c_str());
  Result r = run("measure bsdf " + surface_ +
                 " --material dielectric --eta 1.5 --theta-i 40 --phi-i 0 --rays 20000 --resolution 16 -q -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(exists(out));
  ASSERT_TRUE(exists(js));
  const auto j = nlohmann::json::parse(slurp(js));
  for (const char* side : {"reflected", "transmitted"})
    for (const char* k : {"order_1", "order_2", "order_3", "order_4plus", "total"}) {
      EXPECT_TRUE(j["albedo"][side][k].is_number()) << side << " " << k;
      EXPECT_TRUE(j[std::string(side) + "_stderr"][k].is_number()) << side << " " << k;
    }
  const double R = j["albedo"]["reflected"]["total"], T = j["albedo"]["transmitted"]["total"];
  EXPECT_NEAR(R + T, 1.0, 1e-12);
  ASSERT_EQ(j["in_plane"].size(), 32u);  // 16 bins per side, two sides
  for (const auto& row : j["in_plane"])
    for (const char* k : {"theta_o_deg", "f_order_1", "f_order_1_stderr", "f_total", "f_total_stderr",
                          "smith_single", "vcavity_single", "smith_multiple"})
      EXPECT_TRUE(row[k].is_number()) << k;
  EXPECT_EQ(j["parameters"]["material"], "dielectric");
  EXPECT_EQ(j["surface"]["kind"], "gaussian");
  EXPECT_TRUE(j["wall_seconds"].is_number());
  // EXR: one channel per order plus total, with standard errors, both sides; parameters in the header.
  const microsim::ExrTable t = microsim::read_exr(out);
  EXPECT_EQ(t.width, 16);
  EXPECT_EQ(t.channel_names.size(), 2u * 5u * 2u);
  for (const char* c : {"reflected.f_order_1", "reflected.f_total_stderr", "transmitted.f_order_4plus"})
    EXPECT_NE(std::find(t.channel_names.begin(), t.channel_names.end(), c), t.channel_names.end()) << c;
  for (const char* a : {"parameters", "surface", "parameterization", "albedo"})
    EXPECT_TRUE(t.attributes.contains(a)) << a;
}

TEST_F(CliBsdf, JsonOnlyAndMirrorHasNoTransmission) {
  const std::string out = tmp("m.json");
  std::remove(out.c_str());
  Result r = run("measure bsdf " + surface_ + " --material mirror --theta-i 0 --phi-i 0 --rays 20000 --orders 3 -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("order_3plus"), std::string::npos);  // printed table
  const auto j = nlohmann::json::parse(slurp(out));
  EXPECT_EQ(j["albedo"]["reflected"]["total"], 1.0);
  EXPECT_EQ(j["albedo"]["transmitted"]["total"], 0.0);
  EXPECT_TRUE(j["albedo"]["reflected"]["order_3plus"].is_number());
  EXPECT_FALSE(exists(tmp("m.exr")));
}

TEST_F(CliBsdf, BadInput) {
  const std::string out = tmp("bad.json");
  const std::string base = "measure bsdf " + surface_ + " --theta-i 30 --phi-i 0 --rays 1000 -o " + out;
  expect_usage_error(base + " --material plastic", out, "--material");
  expect_usage_error(base + " --material conductor --eta 0.2", out, "--k");
  expect_usage_error(base + " --material mirror --eta 1.5", out, "--eta");
  expect_usage_error(base + " --material dielectric", out, "--eta");
  expect_usage_error(base + " --material dielectric --eta 0", out, "--eta");
  expect_usage_error(base + " --material conductor --eta 0.2 --k -1", out, "--k");
  expect_usage_error("measure bsdf " + surface_ + " --material mirror --theta-i 90 --phi-i 0 -o " + out, out,
                     "--theta-i");
  expect_usage_error("measure bsdf " + surface_ + " --material mirror --theta-i -5 --phi-i 0 -o " + out, out,
                     "--theta-i");
  expect_usage_error(base + " --material mirror --orders 0", out, "--orders");
  expect_usage_error(base + " --material mirror --resolution 0", out, "--resolution");
  expect_usage_error(base + " --material mirror --resolution 100000", out, "--resolution");
  expect_usage_error("measure bsdf " + surface_ + " --material mirror --theta-i 30 --phi-i 0 --rays 0 -o " + out,
                     out, "--rays");
  expect_usage_error("measure bsdf " + surface_ + " --material mirror --theta-i 30 --phi-i 0 -o " + tmp("x.png"),
                     tmp("x.png"), "-o");
  expect_usage_error("measure bsdf " + tmp("missing.exr") + " --material mirror --theta-i 30 --phi-i 0 -o " + out,
                     out, "missing");
  expect_usage_error("measure bsdf " + surface_ + " --material mirror --phi-i 0 -o " + out, out, "--theta-i");
}

TEST_F(CliBsdf, NoModelsMeasuresTheSameAndLeavesTheModelsOut) {
  // --no-models drops the analytic columns (their cost) and must not change a measured bit.
  const std::string with = tmp("m.json"), without = tmp("nm.json");
  const std::string args = "measure bsdf " + surface_ +
                           " --material mirror --theta-i 60 --phi-i 0 --rays 20000 --resolution 16 -q -o ";
  Result a = run(args + with);
  ASSERT_EQ(a.code, 0) << a.err;
  Result b = run(args + without + " --no-models");
  ASSERT_EQ(b.code, 0) << b.err;
  const auto ja = nlohmann::json::parse(slurp(with)), jb = nlohmann::json::parse(slurp(without));
  EXPECT_EQ(ja["albedo"], jb["albedo"]);
  EXPECT_EQ(ja["reflected_stderr"], jb["reflected_stderr"]);
  EXPECT_TRUE(ja["albedo_models"]["smith_multiple"].is_object());
  EXPECT_TRUE(ja["albedo_models"]["smith_single"].is_object());
  EXPECT_TRUE(jb["albedo_models"]["smith_multiple"].is_null());
  EXPECT_TRUE(jb["albedo_models"]["smith_single"].is_null());
  EXPECT_EQ(jb["parameters"]["smith_multiple_walks"], 0);
  EXPECT_EQ(jb["parameters"]["models"], false);
  std::remove(with.c_str());
  std::remove(without.c_str());
}

// -o .pbsdf: Mueller matrices of a conductor or mirror, one azimuth, the five wavelengths the
// plugin reads; each refusal names the option. A mirror's table is written (five copies of its
// single matrix) and the record says how it was filled.
TEST_F(CliBsdf, PolarizedTableRefusalsNameTheOption) {
  const std::string out = tmp("p.pbsdf");
  const std::string base = "measure bsdf " + surface_ + " --theta-i 30 --rays 1000 --no-models --table-resolution 8 -o " + out;
  expect_usage_error(base + " --material mirror", out, "--polarized");
  expect_usage_error(base + " --material dielectric --eta 1.5 --polarized", out, "--material");
  expect_usage_error(base + " --material conductor --metal Au --wavelengths 450:650:100 --polarized", out,
                     "--wavelengths");
  expect_usage_error(base + " --material conductor --metal Au --wavelengths 450,500,550,600,650.5 --polarized", out,
                     "--wavelengths");
  expect_usage_error(base + " --material mirror --polarized --phi-i 0,90", out, "--phi-i");
  const Result r = run(base + " --material mirror --polarized --table-azimuths 2");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(exists(out));
  std::ifstream in(tmp("p.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["table"]["shape"], nlohmann::json({9, 5, 5, 5, 4, 4}));
  EXPECT_EQ(j["table"]["wavelengths_nm"], nlohmann::json({450, 500, 550, 600, 650}));
  EXPECT_EQ(j["incidences"][0]["polarization"]["bins"]["resolution"], 32);
}
