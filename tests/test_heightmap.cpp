// Measured heightmaps: reading images and text grids, detrending, filling missing heights, the
// metrology parameters on surfaces where they are known exactly, and round trips of a generated
// tile through plain EXR, 16-bit PNG and CSV that must measure like the original.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <fstream>
#include <random>

#include "cli_helpers.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/ndf_measure.hpp"
#include "microsim/surface/discretization.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/heightmap_import.hpp"
#include "microsim/surface/metrology.hpp"
#include "microsim/surface/surface_io.hpp"

using namespace microsim;
using microsim::testing::Result;
using microsim::testing::exists;
using microsim::testing::lines;
using microsim::testing::run_microsim;

namespace {
std::string tmp(const std::string& name) { return microsim::testing::temp_path("hm", name); }

HeightGridView view(const std::vector<float>& z, int nx, int ny, double dx, double dy, bool periodic) {
  HeightGridView g;
  g.nx = nx;
  g.ny = ny;
  g.dx = dx;
  g.dy = dy;
  g.z = &z;
  g.periodic = periodic;
  return g;
}

// A single-channel image written through OpenImageIO (the formats instruments export).
void write_image(const std::string& path, int w, int h, const std::string& channel,
                 OIIO::TypeDesc type, const void* pixels, OIIO::TypeDesc pixel_type) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << path;
  OIIO::ImageSpec spec(w, h, 1, type);
  spec.channelnames = {channel};
  ASSERT_TRUE(out->open(path, spec));
  ASSERT_TRUE(out->write_image(pixel_type, pixels));
  out->close();
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
}

// One line on stderr naming `what`, exit code 2, no output file.
void expect_refused(const std::string& args, const std::string& out, const std::string& what) {
  Result r = run_microsim(args);
  EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << "'" << what << "' not in: " << r.err;
  EXPECT_FALSE(exists(out)) << out;
}

GaussianParams small_tile(std::uint64_t seed = 3) {
  GaussianParams p;
  p.resolution = 64;
  p.alpha_x = p.alpha_y = 0.5;
  p.seed = seed;
  return p;
}
}  // namespace

// ---- metrology on surfaces where every parameter is known exactly ----

TEST(Metrology, SinusoidHeightsSlopesAndCorrelationLength) {
  // z = A sin(2 pi x / L), one period over N cells: Sq = A / sqrt 2 exactly on the grid;
  // Sa = (2 / N) cot(pi / N) A (the grid sum of |sin|; -> 2A/pi); the facet slope is the forward
  // difference, RMS sqrt 2 A sin(pi / N) / dx; the ACF is cos(2 pi tau_x / L), which falls to
  // 0.2 at tau = L acos(0.2) / (2 pi) along x and never along y.
  const int N = 64;
  const double A = 0.05, L = 2.0, dx = L / N;
  std::vector<float> z(N * N);
  for (int j = 0; j < N; ++j)
    for (int i = 0; i < N; ++i) z[j * N + i] = static_cast<float>(A * std::sin(2 * kPi * i / N));
  Metrology m = measure_metrology(view(z, N, N, dx, dx, true));
  ASSERT_TRUE(m.textured);
  EXPECT_NEAR(m.sq, A / std::sqrt(2.0), 1e-6 * A);
  EXPECT_NEAR(m.sa, 2.0 / N / std::tan(kPi / N) * A, 1e-6 * A);
  EXPECT_NEAR(m.sa, 2 * A / kPi, 1e-3 * A);  // the continuous value, to O(1/N^2)
  const double sdq = std::sqrt(2.0) * A * std::sin(kPi / N) / dx;
  EXPECT_NEAR(m.slopes.sdq, sdq, 1e-5 * sdq);
  EXPECT_NEAR(m.slopes.beckmann_alpha_x, std::sqrt(2.0) * sdq, 1e-5 * sdq);
  EXPECT_EQ(m.slopes.beckmann_alpha_y, 0.0);
  EXPECT_NEAR(m.skewness, 0.0, 1e-5);
  EXPECT_NEAR(m.kurtosis, 1.5, 1e-5);  // of a sine
  const double sal = L * std::acos(0.2) / (2 * kPi);
  EXPECT_NEAR(m.acf.sal, sal, 2e-3 * sal);  // bilinear ACF between integer lags
  EXPECT_FALSE(m.acf.decayed_in_every_direction);
  EXPECT_NEAR(m.cells_per_correlation_length, sal / dx, 2e-3 * sal / dx);
  // Power: a wrong amplitude or period moves each parameter far beyond these tolerances.
  for (auto& v : z) v *= 1.01f;
  EXPECT_GT(std::abs(measure_metrology(view(z, N, N, dx, dx, true)).sq - A / std::sqrt(2.0)), 1e-3 * A);
}

