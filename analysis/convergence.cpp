// One level of the discretization study of Gaussian heightfields (analysis/convergence.sh runs
// every level, analysis/convergence.py makes the table and figures). A level is a grid
// (cells per correlation length l / dx) and a tile (correlation lengths per tile L / l); it is
// measured on an ensemble of K independent tiles, and every quantity is written per tile so
// that the ensemble mean carries the between-surface error (docs/theory/error-bars.md).
//
// Per tile: fitted alpha and D per 5-degree ring (exact from the facets), averaged G1 and G1 per
// normal bin at 80 deg, G2 at 70/70 deg with the two directions at the same and at opposite
// azimuths, the VNDF chi-square against the nominal D_v at 80 deg, mirror albedo per order at
// theta_i = 0, 60, 80 deg with the in-plane lobe at 80 deg, dielectric eta = 1.5 reflected and
// transmitted per order at theta_i = 0, 60 deg.
//
//   convergence --kind gaussian --alpha 1 --cells-per-l 8 --lengths-per-tile 32 --surfaces 16
//               --rays-bsdf 4000000 --rays-g 2000000 -o level.json
// Ray counts are per level (split over the K tiles).
#include <chrono>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numeric>
#include <algorithm>
#include <string>

#include "microsim/io/output.hpp"
#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/measure/ndf_measure.hpp"
#include "microsim/measure/vndf_measure.hpp"
#include "microsim/surface/discretization.hpp"
#include "microsim/surface/gaussian.hpp"

#include <tbb/parallel_for.h>
#include <unsupported/Eigen/FFT>

using namespace microsim;

namespace {

struct Args {
  std::string kind = "gaussian", out;
  double alpha = 1.0;
  int cells_per_l = 8, lengths_per_tile = 32, surfaces = 8;
  std::uint64_t rays_bsdf = 2000000, rays_g = 1000000, smith_walks = 0, seed0 = 1;
  bool nested = true;  // common random numbers across grids (0: generate_gaussian[_ggx])
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}


Json est(const Estimate& e) { return Json::array({e.mean, e.stderr_}); }

// Albedo per side and order slot (orders 1, 2, 3, 4+, total) with ray-count errors.
Json albedos(const BsdfResult& r, int side) {
  Json a = Json::array();
  for (int k = 0; k <= r.options.orders; ++k) a.push_back(est(r.albedo(side, k)));
  return a;
}

// A Gaussian field drawn with common random numbers across grids: the complex white noise of
// each spatial frequency is keyed by the frequency (and the stream), not by the pixel, so fields
// of the same seed at 2, 4, ... 32 cells per l sample the same continuous field (the spectrum
// exp(-k^2 l^2 / 4) of the autocorrelation exp(-r^2/l^2) is negligible beyond the coarsest
// grid's Nyquist frequency: exp(-pi^2) at 2 cells per l). h = Re(IFFT(H W)) is a stationary
// Gaussian field with the spectrum S = |H|^2 (its covariance is the even part of that of H W).
// Scaled like generate_gaussian: expected finite-difference slope variance alpha^2/2 per axis.
std::vector<double> nested_field(int n, double ell, double alpha, std::uint64_t seed, std::uint64_t stream) {
  using C = std::complex<double>;
  const double size = 1.0, dx = size / n;
  std::vector<C> a(static_cast<std::size_t>(n) * n);
  auto freq = [n](int i) { return i <= n / 2 ? i : i - n; };
  double var_dx = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int fi = freq(i), fj = freq(j);
      const double kx = 2 * kPi * fi / size, ky = 2 * kPi * fj / size;
      const double sk = std::exp(-(kx * kx + ky * ky) * ell * ell / 4.0);
      const std::uint64_t key = (static_cast<std::uint64_t>(fi + (1 << 20)) << 21) |
                                static_cast<std::uint64_t>(fj + (1 << 20));
      CounterRng rng(seed, stream, key);
      const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
      const double r = std::sqrt(-2.0 * std::log(u1));
      a[static_cast<std::size_t>(j) * n + i] = std::sqrt(sk) * C(r * std::cos(2 * kPi * u2), r * std::sin(2 * kPi * u2));
      const double sx = std::sin(kx * dx / 2);
      var_dx += sk * 4 * sx * sx;
    }
  a[0] = 0.0;
  // Inverse 2D FFT (rows, then columns; Eigen's inv includes 1/n per dimension).
  tbb::parallel_for(0, n, [&](int j) {
    Eigen::FFT<double> fft;
    std::vector<C> in(a.begin() + static_cast<long>(j) * n, a.begin() + static_cast<long>(j + 1) * n), out;
    fft.inv(out, in);
    std::copy(out.begin(), out.end(), a.begin() + static_cast<long>(j) * n);
  });
  tbb::parallel_for(0, n, [&](int i) {
    Eigen::FFT<double> fft;
    std::vector<C> in(n), out;
    for (int j = 0; j < n; ++j) in[j] = a[static_cast<std::size_t>(j) * n + i];
    fft.inv(out, in);
    for (int j = 0; j < n; ++j) a[static_cast<std::size_t>(j) * n + i] = out[j];
  });
  // Expected Var[h(x + dx) - h(x)] = (1/n^4) sum_k S 4 sin^2(kx dx / 2) (E|W|^2 = 2, halved by
  // the real part); scaled to alpha^2 dx^2 / 2.
  var_dx /= static_cast<double>(n) * n * n * n;
  const double scale = std::sqrt(0.5 * alpha * alpha * dx * dx / var_dx);
  std::vector<double> h(a.size());
  for (std::size_t k = 0; k < a.size(); ++k) h[k] = scale * a[k].real();
  return h;
}

