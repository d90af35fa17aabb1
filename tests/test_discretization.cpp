// Cells per correlation length and correlation lengths per tile: stated by the Gaussian
// generators, recovered from older descriptions, printed by `info`, and turned into an info row
// of `validate` when a surface is coarser than the study's converged level.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <tuple>

#include "cli_helpers.hpp"
#include "microsim/surface/discretization.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/validate/validate.hpp"

using namespace microsim;

namespace {

GaussianParams params(int n, double ell, double ax, double ay) {
  GaussianParams p;
  p.resolution = n;
  p.size = 2.0;
  p.correlation_length = ell;
  p.alpha_x = ax;
  p.alpha_y = ay;
  p.seed = 3;
  return p;
}

}  // namespace

TEST(Discretization, GaussianDescriptionStatesTheGrid) {
  // 96 cells over a tile of 2: dx = 1/48; l = 0.25 is 12 cells, 8 lengths per tile.
  Microsurface s = generate_gaussian(params(96, 0.25, 0.5, 0.5));
  EXPECT_DOUBLE_EQ(s.description["cells_per_correlation_length"].get<double>(), 12.0);
  EXPECT_DOUBLE_EQ(s.description["correlation_lengths_per_tile"].get<double>(), 8.0);
  auto d = discretization_of(s.description);
  ASSERT_TRUE(d);
  EXPECT_DOUBLE_EQ(d->cells_per_correlation_length, 12.0);
  // Default length on a small tile: 16 correlation lengths per tile, here 4 cells.
  GaussianParams p = params(64, 0.0, 1.0, 1.0);
  Microsurface t = generate_gaussian(p);
  EXPECT_DOUBLE_EQ(t.description["cells_per_correlation_length"].get<double>(), 4.0);
  EXPECT_DOUBLE_EQ(t.description["correlation_lengths_per_tile"].get<double>(), 16.0);
}

TEST(Discretization, DefaultTileIsAtTheConvergedLevelOfEveryGroup) {
  // 16 cells per l, at least 16 l per tile and 4 cells: the default 1024^2 tile is the study's
  // recommended level (16 cells, 64 l), smaller tiles keep 16 l per tile down to 4 cells.
  auto level = [](int n, double size) {
    const double ell = default_correlation_length(n, size);
    return std::pair{ell / (size / n), size / ell};
  };
  const std::vector<std::tuple<int, double, double>> expected = {
      {1024, 16, 64}, {2048, 16, 128}, {512, 16, 32}, {256, 16, 16}, {128, 8, 16}, {64, 4, 16}, {16, 4, 4}};
  for (const auto& [n, cells, tiles] : expected) {
    const auto [c, t] = level(n, 2.0);
    EXPECT_NEAR(c, cells, 1e-12) << n;
    EXPECT_NEAR(t, tiles, 1e-12) << n;
  }
  const GaussianParams defaults;
  Microsurface s = generate_gaussian(params(defaults.resolution, 0.0, 1.0, 1.0));
  const auto d = discretization_of(s.description);
  ASSERT_TRUE(d);
  EXPECT_DOUBLE_EQ(d->cells_per_correlation_length, 16.0);
  EXPECT_DOUBLE_EQ(d->correlation_lengths_per_tile, 64.0);
  for (const auto& l : converged_levels()) {
    EXPECT_GE(d->cells_per_correlation_length, l.cells_per_correlation_length) << l.quantity;
    EXPECT_GE(d->correlation_lengths_per_tile, l.correlation_lengths_per_tile) << l.quantity;
  }
  // A coarser default (8 cells per l) would be flagged for G2 and the mirror albedos.
  EXPECT_LT(8.0, converged_level("bsdf_albedo")->cells_per_correlation_length);
  EXPECT_LT(8.0, converged_level("g2")->cells_per_correlation_length);
}

TEST(Discretization, AnisotropicUsesShortLengthForCellsAndLongForTile) {
  Microsurface s = generate_gaussian(params(128, 0.125, 0.8, 0.4));
  const double lx = s.description["correlation_length_x"].get<double>();
  const double ly = s.description["correlation_length_y"].get<double>();
  ASSERT_GT(ly, lx);  // the smoother axis has the longer length
  const double dx = 2.0 / 128;
  EXPECT_DOUBLE_EQ(s.description["cells_per_correlation_length"].get<double>(), lx / dx);
  EXPECT_DOUBLE_EQ(s.description["correlation_lengths_per_tile"].get<double>(), 2.0 / ly);
  EXPECT_LT(s.description["correlation_lengths_per_tile"].get<double>(), 16.0);
}