TEST(Metrology, TwoCosinesAnisotropyAgainstTheExactAcf) {
  // z = cos(2 pi x / L) + cos(2 pi y / L): ACF = (cos(2 pi tx / L) + cos(2 pi ty / L)) / 2.
  // Independent route: the exact ACF along each direction, its first 0.2 crossing by bisection.
  const int N = 64;
  const double L = 1.0, dx = L / N;
  std::vector<float> z(N * N);
  for (int j = 0; j < N; ++j)
    for (int i = 0; i < N; ++i)
      z[j * N + i] = static_cast<float>(std::cos(2 * kPi * i / N) + std::cos(2 * kPi * j / N));
  AcfStats a = acf_stats(view(z, N, N, dx, dx, true));
  double sal = 1e9, longest = 0;
  for (int d = 0; d < 1800; ++d) {
    const double th = kPi * d / 1800, c = std::cos(th), s = std::sin(th);
    auto acf = [&](double r) { return 0.5 * (std::cos(2 * kPi * r * c / L) + std::cos(2 * kPi * r * s / L)); };
    double lo = 0, hi = 0;
    for (double r = 1e-3; r < 0.5 * L; r += 1e-3)
      if (acf(r) <= 0.2) { hi = r; break; } else lo = r;
    for (int it = 0; it < 60; ++it) (acf(0.5 * (lo + hi)) > 0.2 ? lo : hi) = 0.5 * (lo + hi);
    sal = std::min(sal, hi);
    longest = std::max(longest, hi);
  }
  EXPECT_TRUE(a.decayed_in_every_direction);
  EXPECT_NEAR(a.sal, sal, 3e-3 * sal);
  EXPECT_NEAR(a.longest, longest, 3e-3 * longest);
  EXPECT_NEAR(a.str, sal / longest, 5e-3);
  EXPECT_NEAR(a.str, 1.9366 / 2.2143, 5e-3);  // 45 deg vs the axes, solved by hand
}

TEST(Metrology, PlaneWindowSlopesAndConstantMap) {
  // A tilted plane as a window: every facet has the slope (a, b); Sdq = |(a, b)|.
  const int nx = 12, ny = 9;
  const double a = 0.3, b = -0.2, dx = 0.5, dy = 0.25;
  std::vector<float> z(nx * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) z[j * nx + i] = static_cast<float>(a * i * dx + b * j * dy);
  auto sl = facet_slopes(view(z, nx, ny, dx, dy, false));
  ASSERT_EQ(sl.size(), 2u * (nx - 1) * (ny - 1));
  for (const auto& s : sl) {
    EXPECT_NEAR(s[0], a, 1e-5);
    EXPECT_NEAR(s[1], b, 1e-5);
  }
  Metrology m = measure_metrology(view(z, nx, ny, dx, dy, false));
  EXPECT_NEAR(m.slopes.sdq, std::hypot(a, b), 1e-5);
  EXPECT_NEAR(m.slopes.rms_x, 0.0, 1e-5);
  // Periodic wrap of the same plane adds the seam's cliff: the window must not wrap.
  EXPECT_GT(measure_metrology(view(z, nx, ny, dx, dy, true)).slopes.sdq, 2 * std::hypot(a, b));
  std::vector<float> flat(16, 0.25f);
  Metrology c = measure_metrology(view(flat, 4, 4, 1, 1, true));
  EXPECT_FALSE(c.textured);
  EXPECT_EQ(c.sq, 0.0);
}

namespace {
// iid slopes from anisotropic GGX (inverse CDF of the radius q: q^2 = u / (1 - u)) or Beckmann
// (q^2 = -ln(1 - u)), scaled by (ax, ay).
std::vector<std::array<double, 2>> sample_slopes(bool ggx, double ax, double ay, int n, std::uint64_t seed) {
  std::vector<std::array<double, 2>> out;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < n; ++k) {
    const double v = u(rng), phi = 2 * kPi * u(rng);
    const double q = ggx ? std::sqrt(v / (1 - v)) : std::sqrt(-std::log1p(-v));
    out.push_back({ax * q * std::cos(phi), ay * q * std::sin(phi)});
  }
  return out;
}
}  // namespace