// The Beckmann tile of generate_gaussian (same spectrum and scaling), on common random numbers.
Microsurface nested_beckmann_tile(int n, double ell, double alpha, std::uint64_t seed) {
  const double size = 1.0, dx = size / n;
  const std::vector<double> f = nested_field(n, ell, alpha, seed, 0xC0417E);
  std::vector<float> h(f.begin(), f.end());
  Microsurface s = Microsurface::heightfield(n, n, size, size, std::move(h));
  s.nominal = models::Ndf::beckmann(alpha, alpha);
  s.description = {{"kind", "gaussian"}, {"synthesis", "frequency-keyed noise (common across grids)"},
                   {"resolution", n}, {"size", size}, {"correlation_length", ell},
                   {"alpha_x", alpha}, {"alpha_y", alpha}, {"seed", seed}, {"nominal_ndf", "beckmann"}};
  add_discretization(s.description, dx, size, ell, ell);
  return s;
}

// The GGX heightfield of generate_gaussian_ggx (a Beckmann field g of length l whose local
// roughness alpha / sqrt(E) varies over `big`, E taking exactly the Exp(1) quantiles over the
// tile by the ranks of a smooth field z), with g and z on common random numbers: on every grid
// E(x) is the empirical quantile of the same continuous z, so the grids are paired here too.
Microsurface nested_ggx_tile(int n, double ell, double big, double alpha, double tail, std::uint64_t seed) {
  const double size = 1.0, dx = size / n;
  const std::vector<double> g = nested_field(n, ell, alpha, seed, 0xC0417E);
  const std::vector<double> z = nested_field(n, big, 1.0, seed, 0xC0418E);
  const std::size_t count = g.size();
  std::vector<std::uint32_t> order(count);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
    return z[p] < z[q] || (z[p] == z[q] && p < q);
  });
  const double e_min = -std::log1p(-tail);
  std::vector<float> h(count);
  for (std::size_t r = 0; r < count; ++r) {
    const double u = (static_cast<double>(r) + 0.5) / static_cast<double>(count);
    const double e = std::max(e_min, -std::log1p(-u));
    h[order[r]] = static_cast<float>(g[order[r]] / std::sqrt(e));
  }
  Microsurface s = Microsurface::heightfield(n, n, size, size, std::move(h));
  s.nominal = models::Ndf::ggx(alpha, alpha);
  s.description = {{"kind", "gaussian-ggx"}, {"synthesis", "frequency-keyed noise (common across grids)"},
                   {"resolution", n}, {"size", size}, {"correlation_length", ell},
                   {"roughness_correlation_length", big}, {"alpha_x", alpha}, {"alpha_y", alpha},
                   {"tail_fraction", tail}, {"seed", seed}, {"nominal_ndf", "ggx"}};
  add_discretization(s.description, dx, size, ell, ell);
  return s;
}

