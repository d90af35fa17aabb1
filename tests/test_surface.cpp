// Surface layer: Gaussian generator statistics, [GeomBSDF24, eq. 1b/1c], file round trips, bad input.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include <OpenMesh/Core/System/omstream.hh>

#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/mesh_check.hpp"
#include "microsim/surface/surface_io.hpp"
#include "cli_helpers.hpp"  // removes this program's temporary files at exit
#include "test_helpers.hpp"

using namespace microsim;

namespace {
GaussianParams small(double alpha, std::uint64_t seed, int res = 128) {
  GaussianParams p;
  p.resolution = res;
  p.correlation_length = 4.0 / res;  // 4 cells per l
  p.alpha_x = p.alpha_y = alpha;
  p.seed = seed;
  return p;
}
std::string tmp(const std::string& name) {
  return ::testing::TempDir() + "microsim_" + std::to_string(getpid()) + "_" + name;
}
}  // namespace

TEST(Gaussian, SameSeedSameHeightsOtherSeedOtherHeights) {
  Microsurface a = generate_gaussian(small(0.5, 7)), b = generate_gaussian(small(0.5, 7)),
               c = generate_gaussian(small(0.5, 8));
  EXPECT_EQ(a.heights(), b.heights());
  EXPECT_NE(a.heights(), c.heights());
}

TEST(Gaussian, Eq1bAnd1cHoldExactlyOnPeriodicTile) {
  // [GeomBSDF24, eq. 1b]: sum_f m_f A_f / A = n;  eq. 1c: sum_f (n.m_f) A_f / A = 1.
  Microsurface s = generate_gaussian(small(0.8, 3));
  FacetSums f = facet_sums(s);
  EXPECT_NEAR(f.sum_area_normal.x(), 0.0, 1e-9);
  EXPECT_NEAR(f.sum_area_normal.y(), 0.0, 1e-9);
  EXPECT_NEAR(f.sum_area_normal.z(), 1.0, 1e-9);
  EXPECT_NEAR(f.sum_area_cos, 1.0, 1e-9);
  EXPECT_GT(f.total_area, 1.05);  // a rough surface has more area than its macrosurface
}

TEST(Gaussian, SlopeVarianceMatchesAlphaOverAnEnsemble) {
  // E[slope variance] = alpha^2/2 per axis ([Heitz14, Sec. 3.3] Beckmann); test the ensemble mean of
  // 8 tiles against its own standard error, and that a wrong alpha would be detected.
  const double alpha = 0.6;
  std::vector<double> vx;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    FacetSums f = facet_sums(generate_gaussian(small(alpha, seed)));
    vx.push_back(f.slope_var_x);
    vx.push_back(f.slope_var_y);
  }
  double mean = 0, var = 0;
  for (double x : vx) mean += x / vx.size();
  for (double x : vx) var += (x - mean) * (x - mean) / (vx.size() - 1);
  double se = std::sqrt(var / vx.size());
  EXPECT_LT(std::abs(mean - alpha * alpha / 2) / se, 4.0) << "mean " << mean << " se " << se;
  EXPECT_GT(std::abs(mean - 1.1 * 1.1 * alpha * alpha / 2) / se, 4.0);  // power of the test
}

TEST(Gaussian, AnisotropicSlopeVariancesFollowAlphaXAndAlphaY) {
  // The expected variance of the traced finite-difference slopes is exact on the grid for both
  // axes (not only x), and an ensemble of tiles reproduces it within its standard error.
  GaussianParams p = small(0.3, 5, 256);
  p.alpha_y = 0.6;
  std::vector<double> vx, vy;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    p.seed = seed;
    Microsurface s = generate_gaussian(p);
    EXPECT_NEAR(s.description["expected_slope_var_y"].get<double>(), 0.18, 1e-9);
    FacetSums f = facet_sums(s);
    vx.push_back(f.slope_var_x);
    vy.push_back(f.slope_var_y);
  }
  auto z = [](const std::vector<double>& v, double expected) {
    double mean = 0, var = 0;
    for (double x : v) mean += x / v.size();
    for (double x : v) var += (x - mean) * (x - mean) / (v.size() - 1);
    return (mean - expected) / std::sqrt(var / v.size());
  };
  EXPECT_LT(std::abs(z(vx, 0.045)), 4.0);
  EXPECT_LT(std::abs(z(vy, 0.18)), 4.0);
  EXPECT_GT(std::abs(z(vy, 0.95 * 0.18)), 4.0);  // a 5% shortfall (the old bug) is detected
}

TEST(Gaussian, TileIsPeriodic) {
  Microsurface s = generate_gaussian(small(0.5, 2, 64));
  // grid_point past the border is the periodic copy, shifted by the tile size.
  Vec3 a = s.grid_point(0, 5), b = s.grid_point(64, 5);
  EXPECT_DOUBLE_EQ(a.z(), b.z());
  EXPECT_DOUBLE_EQ(b.x() - a.x(), 1.0);
}

TEST(Gaussian, HeightWrapsAnyIndex) {
  // height(i, j) is the periodic copy for any index, negative or several tiles away; the
  // in-tile shortcut must give the same element as the plain double modulo.
  const Microsurface s = generate_gaussian(small(0.5, 2, 64));
  auto wrap = [](long i, long n) { return ((i % n) + n) % n; };
  const long nx = s.nx(), ny = s.ny();
  for (long j = -2 * ny - 1; j <= 2 * ny + 1; j += 7)
    for (long i = -3 * nx - 2; i <= 3 * nx + 2; ++i)
      ASSERT_EQ(s.height(i, j), s.heights()[static_cast<std::size_t>(wrap(j, ny) * nx + wrap(i, nx))])
          << i << " " << j;
}

