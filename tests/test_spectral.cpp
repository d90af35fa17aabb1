// Tests of spectral conductors: the shipped tables of optical constants and their interpolation
// (models/metals.hpp), index files and their errors, the colour of a spectrum
// (models/spectral_rgb.hpp), and the spectral random walk (measure/bsdf_measure.hpp): a flat
// conductor reflects the Fresnel reflectance of each wavelength's index at normal incidence,
// and each wavelength's tallies are those of a run with that index alone, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "cli_helpers.hpp"
#include "microsim/io/merl.hpp"
#include "microsim/io/rgl_reader.hpp"
#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/models/metals.hpp"
#include "microsim/models/spectral_rgb.hpp"
#include "microsim/surface/gaussian.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;
namespace mm = microsim::models;

namespace {

// Normal-incidence reflectance of a conductor of index n + i k in vacuum.
double normal_reflectance(double n, double k) {
  return ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k);
}

BsdfOptions spectral_options(const mm::IndexTable& table, const std::vector<double>& nm, double theta_deg,
                             std::uint64_t rays) {
  BsdfOptions o;
  o.wavelengths_nm = nm;
  for (double x : nm) {
    const mm::OpticalConstant c = table.at(x);
    o.spectral.push_back(mm::Material::conductor(c.n, c.k));
  }
  o.material = o.spectral.front();
  o.theta_i = rad(theta_deg);
  o.rays = rays;
  o.resolution = 16;
  o.models = false;
  return o;
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string p = temp_path("spectral", name);
  std::ofstream(p) << text;
  return p;
}

}  // namespace

TEST(MetalTables, CoverTheVisibleAndIncrease) {
  for (const std::string& name : mm::metal_names()) {
    const mm::IndexTable& t = mm::metal_table(name);
    EXPECT_LE(t.min_nm(), 360.0) << name;
    EXPECT_GE(t.max_nm(), 830.0) << name;
    for (std::size_t i = 1; i < t.rows.size(); ++i) EXPECT_GT(t.rows[i].wavelength_nm, t.rows[i - 1].wavelength_nm);
  }
  EXPECT_THROW(mm::metal_table("Fe"), UsageError);
}

TEST(MetalTables, InterpolationExactAtRowsAndLinearBetween) {
  for (const std::string& name : mm::metal_names()) {
    const mm::IndexTable& t = mm::metal_table(name);
    for (const mm::OpticalConstant& row : t.rows) {
      const mm::OpticalConstant c = t.at(row.wavelength_nm);
      EXPECT_EQ(c.n, row.n) << name << " " << row.wavelength_nm;
      EXPECT_EQ(c.k, row.k) << name << " " << row.wavelength_nm;
    }
    // A quarter of the way between two rows: a quarter of the change (linear in the wavelength).
    const mm::OpticalConstant& a = t.rows[30];
    const mm::OpticalConstant& b = t.rows[31];
    const mm::OpticalConstant c = t.at(a.wavelength_nm + 0.25 * (b.wavelength_nm - a.wavelength_nm));
    EXPECT_NEAR(c.n, a.n + 0.25 * (b.n - a.n), 1e-12) << name;
    EXPECT_NEAR(c.k, a.k + 0.25 * (b.k - a.k), 1e-12) << name;
    EXPECT_THROW(t.at(t.min_nm() - 1), std::out_of_range);
    EXPECT_THROW(t.at(t.max_nm() + 1), std::out_of_range);
  }
  // Values of the published table [JohnsonChristy72]: gold at 0.5486 um.
  EXPECT_EQ(mm::metal_table("Au").at(548.6).n, 0.43);
  EXPECT_EQ(mm::metal_table("Au").at(548.6).k, 2.455);
}

TEST(IndexFile, ReadsRowsWithHeaderAndComments) {
  const std::string p = write_file("ok.csv", "wavelength_nm,n,k\n# measured\n400, 1.5, 3.0\n\n500\t1.0\t4.0\n");
  const mm::IndexTable t = mm::read_index_file(p);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.at(450.0).n, 1.25);
  EXPECT_EQ(t.at(450.0).k, 3.5);
}