// Median of tan(theta_m) over the projected area (every facet of a heightfield projects to
// dx^2 / 2): the NDF's alpha without its second moment, which GGX does not have. GGX:
// P(tan theta_m < t) = t^2 / (alpha^2 + t^2), median alpha; Beckmann: 1 - exp(-t^2 / alpha^2),
// median alpha sqrt(ln 2).
double median_tan_theta_m(const Microsurface& s) {
  std::vector<float> t(s.num_facets());
  tbb::parallel_for(std::size_t{0}, t.size(), [&](std::size_t k) {
    const Vec3 m = s.facet(k).normal();
    t[k] = static_cast<float>(std::hypot(m.x(), m.y()) / m.z());
  });
  auto mid = t.begin() + static_cast<long>(t.size() / 2);
  std::nth_element(t.begin(), mid, t.end());
  return *mid;
}

Microsurface make_tile(const Args& a, std::uint64_t seed, Json& desc) {
  const int n = a.cells_per_l * a.lengths_per_tile;
  const double ell = 1.0 / a.lengths_per_tile;
  if (a.kind == "gaussian" && a.nested) {
    Microsurface s = nested_beckmann_tile(n, ell, a.alpha, seed);
    desc = s.description;
    return s;
  }
  if (a.kind == "gaussian") {
    GaussianParams p;
    p.resolution = n;
    p.size = 1.0;
    p.correlation_length = ell;
    p.alpha_x = p.alpha_y = a.alpha;
    p.seed = seed;
    Microsurface s = generate_gaussian(p);
    desc = s.description;
    return s;
  }
  if (a.kind == "gaussian-ggx" && a.nested) {
    // The preset's roughness length (16 l, surfaces/gaussian-ggx.toml) where the tile holds it
    // at least four times, else a quarter tile; the preset's tail fraction.
    Microsurface s = nested_ggx_tile(n, ell, std::min(16 * ell, 0.25), a.alpha, 0.001, seed);
    desc = s.description;
    return s;
  }
  if (a.kind == "gaussian-ggx") {
    GaussianGgxParams p;
    p.resolution = n;
    p.size = 1.0;
    p.correlation_length = ell;
    // The roughness field's own length: 16 l where the tile holds it twice, else a quarter tile.
    p.roughness_correlation_length = std::min(16 * ell, 0.25);
    p.alpha_x = p.alpha_y = a.alpha;
    p.seed = seed;
    Microsurface s = generate_gaussian_ggx(p);
    desc = s.description;
    return s;
  }
  std::fprintf(stderr, "--kind must be gaussian or gaussian-ggx\n");
  std::exit(2);
}

