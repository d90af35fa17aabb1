// The command line as users and scripts see it: outputs and their fields, and bad input
// answered with one line on stderr, exit code 2 and no output file.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "cli_helpers.hpp"
#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/measure/stats.hpp"
#include "microsim/measure/vcavity_measure.hpp"
#include "microsim/measure/vndf_measure.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/trace/tracer.hpp"

namespace {
using namespace microsim::testing;
std::string tmp(const std::string& name) { return temp_path("cli", name); }
Result run(const std::string& args) { return run_microsim(args); }

class Cli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    surface_ = tmp("s.exr");
    Result r = run("generate gaussian --resolution 64 --alpha 0.5 --seed 2 -o " + surface_);
    ASSERT_EQ(r.code, 0) << r.err;
  }
  // Bad input: exit 2, exactly one line on stderr mentioning `needle`, no output written.
  static void expect_usage_error(const std::string& args, const std::string& output,
                                 const std::string& needle) {
    std::remove(output.c_str());
    Result r = run(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(lines(r.err), 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\n" << r.err;
    EXPECT_FALSE(exists(output)) << args;
  }
  static std::string surface_;
};
std::string Cli::surface_;
}  // namespace

TEST_F(Cli, MeasureG1WritesTheDocumentedJsonFields) {
  std::string out = tmp("g1.json");
  Result r = run("measure g1 " + surface_ + " --theta 0:80:40 --phi 0,90 --rays 20000 --seed 3 -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  auto j = nlohmann::json::parse(slurp(out));
  ASSERT_EQ(j["rows"].size(), 6u);
  for (const auto& row : j["rows"]) {
    for (const char* k : {"theta_deg", "phi_deg", "g1", "g1_stderr", "visible_area_ratio",
                          "smith_numeric", "smith_nominal", "bins"})
      EXPECT_TRUE(row.contains(k)) << k;
    EXPECT_TRUE(row["smith_nominal"].is_number());
    ASSERT_FALSE(row["bins"].empty());
    for (const char* k : {"m", "area_fraction", "g1", "g1_stderr"})
      EXPECT_TRUE(row["bins"][0].contains(k)) << k;
  }
  EXPECT_EQ(j["rows"][1]["theta_deg"], 40.0);
  EXPECT_EQ(j["rows"][3]["phi_deg"], 90.0);
  EXPECT_EQ(j["parameters"]["seed"], 3);
  EXPECT_TRUE(j["surface"].contains("alpha_x"));
  // The same run as CSV: one line per row plus the header.
  std::string csv = tmp("g1.csv");
  ASSERT_EQ(run("measure g1 " + surface_ + " --theta 0:80:40 --phi 0,90 --rays 20000 --seed 3 -o " + csv).code, 0);
  EXPECT_EQ(lines(slurp(csv)), 7);
}

TEST_F(Cli, MeasureG1OverSeveralSurfacesReportsTheBetweenSurfaceError) {
  std::string second = tmp("s2.exr"), out = tmp("ens.json");
  ASSERT_EQ(run("generate gaussian --resolution 64 --alpha 0.5 --seed 3 -o " + second).code, 0);
  Result r = run("measure g1 " + surface_ + " " + second + " --theta 70 --rays 20000 -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  auto j = nlohmann::json::parse(slurp(out));
  ASSERT_EQ(j["per_surface"].size(), 2u);
  const auto& row = j["rows"][0];
  double a = j["per_surface"][0]["rows"][0]["g1"], b = j["per_surface"][1]["rows"][0]["g1"];
  EXPECT_NEAR(row["g1"].get<double>(), 0.5 * (a + b), 1e-12);
  // Between-surface standard error of two values: |a - b| / 2.
  EXPECT_NEAR(row["g1_stderr"].get<double>(), std::abs(a - b) / 2, 1e-12);
  EXPECT_TRUE(row.contains("g1_stderr_rays"));
  EXPECT_TRUE(row["z_nominal"].is_number());
  EXPECT_FALSE(row["bins"].empty());
}

TEST_F(Cli, ConvertExportsAMeshThatMeasuresLikeTheHeightfield) {
  std::string ply = tmp("s.ply"), a = tmp("a.json"), b = tmp("b.json");
  ASSERT_EQ(run("convert " + surface_ + " -o " + ply).code, 0);
  ASSERT_EQ(run("measure g1 " + surface_ + " --theta 75 --rays 20000 -o " + a).code, 0);
  ASSERT_EQ(run("measure g1 " + ply + " --theta 75 --rays 20000 -o " + b).code, 0);
  auto ja = nlohmann::json::parse(slurp(a)), jb = nlohmann::json::parse(slurp(b));
  EXPECT_NEAR(ja["rows"][0]["smith_numeric"].get<double>(), jb["rows"][0]["smith_numeric"].get<double>(), 1e-5);
  double se = std::hypot(ja["rows"][0]["g1_stderr"].get<double>(), jb["rows"][0]["g1_stderr"].get<double>());
  EXPECT_LT(std::abs(ja["rows"][0]["g1"].get<double>() - jb["rows"][0]["g1"].get<double>()), 4 * se);
}

TEST_F(Cli, MeasureNdfWritesExrAndJson) {
  std::string exr = tmp("ndf.exr"), json = tmp("ndf.json");
  ASSERT_EQ(run("measure ndf " + surface_ + " -o " + exr).code, 0);
  EXPECT_TRUE(exists(exr));
  ASSERT_EQ(run("measure ndf " + surface_ + " -o " + json + " --quiet").code, 0);
  auto j = nlohmann::json::parse(slurp(json));
  EXPECT_LT(j["checks"]["eq_1b_error"].get<double>(), 1e-9);
  EXPECT_LT(j["checks"]["eq_1c_error"].get<double>(), 1e-9);
  EXPECT_EQ(j["rows"].size(), 90u);
}

TEST_F(Cli, InfoPrintsFittedAlphaAndChecks) {
  Result r = run("info " + surface_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("fitted alpha"), std::string::npos);
  EXPECT_NE(r.out.find("eq. 1b"), std::string::npos);
  EXPECT_NE(r.out.find("eq. 1c"), std::string::npos);
}

TEST_F(Cli, PresetConfigGeneratesTheDocumentedSurface) {
  std::string out = tmp("preset.exr");
  Result r = run("generate gaussian --config " + std::string(MICROSIM_SOURCE_DIR) +
              "/surfaces/beckmann-0.5.toml --resolution 64 --correlation-length 0.0625 -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  Result info = run("info " + out + " --json " + tmp("info.json"));
  auto j = nlohmann::json::parse(slurp(tmp("info.json")));
  EXPECT_EQ(j["surface"]["alpha_x"], 0.5);
  EXPECT_EQ(j["surface"]["resolution"], 64);
  EXPECT_EQ(j["surface"]["correlation_length"], 0.0625);
  // The preset applies: its correlation length (16 cells of 1024) is below one cell of 32.
  std::remove(out.c_str());
  r = run("generate gaussian --config " + std::string(MICROSIM_SOURCE_DIR) +
          "/surfaces/beckmann-0.5.toml --resolution 32 -o " + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--correlation-length"), std::string::npos) << r.err;
  EXPECT_FALSE(exists(out));
}

TEST_F(Cli, BadInputIsOneLineExitTwoAndNoOutput) {
  std::string o = tmp("bad.json"), s = tmp("bad.exr");
  expect_usage_error("generate gaussian --alpha 0 -o " + s, s, "--alpha");
  expect_usage_error("generate gaussian --alpha -0.5 -o " + s, s, "--alpha");
  expect_usage_error("generate gaussian --resolution 0 -o " + s, s, "--resolution");
  expect_usage_error("generate gaussian --resolution 50000 -o " + s, s, "--resolution");
  expect_usage_error("generate gaussian -o " + tmp("bad.xyz"), tmp("bad.xyz"), "format");
  expect_usage_error("generate sphere -o " + s, s, "sphere");
  expect_usage_error("measure g1 " + surface_ + " --theta 90 -o " + o, o, "--theta");
  expect_usage_error("measure g1 " + surface_ + " --theta 0:95:5 -o " + o, o, "--theta");
  expect_usage_error("measure g1 " + surface_ + " --rays -5 -o " + o, o, "--rays");
  expect_usage_error("measure g1 " + surface_ + " --theta abc -o " + o, o, "--theta");
  expect_usage_error("measure g1 " + tmp("missing.exr") + " -o " + o, o, "does not exist");
  std::string corrupt = tmp("corrupt.exr");
  std::ofstream(corrupt) << "not an exr";
  expect_usage_error("measure g1 " + corrupt + " -o " + o, o, "corrupt.exr");
  expect_usage_error("measure ndf " + corrupt + " -o " + o, o, "corrupt.exr");
  expect_usage_error("info " + corrupt, o, "corrupt.exr");
  expect_usage_error("measure g1 " + surface_ + " -o " + tmp("bad.exr"), tmp("bad.exr"), ".json");
  expect_usage_error("frobnicate", o, "frobnicate");
}

// Structured and non-heightfield surfaces through the command line.
TEST_F(Cli, EveryStructuredKindGeneratesAndMeasures) {
  const std::vector<std::pair<std::string, std::string>> kinds = {
      {"box --width 1 --depth 1 --height 0.5", "box.ply"},
      {"tiled-boxes --tiles 2", "tiled.ply"},
      {"square-wave --period 1 --duty 0.5 --height 0.5", "sw.obj"},
      {"square-wave --2d", "sw2.off"},
      {"vgroove --facet-angle 30", "vg.exr"},
      {"vgroove --facet-angle 30 --2d", "pyr.ply"},
      {"vcavity --ndf ggx --alpha 0.4 --grooves 64", "vc.ply"},
      {"parallelepiped --shear-x 0.5 --tiles 2", "pp.ply"},
      {"ellipsoid --alpha-x 0.5 --alpha-y 0.3 --rings 16 --segments 64", "el.ply"},
      {"gaussian-ggx --resolution 64 --alpha 0.3", "gg.exr"}};
  for (const auto& [args, file] : kinds) {
    const std::string out = tmp(file);
    Result r = run("generate " + args + " -o " + out);
    ASSERT_EQ(r.code, 0) << args << "\n" << r.err;
    Result info = run("info " + out);
    EXPECT_EQ(info.code, 0) << args << "\n" << info.err;
    EXPECT_NE(info.out.find("eq. 1b"), std::string::npos);
  }
  // Views below the horizon on a mesh: the undersurface beside both approximations.
  const std::string g1 = tmp("box_g1.json");
  Result r = run("measure g1 " + tmp("box.ply") + " --theta 30,120 --rays 200000 -o " + g1);
  ASSERT_EQ(r.code, 0) << r.err;
  auto j = nlohmann::json::parse(slurp(g1));
  EXPECT_FALSE(j["rows"][0].contains("undersurface"));
  for (const char* k : {"undersurface", "g1_reverse_v", "g1_reverse_v_stderr", "g1_reflect_v",
                        "g1_reflect_v_stderr", "z_reverse_v", "z_reflect_v"})
    EXPECT_TRUE(j["rows"][1].contains(k)) << k;
  {
    // A convex box seen across a face: visible area ratio 1 + (H/B) tan(theta) = 1 + tan(30)/2
    // exactly [GeomBSDF24, Fig. 5], within its own standard error; a 2% wrong value is outside it.
    const double ratio = j["rows"][0]["visible_area_ratio"].get<double>();
    const double se = j["rows"][0]["visible_area_ratio_stderr"].get<double>();
    const double exact = 1 + 0.5 * std::tan(std::acos(-1.0) / 6), zt = microsim::sidak_z(0.01, 1);
    EXPECT_LT(std::abs(ratio - exact), zt * se) << ratio << " +- " << se << " vs " << exact;
    EXPECT_GT(std::abs(ratio - 1.02 * exact), zt * se) << "no power against a 2% error: +- " << se;
  }
  // The V-cavity ensemble: per-bin V-cavity and Smith models beside the measurement.
  const std::string vc = tmp("vc_g1.json");
  r = run("measure g1 " + tmp("vc.ply") + " --theta 80 --rays 20000 -o " + vc);
  ASSERT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(slurp(vc));
  EXPECT_EQ(j["surface"]["kind"], "vcavity");
  for (const char* k : {"bins_chi2_vcavity", "bins_chi2_smith", "bins_mad_vcavity", "bins_mad_smith"})
    EXPECT_TRUE(j["rows"][0].contains(k)) << k;
  bool has_model = false;
  for (const auto& b : j["rows"][0]["bins"]) has_model = has_model || b.contains("vcavity_numeric");
  EXPECT_TRUE(has_model);
  // D over the whole sphere of a non-heightfield.
  EXPECT_EQ(run("measure ndf " + tmp("pp.ply") + " -o " + tmp("pp_ndf.json")).code, 0);
}

TEST_F(Cli, BadMeshesAndStructuredParametersAreRefused) {
  const std::string bad = tmp("nonmanifold.off"), out = tmp("out.ply"), o = tmp("bad.json");
  std::ofstream(bad) << "OFF\n5 3 0\n0 0 1\n1 0 1\n0 1 1\n0 -1 1\n0 0 2\n3 0 1 2\n3 1 0 3\n3 0 1 4\n";
  expect_usage_error("generate mesh --input " + bad + " -o " + out, out, "non-manifold");
  expect_usage_error("measure g1 " + bad + " -o " + o, o, "non-manifold");
  const std::string open = tmp("open.off");
  // A box without its top: open where it must be closed.
  std::ofstream(open) << "OFF\n8 8 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
                         "3 1 2 6\n3 1 6 5\n3 0 4 7\n3 0 7 3\n3 3 7 6\n3 3 6 2\n3 0 1 5\n3 0 5 4\n";
  expect_usage_error("generate mesh --input " + open + " -o " + out, out, "open mesh");
  expect_usage_error("generate mesh --input " + tmp("none.ply") + " -o " + out, out, "does not exist");
  expect_usage_error("generate box --height 0 -o " + out, out, "--height");
  expect_usage_error("generate box -o " + tmp("box.exr"), tmp("box.exr"), ".ply");
  expect_usage_error("generate square-wave --duty 1.5 -o " + out, out, "--duty");
  expect_usage_error("generate vgroove --facet-angle 95 -o " + out, out, "--facet-angle");
  expect_usage_error("generate parallelepiped --matrix 1,0,0,0,1,0,0.5,0,1 -o " + out, out, "--matrix");
  expect_usage_error("generate vcavity --ndf phong -o " + out, out, "--ndf");
  expect_usage_error("measure g1 " + surface_ + " --theta 120 -o " + o, o, "heightfield");
}

// A V-cavity ensemble is measured groove by groove, each groove traced on its own as an infinite
// periodic V-groove [Heitz14, Sec. 6.1], where the V-cavity model ([Heitz14, eq. 24 and Sec. 6], and eq. 13 with it
// for the VNDF) is exact: measure g2 and measure vndf agree with it within their ray-count
// errors, and give the library's groove-by-groove estimates. Power: the stored strips traced
// together (grooves masking each other through the strips' open ends), at the same seed and
// sample counts, are rejected by the same tests.
TEST_F(Cli, MeasureG2AndVndfTraceAVcavityEnsembleGrooveByGroove) {
  using namespace microsim;
  const std::string vc = tmp("vc512.ply"), g2 = tmp("vc_g2.json"), vndf = tmp("vc_vndf.json");
  ASSERT_EQ(run("generate vcavity --grooves 512 -q -o " + vc).code, 0);
  Result r = run("measure g2 " + vc + " --theta-o 80 --theta-i 70 --phi-i 180 --rays 100000 -q -o " + g2);
  ASSERT_EQ(r.code, 0) << r.err;
  r = run("measure vndf " + vc + " --theta 80 --rays 100000 --sampler-samples 0 -q -o " + vndf);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto jg = nlohmann::json::parse(slurp(g2)), jv = nlohmann::json::parse(slurp(vndf));
  EXPECT_TRUE(jg.value("groove_by_groove", false));
  EXPECT_TRUE(jv.value("groove_by_groove", false));
  const Microsurface s = load_surface(vc);
  ASSERT_TRUE(is_vcavity(s));
  const Vec3 vo = direction_from_angles(rad(80), 0), vi = direction_from_angles(rad(70), rad(180));
  const double zt = sidak_z(0.01, 1);

  // G2 against the V-cavity model, with the ray-count error (the model is the facets' own).
  const nlohmann::json& row = jg["rows"][0];
  const double z = row["z_vcavity"].get<double>();
  std::printf("g2 o 80/0 i 70/180: %.5f +- %.5f, V-cavity %.5f, z %.2f\n", row["g2"].get<double>(),
              row["g2_stderr"].get<double>(), row["vcavity"].get<double>(), z);
  EXPECT_LT(std::abs(z), zt);
  G2Options go;
  go.rays = 100000;
  EXPECT_EQ(row["g2"].get<double>(), measure_g2(vcavity_grooves(s, "test", GrooveFrames::StoredNormalNormalized), vo, vi, go).g2().mean);
  Tracer joint(s);
  const G2Result together = measure_g2(joint, vo, vi, go);
  const double z_together = (together.g2().mean - together.vcavity) / together.g2().stderr_;
  std::printf("strips traced together: %.5f +- %.5f, z %.2f\n", together.g2().mean, together.g2().stderr_,
              z_together);
  EXPECT_GT(std::abs(z_together), zt);

  // The VNDF histogram against the V-cavity model's bin probabilities, recomputed here from the
  // record's bin counts.
  const nlohmann::json& vrow = jv["rows"][0];
  VndfOptions opt;
  opt.rays = 100000;
  opt.theta_bins = jv["parameters"]["normal_bins"]["theta"].get<int>();
  opt.phi_bins = jv["parameters"]["normal_bins"]["phi"].get<int>();
  const DirectionBinning binning = vndf_binning(opt);
  ASSERT_EQ(vrow["bins"].size(), static_cast<std::size_t>(binning.size()));
  std::vector<std::uint64_t> hits;
  for (const auto& b : vrow["bins"]) hits.push_back(b["hits"].get<std::uint64_t>());
  const std::vector<double> p = vcavity_vndf_probabilities(s, vo, binning);
  const GofResult grooves = histogram_gof(hits, vrow["hits"].get<std::uint64_t>(), p, opt.family_alpha);
  const VndfResult joint_vndf = measure_vndf(joint, vo, opt);
  const GofResult strips = histogram_gof(joint_vndf.bin_hits, joint_vndf.hits, p, opt.family_alpha);
  std::printf("vndf theta 80 vs V-cavity: groove by groove p %.3g, strips together p %.3g\n",
              grooves.p_value, strips.p_value);
  EXPECT_GT(grooves.p_value, 1e-3);
  EXPECT_LT(strips.p_value, 1e-6);
  EXPECT_FALSE(strips.pass());
  ASSERT_TRUE(vrow.contains("p_value_vcavity") && vrow.contains("pass_vcavity"));
  EXPECT_DOUBLE_EQ(vrow["p_value_vcavity"].get<double>(), grooves.p_value);
  EXPECT_TRUE(vrow["pass_vcavity"].get<bool>());
}

// The VNDF table keeps its columns for any value. An ensemble's z divides by the spread between
// its surfaces: two ellipsoids whose alphas differ by 2e-7 (Embree's float vertices move by about
// an ulp) give almost the same hits, and at theta 20 a max|z| above 10^5 (measured 1.3e6) that
// no longer fits "%.2f" in its 9 columns (it ran into the column before it); the sidak column
// (3.3e4 here) likewise. Every row's cells end where the header's do, a space before each.
TEST_F(Cli, VndfTableColumnsStayAlignedForLargeValues) {
  const std::string a = tmp("ell_a.ply"), b = tmp("ell_b.ply"), out = tmp("ell_vndf.json");
  ASSERT_EQ(run("-q generate ellipsoid --alpha 0.5 --rings 16 --segments 32 -o " + a).code, 0);
  ASSERT_EQ(run("-q generate ellipsoid --alpha 0.5000001 --rings 16 --segments 32 -o " + b).code, 0);
  const Result r = run("measure vndf " + a + " " + b + " --theta 0,20 --rays 1000000 --sampler-samples 0 -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(out));
  ASSERT_GE(j["rows"][1]["max_abs_z"].get<double>(), 1e5) << "no large value to show";
  std::istringstream table(r.out);
  std::string header, line;
  while (std::getline(table, header) && header.find("max|z|") == std::string::npos) {
  }
  ASSERT_FALSE(header.empty()) << r.out;
  const int widths[] = {7, 6, 11, 10, 9, 8, 9, 14, 14};
  int rows = 0;
  for (; std::getline(table, line) && line.rfind("rays lost", 0) != 0; ++rows) {
    ASSERT_EQ(line.size(), header.size()) << header << "\n" << line;
    int end = 0;
    for (int w : widths) {
      EXPECT_EQ(line[end], ' ') << "no space before the cell ending at " << end + w << "\n" << header << "\n" << line;
      end += w;
      EXPECT_NE(line[end - 1], ' ') << header << "\n" << line;
    }
  }
  EXPECT_EQ(rows, 2);
}