TEST(Metrology, GgxMaximumLikelihoodRecoversAlphaWithinItsStandardError) {
  // 8 independent batches: the mean of the batch estimates is within 4 standard errors of the
  // truth, and a 10% wrong alpha is rejected by the same test (power).
  const double ax = 0.3, ay = 0.6;
  std::vector<double> ex, ey;
  for (int b = 0; b < 8; ++b) {
    SlopeStats s = slope_stats(sample_slopes(true, ax, ay, 4000, 100 + b));
    ex.push_back(s.ggx_alpha_x);
    ey.push_back(s.ggx_alpha_y);
  }
  auto mean_se = [](const std::vector<double>& v) {
    double m = 0, q = 0;
    for (double x : v) m += x / v.size();
    for (double x : v) q += (x - m) * (x - m) / (v.size() - 1);
    return std::make_pair(m, std::sqrt(q / v.size()));
  };
  auto [mx, sx] = mean_se(ex);
  auto [my, sy] = mean_se(ey);
  EXPECT_LT(std::abs(mx - ax), 4 * sx) << mx << " +- " << sx;
  EXPECT_LT(std::abs(my - ay), 4 * sy) << my << " +- " << sy;
  EXPECT_GT(std::abs(mx - 1.1 * ax), 4 * sx);
  EXPECT_GT(std::abs(my - 1.1 * ay), 4 * sy);
  // Isotropic samples: the isotropic estimate agrees with the anisotropic ones.
  SlopeStats iso = slope_stats(sample_slopes(true, 0.4, 0.4, 20000, 7));
  EXPECT_NEAR(iso.ggx_alpha, 0.4, 0.02);
  EXPECT_NEAR(iso.ggx_alpha_x, 0.4, 0.02);
}

TEST(Metrology, SlopeHistogramsTellBeckmannFromGgx) {
  SlopeStats b = slope_stats(sample_slopes(false, 0.5, 0.3, 20000, 11));
  EXPECT_NEAR(b.beckmann_alpha_x, 0.5, 0.01);
  EXPECT_NEAR(b.beckmann_alpha_y, 0.3, 0.01);
  EXPECT_EQ(b.beckmann_fit.dof, 17);
  EXPECT_LT(b.beckmann_fit.chi2_per_dof(), 2.5);  // chi^2_17 > 42.5 has p < 0.001
  EXPECT_GT(b.ggx_fit.chi2_per_dof(), 10.0);
  SlopeStats g = slope_stats(sample_slopes(true, 0.5, 0.3, 20000, 12));
  EXPECT_LT(g.ggx_fit.chi2_per_dof(), 2.5);
  EXPECT_GT(g.beckmann_fit.chi2_per_dof(), 10.0);
  // Heights: a Gaussian sample fits, a uniform one does not.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> nd(1.0, 0.2);
  std::uniform_real_distribution<double> ud(0, 1);
  std::vector<double> gh, uh;
  for (int k = 0; k < 20000; ++k) {
    gh.push_back(nd(rng));
    uh.push_back(ud(rng));
  }
  EXPECT_LT(gaussian_height_fit(gh).chi2_per_dof(), 2.5);
  EXPECT_GT(gaussian_height_fit(uh).chi2_per_dof(), 10.0);
}

TEST(Metrology, GeneratedGaussianTileMatchesItsParameters) {
  // The generator's ACF exp(-r^2/l^2) decays to 0.2 at l sqrt(ln 5); its slopes are Beckmann.
  GaussianParams p = small_tile(9);
  p.resolution = 128;
  p.correlation_length = 4.0 / 128;  // 4 cells per l
  Microsurface s = generate_gaussian(p);
  Metrology m = measure_metrology(grid_view(s));
  FacetSums f = facet_sums(s);
  EXPECT_NEAR(m.slopes.beckmann_alpha_x, std::sqrt(2 * f.slope_var_x), 1e-6);
  EXPECT_NEAR(m.slopes.beckmann_alpha_y, std::sqrt(2 * f.slope_var_y), 1e-6);
  EXPECT_NEAR(m.cells_per_gaussian_length, 4.0, 0.6);  // one tile: ~10% spread between tiles
  EXPECT_LT(m.slopes.beckmann_fit.chi2_per_dof(), m.slopes.ggx_fit.chi2_per_dof());
}

// ---- import: detrending, filling, parsing ----