Json measure_tile(const Args& a, std::uint64_t seed, int K) {
  Json t;
  t["seed"] = seed;
  auto t0 = std::chrono::steady_clock::now();
  Json desc;
  Microsurface s = make_tile(a, seed, desc);
  t["description"] = desc;
  t["generate_seconds"] = seconds_since(t0);
  const models::Ndf nominal = *s.nominal;

  // Fitted alpha (slope-variance moment) and D per 5-degree ring, exact from the facets.
  NdfOptions no;
  no.n_theta = 36;
  no.n_phi = 1;
  NdfResult nd = measure_ndf(s, no);
  t["alpha_fit_x"] = std::sqrt(2 * nd.sums.slope_var_x);
  t["alpha_fit_y"] = std::sqrt(2 * nd.sums.slope_var_y);
  t["alpha_fit"] = std::sqrt(nd.sums.slope_var_x + nd.sums.slope_var_y);
  t["median_tan_theta_m"] = median_tan_theta_m(s);
  Json rings = Json::array();
  for (int i = 0; i < 18; ++i) rings.push_back(nd.ring_d[i]);
  t["d_ring"] = rings;

  auto t1 = std::chrono::steady_clock::now();
  Tracer tracer(s);
  t["build_seconds"] = seconds_since(t1);
  const std::uint64_t rg = std::max<std::uint64_t>(a.rays_g / K, 64 * 32);
  const std::uint64_t rb = std::max<std::uint64_t>(a.rays_bsdf / K, 64 * 32);

  // G1 at 80 deg: averaged (area sampling; ray casting equals 1/(1 + Lambda_facets) on a
  // periodic heightfield) and per normal bin (10-degree rings, 45-degree sectors).
  {
    G1Options o;
    o.rays = rg;
    o.seed = seed;
    const Vec3 v = direction_from_angles(rad(80), 0);
    G1Result r = measure_g1(tracer, v, o);
    t["g1_80"] = est(r.g1_area_sampling());
    t["g1_80_smith_facets"] = 1.0 / (1.0 + r.lambda_numeric);
    Json bins = Json::array();
    for (int b = 0; b < r.binning.size(); ++b) {
      if (r.bins[b].samples < 100) continue;
      const int it = b / r.binning.n_phi(), ip = b % r.binning.n_phi();
      bins.push_back({{"theta_lo", r.binning.theta_lo(it) * 180 / kPi},
                      {"phi_lo", r.binning.phi_lo(ip) * 180 / kPi},
                      {"g1", est(r.bin_g1_area_sampling(b))},
                      {"samples", r.bins[b].samples}});
    }
    t["g1_80_bins"] = bins;
  }
  // G2 at theta_o = theta_i = 70 deg, same azimuth (= G1) and opposite azimuths.
  for (double dphi : {0.0, 180.0}) {
    G2Options o;
    o.rays = rg;
    o.seed = seed;
    G2Result r = measure_g2(tracer, direction_from_angles(rad(70), 0),
                            direction_from_angles(rad(70), rad(dphi)), o);
    t[dphi == 0 ? "g2_70_70_dphi0" : "g2_70_70_dphi180"] = est(r.g2());
  }
  // VNDF at 80 deg: chi-square per degree of freedom of the first-hit normals against the
  // nominal D_v [Heitz14, eq. 13], 5-degree rings x 22.5-degree sectors.
  {
    VndfOptions o;
    o.rays = rg;
    o.seed = seed;
    const Vec3 v = direction_from_angles(rad(80), 0);
    VndfResult r = measure_vndf(tracer, v, o);
    std::vector<double> p =
        bin_integrals(r.binning, [&](const Vec3& m) { return nominal.D_visible(v, m); });
    GofResult g = histogram_gof(r.bin_hits, r.hits, p, o.family_alpha);
    t["vndf_80_chi2_per_dof"] = g.dof > 0 ? g.chi2 / g.dof : 0.0;
    t["vndf_80_dof"] = g.dof;
    // chi2/dof grows with the ray count; (chi2 - dof) / N estimates the chi-square divergence
    // sum_B (p_B - P_B)^2 / P_B of the surface's VNDF from the nominal one, at any ray count.
    t["vndf_80_divergence"] = (g.chi2 - g.dof) / static_cast<double>(r.hits);
    t["vndf_80_rays"] = r.rays;
  }
  // Mirror per order at 0, 60, 80 deg (in-plane lobe at 80 deg: 36 bins of 5 degrees).
  for (double th : {0.0, 60.0, 80.0}) {
    BsdfOptions o;
    o.material = models::Material::mirror();
    o.theta_i = rad(th);
    o.rays = rb;
    o.seed = seed;
    o.models = false;
    o.resolution = 36;
    BsdfResult r = measure_bsdf(tracer, o);
    const std::string key = "mirror_" + std::to_string(static_cast<int>(th));
    t[key] = albedos(r, 0);
    t[key + "_lost"] = r.measured.lost + r.measured.unterminated;
    if (th == 80.0) {
      Json lobe1 = Json::array(), lobe = Json::array();
      for (int b = 0; b < r.plane.size(); ++b) {
        lobe1.push_back(est(r.f_plane(0, 0, b)));
        lobe.push_back(est(r.f_plane(0, o.orders, b)));
      }
      t["lobe_80_order_1"] = lobe1;
      t["lobe_80_total"] = lobe;
    }
  }
  // Dielectric eta = 1.5 at 0 and 60 deg.
  for (double th : {0.0, 60.0}) {
    BsdfOptions o;
    o.material = models::Material::dielectric(1.5);
    o.theta_i = rad(th);
    o.rays = rb;
    o.seed = seed;
    o.models = false;
    o.resolution = 8;
    BsdfResult r = measure_bsdf(tracer, o);
    const std::string key = "dielectric_" + std::to_string(static_cast<int>(th));
    t[key + "_reflected"] = albedos(r, 0);
    t[key + "_transmitted"] = albedos(r, 1);
  }
  t["seconds"] = seconds_since(t0);
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(stderr, "%s needs a value\n", k.c_str());
      return 2;
    }
    const char* v = argv[++i];
    if (k == "--kind") a.kind = v;
    else if (k == "--alpha") a.alpha = std::atof(v);
    else if (k == "--cells-per-l") a.cells_per_l = std::atoi(v);
    else if (k == "--lengths-per-tile") a.lengths_per_tile = std::atoi(v);
    else if (k == "--surfaces") a.surfaces = std::atoi(v);
    else if (k == "--rays-bsdf") a.rays_bsdf = std::strtoull(v, nullptr, 10);
    else if (k == "--rays-g") a.rays_g = std::strtoull(v, nullptr, 10);
    else if (k == "--smith-walks") a.smith_walks = std::strtoull(v, nullptr, 10);
    else if (k == "--seed") a.seed0 = std::strtoull(v, nullptr, 10);
    else if (k == "--nested") a.nested = std::atoi(v) != 0;
    else if (k == "-o") a.out = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  if (a.out.empty() || a.surfaces < 1 || a.cells_per_l < 1 || a.lengths_per_tile < 4) {
    std::fprintf(stderr, "usage: convergence --kind K --alpha A --cells-per-l C --lengths-per-tile T "
                         "--surfaces K --rays-bsdf N --rays-g N [--smith-walks N] -o OUT.json\n");
    return 2;
  }
  try {
    auto t0 = std::chrono::steady_clock::now();
    Json j;
    j["kind"] = a.kind;
    j["alpha"] = a.alpha;
    j["cells_per_correlation_length"] = a.cells_per_l;
    j["correlation_lengths_per_tile"] = a.lengths_per_tile;
    j["resolution"] = a.cells_per_l * a.lengths_per_tile;
    j["surfaces"] = a.surfaces;
    j["nested"] = a.nested;
    j["rays_bsdf_per_level"] = a.rays_bsdf;
    j["rays_g_per_level"] = a.rays_g;
    const models::Ndf nominal = a.kind == "gaussian" ? models::Ndf::beckmann(a.alpha, a.alpha)
                                                     : models::Ndf::ggx(a.alpha, a.alpha);
    // Nominal D per 5-degree ring (ring averages over the solid angle).
    DirectionBinning rings(36, 1, kPi);
    Json dn = Json::array();
    for (int i = 0; i < 18; ++i)
      dn.push_back(rings.bin_average(rings.index(i, 0), [&](const Vec3& m) { return nominal.D(m); }));
    j["d_ring_nominal"] = dn;
    j["tiles"] = Json::array();
    for (int k = 0; k < a.surfaces; ++k) {
      j["tiles"].push_back(measure_tile(a, a.seed0 + static_cast<std::uint64_t>(k), a.surfaces));
      std::fprintf(stderr, "  tile %d/%d done (%.1f s)\n", k + 1, a.surfaces,
                   j["tiles"].back()["seconds"].get<double>());
    }
    // The Smith random walk of the nominal NDF (no surface involved): mirror per order.
    if (a.smith_walks > 0) {
      Json desc;
      Microsurface s = make_tile(a, a.seed0, desc);
      Tracer tracer(s);
      for (double th : {0.0, 60.0, 80.0}) {
        BsdfOptions o;
        o.material = models::Material::mirror();
        o.theta_i = rad(th);
        o.rays = 64 * 32;
        o.model_walks = a.smith_walks;
        o.resolution = 8;
        BsdfResult r = measure_bsdf(tracer, o);
        Json m = Json::array();
        for (int k = 0; k <= o.orders; ++k) m.push_back(est(r.model_albedo(0, k)));
        j["smith_walk_mirror_" + std::to_string(static_cast<int>(th))] = m;
      }
    }
    j["seconds"] = seconds_since(t0);
    write_stream_atomically(a.out, [&](std::ofstream& f) { f << j.dump(1) << "\n"; });
  } catch (const std::exception& e) {
    std::fprintf(stderr, "convergence: %s\n", e.what());
    return 1;
  }
  return 0;
}
