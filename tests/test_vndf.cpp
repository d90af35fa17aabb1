// Distribution of visible normals ([GeomBSDF24, eq. 3b], [Heitz14, eq. 13]): the VNDF sampler's chi-square test,
// the histogram of first-hit normals against the exact GGX of the ellipsoid, the Smith
// independence assumption on a Beckmann tile, and the measure vndf command.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <fstream>
#include <limits>
#include <sys/wait.h>

#include "microsim/measure/stats.hpp"
#include "microsim/measure/vndf_measure.hpp"
#include "microsim/statistics.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/surface_io.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;

namespace {
Vec3 dir(double theta_deg, double phi_deg) { return direction_from_angles(rad(theta_deg), rad(phi_deg)); }

// The upper half-ellipsoid of surface/generators.hpp (normals GGX(ax, ay), [TSBlog24]).
Microsurface ellipsoid(double ax, double ay, int rings = EllipsoidParams{}.rings,
                       int segments = EllipsoidParams{}.segments) {
  EllipsoidParams p;
  p.alpha_x = ax;
  p.alpha_y = ay;
  p.rings = rings;
  p.segments = segments;
  return generate_ellipsoid(p);
}

// A reference mesh for the per-bin test below, tessellated to fit the bins (unlike the generator's
// latitude-longitude image of a hemisphere, whose facet normals straddle the 5-degree bin edges:
// measured with 1e6 rays at normal incidence, chi2 998 on 287 dof at 256 x 1024 for alpha 0.5,
// and 329 on 242 dof at 1024 x 1024 for alpha (0.4, 0.8) at 50 degrees).
// Upper half of the ellipsoid with semi-axes (1/alpha_x, 1/alpha_y, 1): its normal
// distribution is GGX(alpha_x, alpha_y) [TSBlog24]. Tessellated on a grid in normal space: the
// vertex with normal m(theta_k, phi_j) is the ellipsoid point with that normal,
// p = (a^2 m_x, b^2 m_y, c^2 m_z) / |(a m_x, b m_y, c m_z)|, theta_k = k 90/n_theta degrees,
// phi_j = j 360/n_phi degrees, so that facets fall inside normal bins whose edges are on the
// grid. A finite object (periodic = false) whose macro area is the projected area of the
// tessellation ([GeomBSDF24, eq. 1c]; it tends to pi a b), so that eq. 1b holds to rounding.
Microsurface ellipsoid_on_bin_grid(double alpha_x, double alpha_y, int n_theta = 90,
                                   int n_phi = 144) {
  const double a = 1 / alpha_x, b = 1 / alpha_y, c = 1;
  auto point = [&](double th, double ph) {
    const Vec3 m(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    const double d = Vec3(a * m.x(), b * m.y(), c * m.z()).norm();
    return Eigen::Vector3f(static_cast<float>(a * a * m.x() / d), static_cast<float>(b * b * m.y() / d),
                           static_cast<float>(c * c * m.z() / d));
  };
  std::vector<Eigen::Vector3f> verts;
  std::vector<std::array<std::uint32_t, 3>> tris;
  verts.push_back(point(0, 0));  // pole
  for (int k = 1; k <= n_theta; ++k)
    for (int j = 0; j < n_phi; ++j)
      verts.push_back(point(0.5 * kPi * k / n_theta, 2 * kPi * j / n_phi));
  auto id = [&](int k, int j) {  // k >= 1
    return static_cast<std::uint32_t>(1 + (k - 1) * n_phi + ((j % n_phi) + n_phi) % n_phi);
  };
  for (int j = 0; j < n_phi; ++j) tris.push_back({0, id(1, j), id(1, j + 1)});
  for (int k = 1; k < n_theta; ++k)
    for (int j = 0; j < n_phi; ++j) {
      tris.push_back({id(k, j), id(k + 1, j), id(k + 1, j + 1)});
      tris.push_back({id(k, j), id(k + 1, j + 1), id(k, j + 1)});
    }
  Macrosurface m;
  m.periodic = false;
  m.size_x = 2 * a;
  m.size_y = 2 * b;
  m.area = 0;
  for (const auto& t : tris)
    m.area += 0.5 * (verts[t[1]] - verts[t[0]]).cast<double>().cross((verts[t[2]] - verts[t[0]]).cast<double>()).z();
  Microsurface s = Microsurface::mesh(std::move(verts), std::move(tris), m);
  s.description = {{"kind", "ellipsoid"}, {"nominal_ndf", "ggx"}, {"alpha_x", alpha_x},
                   {"alpha_y", alpha_y}};
  s.nominal = models::Ndf::ggx(alpha_x, alpha_y);
  return s;
}

VndfOptions opts(std::uint64_t rays, std::uint64_t seed = 1) {
  VndfOptions o;
  o.rays = rays;
  o.seed = seed;
  return o;
}
}  // namespace

TEST(Stats, ChiSquareTailAndSidak) {
  EXPECT_NEAR(chi2_p_value(3.841458820694124, 1), 0.05, 1e-9);
  EXPECT_NEAR(chi2_p_value(18.307038053275146, 10), 0.05, 1e-9);
  EXPECT_NEAR(chi2_p_value(124.34211340400407, 100), 0.05, 1e-9);
  EXPECT_NEAR(chi2_p_value(2, 2), std::exp(-1.0), 1e-12);
  EXPECT_NEAR(sidak_z(0.05, 1), 1.959963985, 1e-6);
  EXPECT_NEAR(sidak_z(0.0027, 1), 3.0, 2e-3);
}

TEST(VndfModel, BinProbabilitiesAreNormalized) {
  // [Heitz14, eq. 13]: int D_v(m) dm = 1 for any view (the G1 normalization).
  const DirectionBinning bins = vndf_binning(VndfOptions{});
  for (auto ndf : {models::Ndf::beckmann(0.5, 0.5), models::Ndf::ggx(0.3, 0.8), models::Ndf::beckmann(0.2, 0.6)})
    for (double t : {0.0, 45.0, 80.0}) {
      const Vec3 v = dir(t, 30);
      double sum = 0;
      for (double p : bin_integrals(bins, [&](const Vec3& m) { return ndf.D_visible(v, m); })) sum += p;
      // GGX has mass beyond the binned hemisphere's quadrature accuracy only at 1e-4 level.
      EXPECT_NEAR(sum, 1.0, 2e-4) << models::to_string(ndf.kind) << " theta " << t;
    }
}

namespace {
// The library's sampler check (test_vndf_sampler, reported by `measure vndf`) and the chi-square
// harness's Pearson statistic on the same histogram (all bins plus one for the samples outside
// them, against N times the bin integrals): two routes to the same verdict.
ChiSquareResult harness_gof(const SamplerTest& t, const std::vector<double>& probabilities) {
  std::vector<double> observed(t.counts.begin(), t.counts.end()), expected;
  observed.push_back(static_cast<double>(t.outside));
  double inside = 0;
  for (double p : probabilities) {
    expected.push_back(static_cast<double>(t.n) * p);
    inside += p;
  }
  expected.push_back(static_cast<double>(t.n) * std::max(0.0, 1 - inside));
  return pearson_chi2(observed, expected);
}

struct SamplerCase {
  models::Ndf ndf;
  double theta, phi;
};
std::string sampler_case_name(const ::testing::TestParamInfo<SamplerCase>& i) {
  const SamplerCase& c = i.param;
  return std::string(models::to_string(c.ndf.kind)) + "_a" + std::to_string(static_cast<int>(100 * c.ndf.alpha_x)) +
         "x" + std::to_string(static_cast<int>(100 * c.ndf.alpha_y)) + "_theta" + std::to_string(static_cast<int>(c.theta));
}
const SamplerCase kSamplerCases[] = {
    {models::Ndf::beckmann(0.5, 0.5), 0, 0},   {models::Ndf::beckmann(0.5, 0.5), 60, 0},
    {models::Ndf::beckmann(0.5, 0.5), 85, 30}, {models::Ndf::beckmann(0.2, 0.7), 70, 40},
    {models::Ndf::ggx(0.5, 0.5), 0, 0},        {models::Ndf::ggx(0.5, 0.5), 60, 0},
    {models::Ndf::ggx(0.5, 0.5), 85, 30},      {models::Ndf::ggx(0.8, 0.25), 70, 120}};
constexpr int kSamplerTests = sizeof(kSamplerCases) / sizeof(kSamplerCases[0]);
}  // namespace

class VndfSampler : public ::testing::TestWithParam<SamplerCase> {};

TEST_P(VndfSampler, PassesChiSquare) {
  const SamplerCase& c = GetParam();
  const DirectionBinning bins = vndf_binning(VndfOptions{});
  SamplerTest t = test_vndf_sampler(c.ndf, dir(c.theta, c.phi), 400000, bins, 3);
  // Family-wise 1% over the cases.
  EXPECT_GT(t.gof.p_value, sidak_alpha(0.01, kSamplerTests)) << "chi2 " << t.gof.chi2 << "/" << t.gof.dof;
  EXPECT_TRUE(t.gof.pass()) << "max |z| " << t.gof.max_abs_z << " threshold " << t.gof.sidak_z;
  EXPECT_GT(t.gof.dof, 50);
  const ChiSquareResult h = harness_gof(t, t.probabilities);
  EXPECT_TRUE(h.passed(0.01, kSamplerTests)) << h.summary();
  EXPECT_NEAR(h.dof, t.gof.dof, 0.1 * t.gof.dof);  // the two pooling rules differ in the small bins only
}
INSTANTIATE_TEST_SUITE_P(Cases, VndfSampler, ::testing::ValuesIn(kSamplerCases), sampler_case_name);

TEST(VndfSamplerPower, ChiSquareRejectsAWrongDistribution) {
  // Power: samples of Beckmann 0.5 against GGX 0.5, and against Beckmann 0.53 (6% off).
  const DirectionBinning bins = vndf_binning(VndfOptions{});
  const Vec3 v = dir(60, 0);
  SamplerTest t = test_vndf_sampler(models::Ndf::beckmann(0.5, 0.5), v, 400000, bins, 3);
  for (auto wrong : {models::Ndf::ggx(0.5, 0.5), models::Ndf::beckmann(0.53, 0.53)}) {
    auto p = bin_integrals(bins, [&](const Vec3& m) { return wrong.D_visible(v, m); });
    EXPECT_LT(histogram_gof(t.counts, t.n, p, 0.0027).p_value, 1e-6);
    EXPECT_LT(harness_gof(t, p).p_value, 1e-6);
  }
}

TEST(VndfMeasure, FlatPlaneSeesOnlyTheNormal) {
  Microsurface s = flat_heightfield(16);
  Tracer tracer(s);
  VndfResult r = measure_vndf(tracer, dir(70, 10), opts(10000));
  EXPECT_EQ(r.hits, r.rays);
  std::uint64_t ring0 = 0;
  for (int b = 0; b < r.binning.n_phi(); ++b) ring0 += r.bin_hits[b];
  EXPECT_EQ(ring0, r.hits);  // every normal is n, in the first ring
}

TEST(VndfMeasure, EllipsoidIsExactGgxPerBin) {
  // The upper half-ellipsoid with semi-axes (1/ax, 1/ay, 1) has the GGX NDF and no masking of
  // its front faces (convex): the histogram of first-hit normals is GGX's D_v [Heitz14, eq. 13]
  // within 3 sigma per bin, Sidak-corrected over the bins (and by chi-square).
  // Tessellation: a flat facet's normal differs from the smooth normal at its centre by O(h)
  // when the curvature is anisotropic, so facets near a bin edge can fall in the neighbouring
  // bin; this discretization of D is O(h^2) for the sphere-like isotropic case (90 x 144
  // suffices) but O(h / bin size) for the anisotropic one, which needs 360 x 576 to stay below
  // the statistical resolution of 1e6 rays (checked: 2.4% in the worst pole bin, whose
  // standard error is 2.6%; 180 x 288 leaves 8% there and fails).
  for (auto [ax, ay] : {std::pair{0.5, 0.5}, std::pair{0.4, 0.8}}) {
    Microsurface s = ax == ay ? ellipsoid_on_bin_grid(ax, ay) : ellipsoid_on_bin_grid(ax, ay, 360, 576);
    Tracer tracer(s);
    for (auto [t, p] : {std::pair{0.0, 0.0}, std::pair{50.0, 20.0}, std::pair{80.0, 70.0}}) {
      VndfOptions o = opts(1000000, 4);
      VndfResult r = measure_vndf(tracer, dir(t, p), o);
      EXPECT_EQ(r.counters.backface_hits, 0u);
      auto model = bin_integrals(r.binning, [&](const Vec3& m) { return s.nominal->D_visible(r.v, m); });
      GofResult g = histogram_gof(r.bin_hits, r.hits, model, 0.0027);
      EXPECT_TRUE(g.pass()) << ax << "," << ay << " theta " << t << " max|z| " << g.max_abs_z
                            << " > " << g.sidak_z;
      EXPECT_GT(g.p_value, 0.001) << ax << "," << ay << " theta " << t << " chi2 " << g.chi2 << "/" << g.dof;
      EXPECT_GT(g.bins_tested, 40);
      // A convex mesh hides none of its front faces: the histogram is exactly the mesh's own
      // (v.m)+ A_f distribution (Smith with its facets), whatever the tessellation.
      GofResult gm = histogram_gof(r.bin_hits, r.hits, r.smith_numeric_probabilities(), 0.0027);
      EXPECT_TRUE(gm.pass()) << gm.max_abs_z;
      EXPECT_GT(gm.p_value, 0.001);
      // Power: Beckmann with the same roughness is rejected.
      models::Ndf beck = models::Ndf::beckmann(ax, ay);
      auto wrong = bin_integrals(r.binning, [&](const Vec3& m) { return beck.D_visible(r.v, m); });
      EXPECT_LT(histogram_gof(r.bin_hits, r.hits, wrong, 0.0027).p_value, 1e-6);
    }
  }
}

TEST(VndfMeasure, HeightfieldAtNormalIncidenceIsSmithWithItsFacetsButNotAtGrazing) {
  // At normal incidence nothing of a heightfield is masked: the visible normals are
  // distributed as (v.m) D_facets exactly (Smith's VNDF with the surface's own facets). At a
  // grazing view masking depends on m (facets tilted toward the viewer are less masked), which
  // Smith's independence assumption ignores: the same test rejects.
  GaussianParams gp;
  gp.resolution = 256;
  gp.correlation_length = 4.0 / 256;  // 4 cells per l
  gp.seed = 12;
  Microsurface s = generate_gaussian(gp);
  Tracer tracer(s);
  const DirectionBinning bins = vndf_binning(VndfOptions{});
  const FacetTable table = build_facet_table(s, bins);
  VndfResult r0 = measure_vndf(tracer, dir(0, 0), opts(1000000, 2), &table);
  GofResult g0 = histogram_gof(r0.bin_hits, r0.hits, r0.smith_numeric_probabilities(), 0.0027);
  EXPECT_GT(g0.p_value, 0.001) << g0.chi2 << "/" << g0.dof;
  EXPECT_TRUE(g0.pass());
  VndfResult r8 = measure_vndf(tracer, dir(80, 0), opts(1000000, 2), &table);
  GofResult g8 = histogram_gof(r8.bin_hits, r8.hits, r8.smith_numeric_probabilities(), 0.0027);
  EXPECT_LT(g8.p_value, 1e-6) << g8.chi2 << "/" << g8.dof;
}

TEST(VndfMeasure, ResultsDoNotDependOnThreadCount) {
  GaussianParams gp;
  gp.resolution = 64;
  Microsurface s = generate_gaussian(gp);
  Tracer tracer(s);
  auto go = [&](int threads) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
    VndfOptions o = opts(100000, 3);
    return std::pair{measure_vndf(tracer, dir(70, 20), o),
                     test_vndf_sampler(*s.nominal, dir(70, 20), 50000, vndf_binning(o), 3)};
  };
  auto [a, sa] = go(1);
  auto [b, sb] = go(2);
  EXPECT_EQ(a.bin_hits, b.bin_hits);
  EXPECT_EQ(sa.counts, sb.counts);
}