TEST(HeightmapImport, DetrendRemovesAKnownPlaneAndQuadraticExactly) {
  const int nx = 20, ny = 15;
  const double dx = 0.1, dy = 0.2;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> nd(0, 1);
  std::vector<double> r(nx * ny), plane(nx * ny), quad(nx * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x = i * dx, y = j * dy;
      r[j * nx + i] = nd(rng);
      plane[j * nx + i] = 3.0 + 0.7 * x - 1.3 * y;
      quad[j * nx + i] = plane[j * nx + i] + 0.4 * x * x - 0.9 * x * y + 0.25 * y * y;
    }
  std::vector<double> z = plane;
  auto c = detrend(z, nx, ny, dx, dy, Detrend::Plane);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_NEAR(c[0], 3.0, 1e-12);
  EXPECT_NEAR(c[1], 0.7, 1e-12);
  EXPECT_NEAR(c[2], -1.3, 1e-12);
  for (double v : z) EXPECT_NEAR(v, 0.0, 1e-12);
  z = quad;
  c = detrend(z, nx, ny, dx, dy, Detrend::Poly2);
  const double want[6] = {3.0, 0.7, -1.3, 0.4, -0.9, 0.25};
  for (int t = 0; t < 6; ++t) EXPECT_NEAR(c[t], want[t], 1e-10) << t;
  for (double v : z) EXPECT_NEAR(v, 0.0, 1e-11);
  // Linearity: detrending plane + noise leaves exactly what detrending the noise leaves.
  std::vector<double> a = r, b(nx * ny);
  for (int k = 0; k < nx * ny; ++k) b[k] = r[k] + plane[k];
  detrend(a, nx, ny, dx, dy, Detrend::Plane);
  detrend(b, nx, ny, dx, dy, Detrend::Plane);
  for (int k = 0; k < nx * ny; ++k) EXPECT_NEAR(a[k], b[k], 1e-12);
  // Power: removing only the mean leaves the tilt.
  z = plane;
  detrend(z, nx, ny, dx, dy, Detrend::Mean);
  EXPECT_GT(*std::max_element(z.begin(), z.end()), 1.0);
}

TEST(HeightmapImport, HarmonicFillRecoversAHarmonicSurface) {
  // x^2 - y^2 is harmonic for the 4-neighbour Laplacian too: holes are filled exactly.
  const int nx = 16, ny = 12;
  std::vector<double> z(nx * ny), truth(nx * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) truth[j * nx + i] = z[j * nx + i] = 0.01 * (i * i - j * j) + 0.1 * i;
  // Interior holes (a 5-pixel blob and a single one); on the border the rule averages fewer
  // neighbours and is not the Laplace equation.
  const int holes[] = {5 * nx + 5, 5 * nx + 6, 6 * nx + 5, 6 * nx + 6, 7 * nx + 6, 3 * nx + 10};
  for (int h : holes) z[h] = std::nan("");
  EXPECT_EQ(fill_missing(z, nx, ny, false), 6u);
  for (int h : holes) EXPECT_NEAR(z[h], truth[h], 1e-7) << h;
  // A non-harmonic surface (x^2) is not recovered exactly: the rule is the Laplace equation.
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) z[j * nx + i] = 0.01 * i * i;
  const double want = z[5 * nx + 5];
  z[5 * nx + 5] = std::nan("");
  fill_missing(z, nx, ny, false);
  EXPECT_NEAR(z[5 * nx + 5], want + 0.005, 1e-7);  // mean of the 4 neighbours: 0.01 (i^2 + 1/2)
}

TEST(HeightmapImport, TextMatrixAndXyzColumns) {
  const std::string m = tmp("m.csv"), xyz = tmp("p.xyz"), bad = tmp("bad.csv");
  write_text(m, "# exported by an instrument\nz0,z1,z2\n1,2,3\n4,,6\n7,8,9.5\n");
  RawHeightGrid g = read_height_grid(m);
  EXPECT_EQ(g.format, "matrix");
  ASSERT_EQ(g.nx, 3);
  ASSERT_EQ(g.ny, 3);
  EXPECT_EQ(g.z[0], 1);
  EXPECT_TRUE(std::isnan(g.z[4]));
  EXPECT_EQ(g.z[8], 9.5);
  // x,y,z columns, shuffled, one point missing: placed on the grid, spacing from the columns.
  write_text(xyz, "x y z\n0.5 1.0 4\n0.0 0.0 1\n0.5 0.0 2\n1.0 0.0 3\n0.0 1.0 5\n");
  g = read_height_grid(xyz);
  EXPECT_EQ(g.format, "xyz");
  ASSERT_EQ(g.nx, 3);
  ASSERT_EQ(g.ny, 2);
  EXPECT_DOUBLE_EQ(g.dx, 0.5);
  EXPECT_DOUBLE_EQ(g.dy, 1.0);
  EXPECT_EQ(g.z[0], 1);
  EXPECT_EQ(g.z[2], 3);
  EXPECT_EQ(g.z[3], 5);
  EXPECT_EQ(g.z[4], 4);
  EXPECT_TRUE(std::isnan(g.z[5]));
  write_text(bad, "1,2,3\n4,5\n");
  try {
    read_height_grid(bad);
    ADD_FAILURE() << "ragged rows accepted";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find(bad + ":2"), std::string::npos) << e.what();
  }
  write_text(bad, "1,2,3\n4,x5,6\n");
  EXPECT_THROW(read_height_grid(bad), UsageError);
}