TEST(IndexFile, ErrorsNameTheFileAndLine) {
  struct Case {
    const char* text;
    int line;
    const char* what;
  };
  const Case cases[] = {
      {"400,1.5,3\n390,1.5,3\n", 2, "increase"},
      {"400,0,3\n500,1,3\n", 1, "n must be > 0"},
      {"lambda,n,k\n400,1,-0.1\n", 2, "k must be >= 0"},
      {"400,1,3\n500,nan,3\n", 2, "three numbers"},  // not finite: not a number
      {"400,1,3\n500,1\n", 2, "three numbers"},
      {"400,1,3\n500,1,x\n", 2, "three numbers"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string p = write_file("bad" + std::to_string(i++) + ".csv", c.text);
    try {
      mm::read_index_file(p);
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const UsageError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(p + ":" + std::to_string(c.line) + ":"), std::string::npos) << msg;
      EXPECT_NE(msg.find(c.what), std::string::npos) << msg;
    }
  }
  EXPECT_THROW(mm::read_index_file(write_file("one.csv", "400,1,3\n")), UsageError);
  EXPECT_THROW(mm::read_index_file(temp_path("spectral", "missing.csv")), UsageError);
}

TEST(IndexFile, CommandLineExitsTwoNamingFileAndLine) {
  const std::string flat = temp_path("spectral", "flat.exr");
  ASSERT_EQ(run_microsim("--quiet generate flat --resolution 8 -o " + flat).code, 0);
  const std::string bad = write_file("cli_bad.csv", "nm,n,k\n400,1,3\n450,1,3\n440,1,3\n");
  const Result r = run_microsim("--quiet measure bsdf " + flat + " --material conductor --ior-file " + bad +
                                " --theta-i 0 --rays 100 -o " + temp_path("spectral", "bad.json"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(bad + ":4:"), std::string::npos) << r.err;
  // Wavelengths outside the table, and --wavelengths without a table.
  const std::string good = write_file("cli_good.csv", "400,1,3\n700,1,4\n");
  const Result out = run_microsim("--quiet measure bsdf " + flat + " --material conductor --ior-file " + good +
                                  " --wavelengths 450,750 --theta-i 0 --rays 100 -o " + temp_path("spectral", "o.json"));
  EXPECT_EQ(out.code, 2);
  EXPECT_NE(out.err.find("750 nm is outside"), std::string::npos) << out.err;
  const Result none = run_microsim("--quiet measure bsdf " + flat + " --material conductor --eta 1 --k 3 "
                                   "--wavelengths 450 --theta-i 0 --rays 100 -o " + temp_path("spectral", "n.json"));
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("--wavelengths needs --metal or --ior-file"), std::string::npos) << none.err;
}

TEST(SpectrumToRgb, ConstantSpectrumIsTheWhitePoint) {
  for (const std::vector<double>& nm : {std::vector<double>{550}, std::vector<double>{450, 500, 550, 600, 650},
                                        std::vector<double>{360, 400, 480, 700, 830}}) {
    const mm::SpectrumToRgb c(nm);
    const std::vector<double> one(nm.size(), 1.0), half(nm.size(), 0.5);
    const auto w = c.rgb(one);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(w[i], 1.0, 1e-12) << nm.size();
    EXPECT_NEAR(c.luminance(one.data()), 1.0, 1e-12);
    const auto h = c.rgb(half);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(h[i], 0.5, 1e-12);
  }
  // Power: a spectrum rising toward the red is red, not white (gold's reflectance).
  const mm::SpectrumToRgb c({450, 500, 550, 600, 650});
  const auto g = c.rgb(std::vector<double>{0.38, 0.45, 0.78, 0.92, 0.95});
  EXPECT_GT(g[0], g[1] + 0.1);
  EXPECT_GT(g[1], g[2] + 0.1);
}