TEST(Discretization, GgxDescriptionStatesTheGrid) {
  GaussianGgxParams p;
  p.resolution = 128;
  p.size = 1.0;
  p.correlation_length = 1.0 / 16;
  p.alpha_x = p.alpha_y = 0.5;
  Microsurface s = generate_gaussian_ggx(p);
  EXPECT_DOUBLE_EQ(s.description["cells_per_correlation_length"].get<double>(), 8.0);
  EXPECT_DOUBLE_EQ(s.description["correlation_lengths_per_tile"].get<double>(), 16.0);
}

TEST(Discretization, DerivedFromOlderDescriptionsAndAbsentElsewhere) {
  Json old = {{"kind", "gaussian"}, {"resolution", 1024}, {"size", 1.0},
              {"correlation_length", 0.00390625}, {"correlation_length_x", 0.00390625},
              {"correlation_length_y", 0.00390625}};
  auto d = discretization_of(old);
  ASSERT_TRUE(d);
  EXPECT_DOUBLE_EQ(d->cells_per_correlation_length, 4.0);
  EXPECT_DOUBLE_EQ(d->correlation_lengths_per_tile, 256.0);
  EXPECT_FALSE(discretization_of(Json{{"kind", "box"}}));
  EXPECT_FALSE(discretization_of(Json{{"kind", "gaussian"}}));  // no parameters: nothing to say
  EXPECT_FALSE(discretization_of(Json()));
}

TEST(Discretization, ConvergedLevelsCoverTheValidateChecks) {
  for (const auto& c : validation::checks()) {
    if (c.name == "d_identities") continue;  // exact identities: any grid
    auto l = converged_level(c.name);
    ASSERT_TRUE(l) << c.name;
    EXPECT_GE(l->cells_per_correlation_length, 1.0);
    EXPECT_GE(l->correlation_lengths_per_tile, 4.0);
  }
  EXPECT_FALSE(converged_level("no_such_check"));
}

namespace {
std::vector<validation::Row> discretization_rows(const Microsurface& s) {
  validation::SurfaceSet set;
  set.name = "tile";
  set.labels = {"seed 3"};
  set.surfaces = {s};
  set.options.checks = {"d_identities", "d_nominal"};
  validation::Result r = validation::run({set}, 0.01);
  std::vector<validation::Row> rows;
  for (const auto& row : r.rows)
    if (row.model_name == "converged_level") rows.push_back(row);
  return rows;
}
}  // namespace

TEST(Discretization, ValidateAddsAnInfoRowOnlyForCoarseSurfaces) {
  const auto level = *converged_level("d_nominal");
  // Coarse: 2 cells per l on a tile of converged size.
  const double t = level.correlation_lengths_per_tile;
  const int n_coarse = static_cast<int>(2 * t);
  auto coarse = discretization_rows(generate_gaussian(params(n_coarse, 2.0 / t, 0.5, 0.5)));
  ASSERT_EQ(coarse.size(), 1u);
  EXPECT_EQ(coarse[0].kind, validation::Kind::Info);
  EXPECT_EQ(coarse[0].verdict, "measured");
  EXPECT_EQ(coarse[0].quantity, "cells_per_correlation_length");
  EXPECT_DOUBLE_EQ(coarse[0].measured, 2.0);
  EXPECT_DOUBLE_EQ(*coarse[0].model, level.cells_per_correlation_length);
  // Converged grid, tile too small: the row names the tile.
  const int c = static_cast<int>(level.cells_per_correlation_length);
  auto small = discretization_rows(generate_gaussian(params(c * 8, 0.25, 0.5, 0.5)));
  ASSERT_EQ(small.size(), 1u);
  EXPECT_EQ(small[0].quantity, "correlation_lengths_per_tile");
  EXPECT_DOUBLE_EQ(small[0].measured, 8.0);
  // At the converged level: no row.
  const int n = static_cast<int>(c * t);
  EXPECT_TRUE(discretization_rows(generate_gaussian(params(n, 2.0 / t, 0.5, 0.5))).empty());
  // Surfaces without a correlation length: no row.
  EXPECT_TRUE(discretization_rows(generate_flat(FlatParams{})).empty());
}