// ---- round trips: a generated tile exported plainly and imported back measures the same ----

namespace {
struct Tile {
  Microsurface s;
  std::string path;
  double mean = 0;
};

Tile original_tile() {
  Tile t{generate_gaussian(small_tile()), tmp("orig.exr")};
  save_surface(t.s, t.path);
  for (float h : t.s.heights()) t.mean += h / t.s.heights().size();
  return t;
}

void expect_same_measurements(const Microsurface& a, const Microsurface& b, double d_tol, double g1_tol) {
  NdfOptions no;
  no.n_theta = 18;  // 10 degree rings: few facets lie within a rounding of a ring's edge
  NdfResult da = measure_ndf(a, no), db = measure_ndf(b, no);
  ASSERT_EQ(da.ring_d.size(), db.ring_d.size());
  for (std::size_t k = 0; k < da.ring_d.size(); ++k)
    EXPECT_NEAR(db.ring_d[k], da.ring_d[k], d_tol * (da.ring_d[k] + 1e-3)) << k;
  G1Options go;
  go.rays = 20000;
  go.seed = 7;
  Tracer ta(a), tb(b);
  for (double theta : {40.0, 75.0}) {
    const Vec3 v = direction_from_angles(rad(theta), 0.3);
    G1Result ra = measure_g1(ta, v, go), rb = measure_g1(tb, v, go);
    EXPECT_NEAR(rb.g1_area_sampling().mean, ra.g1_area_sampling().mean, g1_tol) << theta;
    EXPECT_NEAR(rb.lambda_numeric, ra.lambda_numeric, g1_tol) << theta;
  }
}
}  // namespace

TEST(HeightmapRoundTrip, PlainExrChannelY) {
  Tile t = original_tile();
  const std::string plain = tmp("plain.exr"), out = tmp("rt_exr.exr");
  write_image(plain, t.s.nx(), t.s.ny(), "Y", OIIO::TypeDesc::FLOAT, t.s.heights().data(), OIIO::TypeDesc::FLOAT);
  Result r = run_microsim("generate heightmap --input " + plain + " --pixel-size " + std::to_string(1.0 / 64) +
                          " --periodic --detrend none -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  Microsurface b = load_surface(out);
  EXPECT_EQ(b.heights(), t.s.heights());  // float in, float out: bit for bit
  EXPECT_DOUBLE_EQ(b.macro().size_x, t.s.macro().size_x);
  EXPECT_EQ(b.description["channel"], "Y");
  expect_same_measurements(t.s, b, 1e-6, 1e-12);
  // A plain microsim tile without header is the same file with channel Z.
  ExrTable z;
  z.width = t.s.nx();
  z.height = t.s.ny();
  z.channel_names = {"Z"};
  z.channels = {t.s.heights()};
  write_exr(tmp("plainz.exr"), z);
  ASSERT_EQ(run_microsim("generate heightmap --input " + tmp("plainz.exr") + " --pixel-size 0.015625 "
                         "--periodic --detrend none -o " + tmp("rt_z.exr")).code, 0);
  EXPECT_EQ(load_surface(tmp("rt_z.exr")).heights(), t.s.heights());
}

TEST(HeightmapRoundTrip, Png16Bit) {
  Tile t = original_tile();
  const auto& h = t.s.heights();
  const float lo = *std::min_element(h.begin(), h.end()), hi = *std::max_element(h.begin(), h.end());
  const double scale = (hi - lo) / 65535.0;
  std::vector<std::uint16_t> counts;
  for (float v : h) counts.push_back(static_cast<std::uint16_t>(std::lround((v - lo) / scale)));
  const std::string png = tmp("tile.png"), out = tmp("rt_png.exr");
  write_image(png, t.s.nx(), t.s.ny(), "Y", OIIO::TypeDesc::UINT16, counts.data(), OIIO::TypeDesc::UINT16);
  char sc[64];
  std::snprintf(sc, sizeof sc, "%.17g", scale);
  Result r = run_microsim("generate heightmap --input " + png + " --pixel-size 0.015625 --height-scale " +
                          sc + " --periodic -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  Microsurface b = load_surface(out);
  // Heights to the format's precision: half a count (after removing the mean, as --detrend mean does).
  double mb = 0;
  for (float v : b.heights()) mb += v / b.heights().size();
  EXPECT_NEAR(mb, 0.0, 1e-7 * (hi - lo));
  double worst = 0;
  for (std::size_t k = 0; k < h.size(); ++k) worst = std::max(worst, std::abs((b.heights()[k] - mb) - (h[k] - t.mean)));
  EXPECT_LE(worst, 0.5 * scale + 1e-6 * (hi - lo));
  EXPECT_GT(worst, 0.0);  // it was quantized (the test can tell)
  // Slopes move by at most a count per cell (1e-4 of the slopes here, normals by < 0.01 deg):
  // 10-degree D rings within 1% (a facet crossing a ring edge), G1 within 1e-3 at the same
  // seed (its standard error is ~4e-3).
  expect_same_measurements(t.s, b, 1e-2, 1e-3);
}

TEST(HeightmapRoundTrip, CsvMatrixAndXyz) {
  Tile t = original_tile();
  const int n = t.s.nx();
  const std::string csv = tmp("tile.csv"), xyz = tmp("tile.xyz");
  {
    std::ofstream f(csv), g(xyz);
    f.precision(9);  // 9 significant digits: every float exactly
    g.precision(9);
    g << "x,y,z\n";
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        f << (i ? "," : "") << t.s.heights()[j * n + i];
        g << i * 0.015625 << "," << j * 0.015625 << "," << t.s.heights()[j * n + i] << "\n";
      }
      f << "\n";
    }
  }
  ASSERT_EQ(run_microsim("generate heightmap --input " + csv + " --pixel-size 0.015625 --periodic "
                         "--detrend none -o " + tmp("rt_csv.exr")).code, 0);
  Microsurface b = load_surface(tmp("rt_csv.exr"));
  EXPECT_EQ(b.heights(), t.s.heights());
  expect_same_measurements(t.s, b, 1e-6, 1e-12);
  // x,y,z columns: the pixel size comes from the columns.
  Result r = run_microsim("generate heightmap --input " + xyz + " --periodic --detrend none -o " + tmp("rt_xyz.exr"));
  ASSERT_EQ(r.code, 0) << r.err;
  Microsurface c = load_surface(tmp("rt_xyz.exr"));
  EXPECT_EQ(c.heights(), t.s.heights());
  EXPECT_DOUBLE_EQ(c.macro().size_x, 1.0);
}