namespace {
int run(const std::string& args) {
  const std::string cmd = std::string(MICROSIM_BINARY) + " " + args + " >/dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}
}  // namespace

TEST(VndfCli, WritesTestsAndBins) {
  const std::string dir_ = ::testing::TempDir();
  const std::string e = dir_ + "microsim_vndf_ellipsoid.ply", out = dir_ + "microsim_vndf.json";
  save_surface(ellipsoid(0.5, 0.5, 45, 72), e);
  ASSERT_EQ(run("measure vndf " + e + " --theta 0,60 --rays 20000 --sampler-samples 20000 -o " + out), 0);
  std::ifstream f(out);
  Json j = Json::parse(f);
  ASSERT_EQ(j["rows"].size(), 2u);
  for (const char* k : {"chi2", "dof", "p_value", "max_abs_z", "sidak_z", "pass", "sampler_p_value",
                        "p_value_smith_numeric", "bins"})
    EXPECT_TRUE(j["rows"][1].contains(k)) << k;
  for (const char* k : {"dv", "dv_stderr", "dv_model", "dv_smith_numeric", "z", "rel_dev"})
    EXPECT_TRUE(j["rows"][1]["bins"][0].contains(k)) << k;
  EXPECT_EQ(j["surface"]["kind"], "ellipsoid");
  EXPECT_EQ(run("measure vndf " + e + " --theta 95 -o " + out + ".bad.json"), 2);
  EXPECT_EQ(run("measure vndf " + e + " --theta-bins 0 -o " + out + ".bad.json"), 2);
}

// Directions from corrupt geometry (NaN or infinite components) have no bin (-1) rather than an
// out-of-range cast or index; huge finite ones stay in range; bin counts whose product overflows
// int are refused. Ordinary directions keep their own bins.
TEST(DirectionBinning, NonFiniteDirectionsHaveNoBin) {
  const DirectionBinning sphere(18, 36, kPi), hemi(9, 36, kPi / 2);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const DirectionBinning* b : {&sphere, &hemi}) {
    for (const Vec3& d : {Vec3(nan, nan, nan), Vec3(nan, 0, 1), Vec3(0, nan, 0.5), Vec3(inf, 0, 0),
                          Vec3(-inf, -inf, 0), Vec3(0, 0, -inf)})
      EXPECT_EQ(b->bin_of(d), -1) << d.transpose();
    const int k = b->bin_of(Vec3(1e300, -1e300, 1e-300));
    EXPECT_TRUE(k >= 0 && k < b->size()) << k;
  }
  EXPECT_THROW(DirectionBinning(1 << 16, 1 << 16, kPi), UsageError);
  EXPECT_THROW(DirectionBinning(0, 36, kPi), UsageError);
  // 25 degrees from the pole, azimuth 45 degrees: ring 2, sector 4 (10-degree bins).
  const double t = 25 * kPi / 180, p = 45 * kPi / 180;
  const Vec3 d(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
  EXPECT_EQ(sphere.bin_of(d), sphere.index(2, 4));
  EXPECT_EQ(hemi.bin_of(d), hemi.index(2, 4));
  EXPECT_EQ(sphere.bin_of(Vec3(0, 0, -1)), sphere.index(17, 0));
  EXPECT_EQ(hemi.bin_of(Vec3(0, 0, -1)), -1);
}