TEST(SpectrumToRgb, FitIsTheCie1931Observer) {
  // The fit of [Wyman13] against three values of the CIE 1931 2-degree tables (within the fit's
  // few-percent error): ybar(555) = 1.0002, xbar(600) = 1.0622, zbar(450) = 1.7721.
  EXPECT_NEAR(mm::cie1931_xyz_fit(555)[1], 1.0002, 0.01);
  EXPECT_NEAR(mm::cie1931_xyz_fit(600)[0], 1.0622, 0.02);
  EXPECT_NEAR(mm::cie1931_xyz_fit(450)[2], 1.7721, 0.04);
}

TEST(SpectralBsdf, FlatConductorAtNormalIncidenceIsFresnel) {
  const Microsurface s = flat_heightfield(16);
  const Tracer tracer(s);
  const std::vector<double> nm = {450, 550, 650};
  for (const std::string& metal : mm::metal_names()) {
    const mm::IndexTable& t = mm::metal_table(metal);
    const BsdfResult r = measure_bsdf(tracer, spectral_options(t, nm, 0.0, 4000));
    ASSERT_EQ(r.wavelengths(), 3);
    for (int l = 0; l < 3; ++l) {
      const mm::OpticalConstant c = t.at(nm[l]);
      const double F = normal_reflectance(c.n, c.k);
      // Every path reflects once with weight F: the mean is F up to the rounding of the sums.
      EXPECT_NEAR(r.albedo(0, 0, l).mean, F, 1e-13) << metal << " " << nm[l];
      EXPECT_NEAR(r.albedo(0, 4, l).mean, F, 1e-13) << metal << " " << nm[l];
      EXPECT_EQ(r.albedo(0, 1, l).mean, 0.0);
      // Power: an index 0.01 off in n, or another wavelength's, is far outside that tolerance.
      EXPECT_GT(std::abs(r.albedo(0, 0, l).mean - normal_reflectance(c.n + 0.01, c.k)), 1e-5) << metal;
      const mm::OpticalConstant other = t.at(nm[(l + 1) % 3]);
      EXPECT_GT(std::abs(r.albedo(0, 0, l).mean - normal_reflectance(other.n, other.k)), 1e-4) << metal;
    }
    // The scalar fields are the first wavelength's.
    EXPECT_EQ(r.albedo(0, 4).mean, r.albedo(0, 4, 0).mean);
  }
}

TEST(SpectralBsdf, EachWavelengthIsTheSingleIndexRunBitForBit) {
  GaussianParams gp;
  gp.resolution = 48;
  gp.correlation_length = 4.0 / 48;
  gp.alpha_x = gp.alpha_y = 0.8;
  gp.seed = 5;
  const Microsurface s = generate_gaussian(gp);
  const Tracer tracer(s);
  const mm::IndexTable& cu = mm::metal_table("Cu");
  const std::vector<double> nm = {420, 560, 610, 700};
  const BsdfOptions so = spectral_options(cu, nm, 50.0, 30000);
  const BsdfResult spectral = measure_bsdf(tracer, so);
  auto same = [](const BsdfTally& a, const BsdfTally& b) {
    return a.albedo == b.albedo && a.albedo2 == b.albedo2 && a.pix == b.pix && a.pix2 == b.pix2 &&
           a.plane == b.plane && a.plane2 == b.plane2 && a.both2 == b.both2 && a.paths == b.paths &&
           a.lost == b.lost && a.unterminated == b.unterminated && a.events == b.events &&
           a.replicates == b.replicates;
  };
  for (std::size_t l = 0; l < nm.size(); ++l) {
    BsdfOptions one = so;
    one.wavelengths_nm.clear();
    one.spectral.clear();
    one.material = so.spectral[l];
    const BsdfResult single = measure_bsdf(tracer, one);
    EXPECT_TRUE(same(spectral.spectral[l], single.measured)) << nm[l];
    EXPECT_GT(single.albedo(0, 1).mean, 0.0);  // the surface scatters more than once
    // Power: another wavelength's tallies differ from this run's.
    EXPECT_FALSE(same(spectral.spectral[(l + 1) % nm.size()], single.measured)) << nm[l];
  }
}