// ---- the command: every estimator on an imported tile, refusals, windows ----

TEST(HeightmapCli, ImportedTileGoesThroughEveryEstimator) {
  Tile t = original_tile();
  const std::string csv = tmp("e.csv"), s = tmp("e.exr");
  {
    std::ofstream f(csv);
    f.precision(9);
    for (int j = 0; j < t.s.ny(); ++j) {
      for (int i = 0; i < t.s.nx(); ++i) f << (i ? " " : "") << 1e3 * t.s.heights()[j * t.s.nx() + i];
      f << "\n";
    }
  }
  // Heights in nm, pixels in um: the unit conversion restores the tile (1 um = 1000 nm).
  Result r = run_microsim("generate heightmap --input " + csv + " --pixel-size 0.015625 --length-unit um "
                          "--height-unit nm --periodic --detrend plane -o " + s);
  ASSERT_EQ(r.code, 0) << r.err;
  Microsurface b = load_surface(s);
  EXPECT_EQ(b.description["length_unit"], "um");
  EXPECT_NEAR(measure_metrology(grid_view(b)).sq, measure_metrology(grid_view(t.s)).sq, 1e-3);
  EXPECT_EQ(run_microsim("measure ndf " + s + " -o " + tmp("e_ndf.json")).code, 0);
  EXPECT_EQ(run_microsim("measure g1 " + s + " --theta 60 --rays 5000 -o " + tmp("e_g1.json")).code, 0);
  EXPECT_EQ(run_microsim("measure g2 " + s + " --theta-o 60 --theta-i 50 --rays 5000 -o " + tmp("e_g2.json")).code, 0);
  EXPECT_EQ(run_microsim("measure vndf " + s + " --theta 60 --rays 5000 --sampler-samples 5000 -o " +
                         tmp("e_vndf.json")).code, 0);
  EXPECT_EQ(run_microsim("measure bsdf " + s + " --material mirror --theta-i 30 --phi-i 0 --rays 5000 -o " +
                         tmp("e_bsdf.json")).code, 0);
  EXPECT_EQ(run_microsim("validate " + s + " --theta 60 --rays 5000 -o " + tmp("e_val.json")).code, 0);
  Result info = run_microsim("info " + s + " --json " + tmp("e_info.json"));
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_NE(info.out.find("Sdq"), std::string::npos);
  Json j = Json::parse(microsim::testing::slurp(tmp("e_info.json")));
  EXPECT_NEAR(j["metrology"]["beckmann_alpha_x"].get<double>(), std::sqrt(2 * facet_sums(b).slope_var_x), 1e-6);
  EXPECT_TRUE(j["metrology"].contains("sal"));
}