TEST(Gaussian, RejectsBadParameters) {
  GaussianParams p;
  p.alpha_x = 0;
  EXPECT_THROW(validate(p), UsageError);
  p = GaussianParams{};
  p.alpha_y = -0.1;
  EXPECT_THROW(validate(p), UsageError);
  p = GaussianParams{};
  p.resolution = 0;
  EXPECT_THROW(validate(p), UsageError);
  p = GaussianParams{};
  p.resolution = 50000;  // ~47 GiB at 20 bytes per cell: refused from the estimate, before allocating
  EXPECT_THROW(validate(p), UsageError);
  EXPECT_GT(gaussian_memory_estimate(50000), 24.0 * (1 << 30));
}

TEST(SurfaceIo, ExrRoundTripKeepsHeightsDescriptionAndNominal) {
  Microsurface s = generate_gaussian(small(0.4, 11, 32));
  std::string path = tmp("rt.exr");
  save_surface(s, path);
  Microsurface t = load_surface(path);
  EXPECT_EQ(s.heights(), t.heights());
  EXPECT_EQ(s.description, t.description);
  ASSERT_TRUE(t.nominal.has_value());
  EXPECT_DOUBLE_EQ(t.nominal->alpha_x, 0.4);
  EXPECT_DOUBLE_EQ(t.macro().area, 1.0);
  std::remove(path.c_str());
}

TEST(SurfaceIo, MeshExportHasTheSameFacets) {
  Microsurface s = generate_gaussian(small(0.4, 12, 16));
  Microsurface m = heightfield_to_mesh(s);
  ASSERT_EQ(m.num_facets(), s.num_facets());
  for (std::size_t k = 0; k < s.num_facets(); ++k) {
    EXPECT_NEAR((m.facet(k).normal() - s.facet(k).normal()).norm(), 0.0, 1e-6);
    EXPECT_NEAR(m.facet(k).area(), s.facet(k).area(), 1e-6 * s.facet(k).area());
  }
  for (const char* ext : {"ply", "obj", "off"}) {
    std::string path = tmp(std::string("rt.") + ext);
    save_surface(s, path);
    Microsurface t = load_surface(path);
    EXPECT_EQ(t.kind(), Microsurface::Kind::Mesh);
    ASSERT_EQ(t.num_facets(), s.num_facets()) << ext;
    EXPECT_TRUE(t.macro().periodic) << ext;
    EXPECT_EQ(t.description, s.description) << ext;
    FacetSums f = facet_sums(t), g = facet_sums(s);
    EXPECT_NEAR(f.total_area, g.total_area, 1e-5);
    std::remove(path.c_str());
    std::remove((path + ".json").c_str());
  }
}

// Loading a mesh captures OpenMesh's messages only while it reads: afterwards omerr reaches its
// own targets again (std::cerr) and the OpenMesh streams have their buffers back.
TEST(SurfaceIo, MeshLoadRestoresOpenMeshStreams) {
  const std::string obj = tmp("complex-edge.obj");
  {
    std::ofstream f(obj);  // three faces on edge 1-2: OpenMesh reports a complex edge on omerr
    f << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n";
  }
  omerr().enable();
  std::streambuf* const err = omerr().rdbuf();
  std::streambuf* const log = omlog().rdbuf();
  EXPECT_THROW(load_surface(obj), UsageError);
  EXPECT_EQ(omerr().rdbuf(), err);
  EXPECT_EQ(omlog().rdbuf(), log);
  std::ostringstream seen;
  std::streambuf* const cerr = std::cerr.rdbuf(seen.rdbuf());
  omerr() << "after the load" << std::endl;
  std::cerr.rdbuf(cerr);
  EXPECT_NE(seen.str().find("after the load"), std::string::npos);
  std::remove(obj.c_str());
}

// A PLY header with a property before any element crashed OpenMesh's reader (SEGV); it is a
// usage error now. The same body with the element declared first loads.
TEST(SurfaceIo, PlyPropertyBeforeElementIsRefused) {
  const std::string body =
      "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const std::string bad = tmp("property-first.ply");
  std::ofstream(bad) << "ply\nformat ascii 1.0\ncomment x element\n" << body;
  try {
    load_surface(bad);
    ADD_FAILURE() << "accepted";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("a property before any element"), std::string::npos) << e.what();
  }
  const std::string good = tmp("element-first.ply");
  std::ofstream(good) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                         "property float z\nelement face 1\n" << body;
  std::vector<Eigen::Vector3f> v;
  std::vector<std::array<std::uint32_t, 3>> t;
  read_mesh_file(good, v, t);
  EXPECT_EQ(v.size(), 3u);
  EXPECT_EQ(t.size(), 1u);
  std::remove(bad.c_str());
  std::remove(good.c_str());
}

TEST(SurfaceIo, MissingCorruptAndUnknownFilesAreUsageErrors) {
  EXPECT_THROW(load_surface(tmp("does-not-exist.exr")), UsageError);
  std::string bad = tmp("corrupt.exr");
  {
    std::ofstream f(bad);
    f << "this is not an EXR file";
  }
  EXPECT_THROW(load_surface(bad), UsageError);
  std::string badply = tmp("corrupt.ply");
  {
    std::ofstream f(badply);
    f << "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n0 0\n";
  }
  EXPECT_THROW(load_surface(badply), UsageError);
  std::string txt = tmp("surface.txt");
  {
    std::ofstream f(txt);
    f << "x";
  }
  EXPECT_THROW(load_surface(txt), UsageError);
  for (const auto& p : {bad, badply, txt}) std::remove(p.c_str());
}