TEST(SpectralBsdf, RglTableCarriesTheWavelengths) {
  const std::string flat = temp_path("spectral", "flat_rgl.exr");
  ASSERT_EQ(run_microsim("--quiet generate flat --resolution 8 -o " + flat).code, 0);
  const std::string out = temp_path("spectral", "au.bsdf");
  const Result r = run_microsim("--quiet measure bsdf " + flat + " --material conductor --metal Au --wavelengths "
                                "450,550,650 --theta-i 0,30 --rays 2000 --table-resolution 8 --no-models -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto fields = read_tensor_file(out);
  const TensorField& w = fields.at("wavelengths");
  ASSERT_EQ(w.shape, std::vector<std::uint64_t>{3});
  std::vector<float> v(3);
  std::memcpy(v.data(), w.data.data(), 12);
  EXPECT_EQ(v, (std::vector<float>{450.0f, 550.0f, 650.0f}));
  EXPECT_EQ(fields.at("spectra").shape, (std::vector<std::uint64_t>{1, 2, 3, 8, 8}));
  EXPECT_EQ(fields.at("rgb").shape, (std::vector<std::uint64_t>{1, 2, 3, 8, 8}));
}

namespace {
// A small rough tile's table at two incidences with the given spectral indices.
BsdfTable spectral_table(const Tracer& tracer, const std::vector<double>& nm, const std::vector<mm::Material>& m) {
  BsdfTableOptions to;
  to.base.wavelengths_nm = nm;
  to.base.spectral = m;
  to.base.material = m.front();
  to.base.rays = 4000;
  to.base.resolution = 8;
  to.base.models = false;
  to.theta_i = {0.0, rad(40.0)};
  to.phi_i = {0.0};
  return measure_bsdf_table(tracer, to);
}
Microsurface rough_tile() {
  GaussianParams gp;
  gp.resolution = 32;
  gp.correlation_length = 4.0 / 32;
  gp.seed = 3;
  return generate_gaussian(gp);
}
}  // namespace

TEST(SpectralBsdf, MerlChannelsAreTheColourOfTheSpectrum) {
  const Microsurface s = rough_tile();
  const Tracer tracer(s);
  const std::vector<double> nm = {450, 550, 650};
  // The same index at every wavelength: a constant spectrum, so R = G = B = the single-index f.
  const mm::Material one = mm::Material::conductor(0.5, 2.5);
  const BsdfTable flat_spectrum = spectral_table(tracer, nm, {one, one, one});
  BsdfTableOptions single;
  single.base.material = one;
  single.base.rays = 4000;
  single.base.resolution = 8;
  single.base.models = false;
  single.theta_i = {0.0, rad(40.0)};
  single.phi_i = {0.0};
  const std::vector<double> f = merl_cells(measure_bsdf_table(tracer, single));
  const auto rgb = merl_rgb_cells(flat_spectrum);
  double total = 0.0;
  for (std::size_t c = 0; c < f.size(); c += 97) {
    for (int ch = 0; ch < 3; ++ch) ASSERT_NEAR(rgb[ch][c], f[c], 1e-12 * (1.0 + f[c])) << c << " " << ch;
    total += f[c];
  }
  EXPECT_GT(total, 0.0);
  // Gold's spectrum is red: over the cells R exceeds B by far (power: equal channels fail).
  const mm::IndexTable& au = mm::metal_table("Au");
  std::vector<mm::Material> gold;
  for (double x : nm) gold.push_back(mm::Material::conductor(au.at(x).n, au.at(x).k));
  const auto g = merl_rgb_cells(spectral_table(tracer, nm, gold));
  double sr = 0.0, sb = 0.0;
  for (std::size_t c = 0; c < g[0].size(); c += 97) {
    sr += g[0][c];
    sb += g[2][c];
  }
  EXPECT_GT(sr, 1.5 * sb);
}

TEST(SpectralBsdf, RglSpectraAreEachWavelengthsTable) {
  const Microsurface s = rough_tile();
  const Tracer tracer(s);
  const mm::IndexTable& cu = mm::metal_table("Cu");
  const std::vector<double> nm = {450, 600, 700};
  std::vector<mm::Material> m;
  for (double x : nm) m.push_back(mm::Material::conductor(cu.at(x).n, cu.at(x).k));
  RglOptions ro;
  ro.resolution = 8;
  const RglTable spectral = build_rgl_table(spectral_table(tracer, nm, m), s, ro);
  ASSERT_EQ(spectral.wavelengths, (std::vector<float>{450.0f, 600.0f, 700.0f}));
  const std::size_t slice = 64, per = 3 * slice;
  ASSERT_EQ(spectral.spectra.size(), 2 * per);
  ASSERT_EQ(spectral.rgb.size(), 2 * per);
  for (int l = 0; l < 3; ++l) {
    // Wavelength l's spectra: the table of a run with its index alone (same seed), sampled at
    // the same vertices (the vndf warp differs: the spectral one follows the luminance).
    BsdfTableOptions single;
    single.base.material = m[l];
    single.base.rays = 4000;
    single.base.resolution = 8;
    single.base.models = false;
    single.theta_i = {0.0, rad(40.0)};
    single.phi_i = {0.0};
    const BsdfTable t = measure_bsdf_table(tracer, single);
    const BsdfTable sp = spectral_table(tracer, nm, m);
    for (int q = 0; q < 2; ++q)
      for (int px = 0; px < sp.results[q].map.size(); ++px)
        ASSERT_EQ(sp.results[q].f_pixel(0, 4, px, l).mean, t.results[q].f_pixel(0, 4, px).mean) << l << " " << px;
  }
  // The spectra in wavelength order: copper reflects 700 nm far better than 450 nm.
  double s450 = 0.0, s700 = 0.0;
  for (std::size_t q = 0; q < 2; ++q)
    for (std::size_t k = 0; k < slice; ++k) {
      s450 += spectral.spectra[q * per + k];
      s700 += spectral.spectra[q * per + 2 * slice + k];
    }
  EXPECT_GT(s700, 1.3 * s450);
  // Copper is red: its rgb's red exceeds its blue.
  double r = 0.0, b = 0.0;
  for (std::size_t q = 0; q < 2; ++q)
    for (std::size_t k = 0; k < slice; ++k) {
      r += spectral.rgb[q * per + k];
      b += spectral.rgb[q * per + 2 * slice + k];
    }
  EXPECT_GT(r, 1.3 * b);
}

// (Spectral runs split over shards and MPI ranks: test_tally_fields.cpp.)
TEST(IndexFile, SpectralRunsRefuseVcavityEnsembles) {
  const std::string vc = temp_path("spectral", "vc.ply");
  ASSERT_EQ(run_microsim("--quiet generate vcavity --config " + std::string(MICROSIM_SOURCE_DIR) +
                         "/surfaces/vcavity.toml -o " + vc).code, 0);
  const Result v = run_microsim("--quiet measure bsdf " + vc + " --material conductor --metal Au --theta-i 0 "
                                "--rays 100 -o " + temp_path("spectral", "vc.json"));
  EXPECT_EQ(v.code, 2);
  EXPECT_NE(v.err.find("V-cavity ensembles"), std::string::npos) << v.err;
  // The same runs with one index go through.
  EXPECT_EQ(run_microsim("--quiet measure bsdf " + vc + " --material conductor --eta 0.2 --k 3 --theta-i 0 "
                         "--rays 100 -o " + temp_path("spectral", "vc1.json")).code, 0);
}