TEST(HeightmapCli, NonPeriodicWindowIsMeasuredInsideItsGuardBand) {
  Tile t = original_tile();
  const std::string w = tmp("w.exr");
  ExrTable z;
  z.width = t.s.nx();
  z.height = t.s.ny();
  z.channel_names = {"Z"};
  z.channels = {t.s.heights()};
  write_exr(tmp("wz.exr"), z);
  ASSERT_EQ(run_microsim("generate heightmap --input " + tmp("wz.exr") + " --pixel-size 1 --detrend plane -o " + w).code, 0);
  // The estimators measure the interior inside the default guard band (tests/test_guard_band.cpp);
  // a guard that leaves no interior is refused.
  Result g1 = run_microsim("measure g1 " + w + " --theta 60 --rays 20000 -o " + tmp("w_g1.json"));
  EXPECT_EQ(g1.code, 0) << g1.err;
  expect_refused("generate heightmap --input " + tmp("wz.exr") + " --pixel-size 1 --guard 30 -o " + tmp("w2.exr"),
                 tmp("w2.exr"), "--guard");
  Result info = run_microsim("info " + w);
  EXPECT_EQ(info.code, 0) << info.err;
  EXPECT_NE(info.out.find("non-periodic measured window"), std::string::npos);
  // Forcing --periodic on a crop (not periodic) warns about the seam; the whole tile does not.
  Result crop = run_microsim("generate heightmap --input " + tmp("wz.exr") + " --pixel-size 0.015625 --crop 4,4,40,40 "
                             "--periodic -o " + tmp("wc.exr"));
  EXPECT_EQ(crop.code, 0) << crop.err;
  EXPECT_NE(crop.err.find("does not look periodic"), std::string::npos) << crop.err;
  Result whole = run_microsim("generate heightmap --input " + tmp("wz.exr") + " --pixel-size 0.015625 --periodic -o " +
                              tmp("wt.exr"));
  EXPECT_EQ(whole.code, 0) << whole.err;
  EXPECT_EQ(whole.err, "");
}

TEST(HeightmapCli, BadInputIsRefusedWithOneLine) {
  const std::string o = tmp("bad_out.exr"), good = tmp("good.csv");
  write_text(good, "0 1 2\n1 2 0\n2 0 1\n");
  for (const char* v : {"0", "-1", "nan", "inf"})
    expect_refused("generate heightmap --input " + good + " --pixel-size " + v + " -o " + o, o, "--pixel-size");
  expect_refused("generate heightmap --input " + good + " --pixel-size 1 --pixel-size-y -2 -o " + o, o, "--pixel-size-y");
  expect_refused("generate heightmap --input " + good + " -o " + o, o, "--pixel-size");
  expect_refused("generate heightmap --input " + good + " --pixel-size 1 --height-scale 0 -o " + o, o, "--height-scale");
  expect_refused("generate heightmap --input " + good + " --pixel-size 1 --detrend cubic -o " + o, o, "--detrend");
  expect_refused("generate heightmap --input " + good + " --pixel-size 1 --crop 1,1,5,5 -o " + o, o, "--crop");
  expect_refused("generate heightmap --input " + good + " --pixel-size 1 --periodic --window -o " + o, o, "--window");
  expect_refused("generate heightmap --input " + tmp("nowhere.csv") + " --pixel-size 1 -o " + o, o, "nowhere.csv");
  const std::string nan = tmp("nan.csv"), flat = tmp("flat.csv"), holes = tmp("holes.csv"), junk = tmp("junk.png");
  write_text(nan, "nan,nan\nnan,nan\n");
  expect_refused("generate heightmap --input " + nan + " --pixel-size 1 -o " + o, o, "nan.csv");
  write_text(flat, "3 3 3\n3 3 3\n");
  expect_refused("generate heightmap --input " + flat + " --pixel-size 1 -o " + o, o, "constant");
  write_text(holes, "0 1 2\n-9 -9 0\n2 0 1\n");
  expect_refused("generate heightmap --input " + holes + " --pixel-size 1 --nodata -9 -o " + o, o, "--max-missing");
  Result ok = run_microsim("generate heightmap --input " + holes + " --pixel-size 1 --nodata -9 --max-missing 0.5 -o " + o);
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_EQ(load_surface_or_window(o, true).description["missing_filled"], 2);
  write_text(junk, "not an image");
  expect_refused("generate heightmap --input " + junk + " --pixel-size 1 -o " + tmp("bad2.exr"), tmp("bad2.exr"), "junk.png");
  // A plane, detrended, leaves nothing.
  write_text(flat, "0 1 2\n1 2 3\n2 3 4\n");
  expect_refused("generate heightmap --input " + flat + " --pixel-size 1 --detrend plane -o " + tmp("bad3.exr"),
                 tmp("bad3.exr"), "nothing left");
}