TEST(Discretization, InfoPrintsAndRecordsTheGrid) {
  const std::string f = microsim::testing::temp_path("disc", "tile.exr");
  const std::string j = microsim::testing::temp_path("disc", "info.json");
  auto g = microsim::testing::run_microsim("generate gaussian --resolution 64 --size 1 --alpha 0.5 "
                                           "--correlation-length 0.03125 -o " + f);
  ASSERT_EQ(g.code, 0) << g.err;
  auto r = microsim::testing::run_microsim("info " + f + " --json " + j);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("2 cells per correlation length l, 32 correlation lengths per tile"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("coarser than the converged level"), std::string::npos) << r.out;
  auto rec = nlohmann::json::parse(microsim::testing::slurp(j));
  EXPECT_DOUBLE_EQ(rec["surface"]["cells_per_correlation_length"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(rec["discretization"]["correlation_lengths_per_tile"].get<double>(), 32.0);
  EXPECT_FALSE(rec["discretization"]["coarser_than_converged"].empty());
}

namespace {
// Cells per l and l per tile of a preset (resolution, size, correlation-length).
std::pair<double, double> preset_level(const std::string& name) {
  std::ifstream f(std::string(MICROSIM_SOURCE_DIR) + "/surfaces/" + name);
  EXPECT_TRUE(f.good()) << name;
  double resolution = 0, size = 0, ell = 0;
  for (std::string line; std::getline(f, line);) {
    if (line.empty() || line[0] == '#') continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    std::string key = line.substr(0, eq);
    key.erase(key.find_last_not_of(' ') + 1);
    const double v = std::stod(line.substr(eq + 1));
    if (key == "resolution") resolution = v;
    if (key == "size") size = v;
    if (key == "correlation-length") ell = v;
  }
  EXPECT_GT(resolution * size * ell, 0) << name;
  return {ell / (size / resolution), size / ell};
}
}  // namespace

TEST(Discretization, PresetsMatchTheConvergedLevelsTheyClaim) {
  // The default presets, beckmann-1.0-converged (16 cells per l) and beckmann-1.0-fine (32, for
  // the few quantities that still move at 16): every group.
  for (const char* preset : {"beckmann-0.5.toml", "gaussian-ggx.toml", "beckmann-1.0-converged.toml",
                             "beckmann-1.0-fine.toml"}) {
    const auto [cells, tiles] = preset_level(preset);
    for (const auto& l : converged_levels()) {
      EXPECT_GE(cells, l.cells_per_correlation_length) << preset << " " << l.quantity;
      EXPECT_GE(tiles, l.correlation_lengths_per_tile) << preset << " " << l.quantity;
    }
  }
  EXPECT_GT(preset_level("beckmann-1.0-fine.toml").first, preset_level("beckmann-1.0-converged.toml").first);
}

TEST(Discretization, DefaultSuiteRunsEveryCheckOnConvergedTiles) {
  // The report's suite: each Gaussian entry, generated as `validate --suite` does, is at or above
  // the converged level of every check it runs (its rows describe the continuous surface and it
  // gets no info row). 4-cell tiles, as the suite had before, are not.
  namespace mv = microsim::validation;
  const std::string dir = std::string(MICROSIM_SOURCE_DIR) + "/surfaces/suites";
  const mv::Suite suite = mv::load_suite(mv::find_suite("default", {dir}));
  int gaussian = 0;
  for (const mv::SuiteEntry& e : suite.entries) {
    if (e.generate != "gaussian" && e.generate != "gaussian-ggx") continue;
    ++gaussian;
    std::string cmd = "-q generate " + e.generate;
    if (!e.preset.empty()) cmd += " --config " + e.preset;
    for (const auto& [key, value] : e.args) cmd += " --" + key + " " + value;
    if (!e.seeds.empty()) cmd += " --seed " + std::to_string(e.seeds.front());
    const std::string f = microsim::testing::temp_path("disc", e.name + ".exr");
    const auto r = microsim::testing::run_microsim(cmd + " -o " + f);
    ASSERT_EQ(r.code, 0) << cmd << "\n" << r.err;
    const auto d = discretization_of(load_surface(f).description);
    ASSERT_TRUE(d) << e.name;
    std::vector<std::string> checks = e.options.checks;
    if (checks.empty())
      for (const auto& l : converged_levels()) checks.push_back(l.quantity);
    for (const std::string& c : checks) {
      const auto l = converged_level(c);
      if (!l) continue;
      EXPECT_GE(d->cells_per_correlation_length, l->cells_per_correlation_length) << e.name << " " << c;
      EXPECT_GE(d->correlation_lengths_per_tile, l->correlation_lengths_per_tile) << e.name << " " << c;
    }
  }
  EXPECT_GE(gaussian, 4);
  // Power: the suite's former tile (512^2, l = 4 cells) is below the G1 and D levels.
  const auto old = discretization_of(Json{{"kind", "gaussian"}, {"resolution", 512}, {"size", 1.0},
                                          {"correlation_length", 0.0078125}});
  ASSERT_TRUE(old);
  EXPECT_LT(old->cells_per_correlation_length, converged_level("g1")->cells_per_correlation_length);
}