// ---- discretization: the map states its grid in the terms of the convergence study ----

namespace {
// A periodic Gaussian tile of `cells` cells per l (128^2, unit size), written as a plain EXR.
std::string gaussian_map(int cells, std::uint64_t seed, const std::string& name) {
  GaussianParams p;
  p.resolution = 128;
  p.size = 1.0;
  p.correlation_length = cells / 128.0;
  p.alpha_x = p.alpha_y = 0.5;
  p.seed = seed;
  Microsurface s = generate_gaussian(p);
  ExrTable z;
  z.width = s.nx();
  z.height = s.ny();
  z.channel_names = {"Z"};
  z.channels = {s.heights()};
  write_exr(tmp(name), z);
  return tmp(name);
}
}  // namespace

TEST(HeightmapImport, StatesCellsPerCorrelationLengthAndLengthsPerTile) {
  auto import = [](const std::string& file, bool periodic) {
    HeightmapImportParams p;
    p.input = file;
    p.pixel_size_x = 1.0 / 128;
    p.periodic = periodic;
    p.detrend = periodic ? Detrend::None : Detrend::Mean;
    p.guard_correlation_lengths = 4;  // a window's guard band: 4 l on each side
    return import_heightmap(p);
  };
  for (int cells : {4, 8}) {
    const std::string file = gaussian_map(cells, 11, "disc" + std::to_string(cells) + ".exr");
    Microsurface s = import(file, true);
    const auto d = discretization_of(s.description);
    ASSERT_TRUE(d) << s.description.dump();
    // The generator's l, recovered from the ACF of one tile (~10% spread between tiles), and
    // exactly metrology's cells per Gaussian length.
    EXPECT_NEAR(d->cells_per_correlation_length, cells, 0.15 * cells);
    EXPECT_DOUBLE_EQ(d->cells_per_correlation_length, measure_metrology(grid_view(s)).cells_per_gaussian_length);
    // The tile of 128 / cells lengths, counted in the slowest direction's length (>= l).
    EXPECT_LE(d->correlation_lengths_per_tile, 1.1 * 128 / cells);
    EXPECT_GE(d->correlation_lengths_per_tile, 0.7 * 128 / cells);
    // The same map as a window counts its interior inside the guard band, not the patch.
    Microsurface w = import(file, false);
    const auto dw = discretization_of(w.description);
    ASSERT_TRUE(dw) << w.description.dump();
    const Json& in = w.description["guard_band"]["interior"];
    const double interior = in["x1"].get<double>() - in["x0"].get<double>();
    EXPECT_NEAR(interior, 1.0 - 8.0 * cells / 128, 0.1) << cells;
    EXPECT_NEAR(dw->correlation_lengths_per_tile / d->correlation_lengths_per_tile, interior, 0.1 * interior) << cells;
  }
}

TEST(HeightmapCli, ValidateFlagsACoarseMeasuredMap) {
  // 4 cells per l: coarser than the converged level of the G1 check (8 cells per l).
  const std::string in = gaussian_map(4, 12, "coarse.exr"), s = tmp("coarse_map.exr"), v = tmp("coarse_val.json");
  ASSERT_EQ(run_microsim("generate heightmap --input " + in + " --pixel-size 0.0078125 --periodic -o " + s).code, 0);
  Result r = run_microsim("validate " + s + " --checks g1 --theta 60 --rays 2000 -o " + v);
  ASSERT_EQ(r.code, 0) << r.err;
  const Json j = Json::parse(microsim::testing::slurp(v));
  int flagged = 0;
  for (const Json& row : j["rows"])
    if (row.value("model_name", "") == "converged_level" && row.value("quantity", "") == "cells_per_correlation_length")
      ++flagged;
  EXPECT_EQ(flagged, 1) << r.out;
  const Json& desc = j["entries"][0]["surfaces"][0]["description"];
  EXPECT_TRUE(desc.contains("cells_per_correlation_length"));
  EXPECT_TRUE(desc.contains("correlation_lengths_per_tile"));
}
