#include "microsim/surface/gaussian.hpp"

#include "microsim/io/checks.hpp"
#include "microsim/surface/discretization.hpp"

#include <unsupported/Eigen/FFT>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <complex>
#include <numeric>
#include <sstream>

namespace microsim {

double gaussian_memory_estimate(int resolution) {
  const double n2 = static_cast<double>(resolution) * resolution;
  // At the peak, the complex<double> work array of the synthesis (16 bytes per cell) and the
  // float heights copied out of it (4); the EXR is then written from the heights themselves.
  // Plus the process and the FFTs' row buffers (the tracing costs are checked when a tile is
  // loaded for a measurement).
  return n2 * (16.0 + 4.0) + 64.0 * (1 << 20);
}

double gaussian_ggx_memory_estimate(int resolution) {
  const double n2 = static_cast<double>(resolution) * resolution;
  // Two fields in double (8 + 8), the second one's complex work array while it is made (16),
  // then the rank order (4) and the float heights (4).
  return n2 * (8.0 + 8.0 + 16.0) + 64.0 * (1 << 20);
}

double default_correlation_length(int resolution, double size) {
  const double dx = size / resolution;
  return std::max(4.0 * dx, std::min(16.0 * dx, size / 16.0));
}

void validate(const GaussianParams& p) {
  if (!(p.alpha_x > 0) || !(p.alpha_y > 0) || !std::isfinite(p.alpha_x) ||
      !std::isfinite(p.alpha_y) || p.alpha_x > 10 || p.alpha_y > 10)
    throw ParameterError("{alpha}/{alpha_x}/{alpha_y} must be in (0, 10]");
  if (p.resolution < 4) throw ParameterError("{resolution} must be at least 4 (got " +
                                             std::to_string(p.resolution) + ")");
  if (p.resolution > 32760)
    throw ParameterError("{resolution} must be at most 32760 (Embree grid limit); got " +
                         std::to_string(p.resolution));
  require_memory(gaussian_memory_estimate(p.resolution), "{resolution} " + std::to_string(p.resolution));
  if (!(p.size > 0) || !std::isfinite(p.size)) throw ParameterError("{size} must be > 0");
  double dx = p.size / p.resolution;
  if (p.correlation_length != 0.0 &&
      !(p.correlation_length >= dx && p.correlation_length <= 0.25 * p.size))
    throw ParameterError("{correlation_length} must be in [size/resolution, size/4]");
}

namespace {
using Complex = std::complex<double>;

// In-place 2D FFT of an n x n row-major array, as rows then columns (Eigen's FFT is 1D).
void fft2d(std::vector<Complex>& a, int n, bool inverse) {
  tbb::parallel_for(0, n, [&](int j) {
    Eigen::FFT<double> fft;
    std::vector<Complex> in(a.begin() + static_cast<long>(j) * n,
                            a.begin() + static_cast<long>(j + 1) * n),
        out;
    if (inverse) fft.inv(out, in); else fft.fwd(out, in);
    std::copy(out.begin(), out.end(), a.begin() + static_cast<long>(j) * n);
  });
  tbb::parallel_for(0, n, [&](int i) {
    Eigen::FFT<double> fft;
    std::vector<Complex> in(n), out;
    for (int j = 0; j < n; ++j) in[j] = a[static_cast<std::size_t>(j) * n + i];
    if (inverse) fft.inv(out, in); else fft.fwd(out, in);
    for (int j = 0; j < n; ++j) a[static_cast<std::size_t>(j) * n + i] = out[j];
  });
}

// One periodic Gaussian field on an n x n grid (tile side `size`), spectrum of the Gaussian
// autocorrelation exp(-(x^2/lx^2 + y^2/ly^2)), scaled so that the expected finite-difference
// slope variance along x is alpha_x^2 / 2. The synthesis leaves the unscaled field in the real
// parts of `a`; the field is scale * a[k].real(), which the callers copy out in the precision
// they keep (the complex work array is the peak of the generator: 16 bytes per cell).
struct GaussianSpectrum {
  std::vector<Complex> a;
  double scale = 1;
  double var_dy_scaled = 0;  // expected finite-difference slope variance along y after scaling
};
GaussianSpectrum gaussian_spectrum(int n, double size, double ell_x, double ell_y, double alpha_x,
                                   std::uint64_t seed, std::uint64_t stream) {
  const double dx = size / n;
  // White noise from the counter-based generator (Box-Muller), deterministic for any threads.
  GaussianSpectrum f;
  std::vector<Complex>& a = f.a;
  a.resize(static_cast<std::size_t>(n) * n);
  tbb::parallel_for(0, n, [&](int j) {
    for (int i = 0; i < n; ++i) {
      CounterRng rng(seed, stream, static_cast<std::uint64_t>(j) * n + i);
      double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
      a[static_cast<std::size_t>(j) * n + i] =
          std::sqrt(-2.0 * std::log(u1)) * std::cos(2 * kPi * u2);
    }
  });
  fft2d(a, n, false);

  // Filter H(k) = sqrt(S(k)), S(k) ~ exp(-(kx^2 lx^2 + ky^2 ly^2)/4) for C(r) = exp(-r^2/l^2).
  // Expected finite-difference variances (unit-variance noise, Eigen's unnormalised fwd):
  //   Var[h(i+1,j) - h(i,j)] = (1/n^2) sum_k |H(k)|^2 4 sin^2(kx dx / 2).
  std::vector<double> kfreq(n);
  for (int i = 0; i < n; ++i) kfreq[i] = 2 * kPi * ((i <= n / 2) ? i : i - n) / size;
  double var_dx = 0, var_dy = 0;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      double kx = kfreq[i], ky = kfreq[j];
      double s = std::exp(-(kx * kx * ell_x * ell_x + ky * ky * ell_y * ell_y) / 4.0);
      a[static_cast<std::size_t>(j) * n + i] *= std::sqrt(s);
      double sx = std::sin(kx * dx / 2), sy = std::sin(ky * dx / 2);
      var_dx += s * 4 * sx * sx;
      var_dy += s * 4 * sy * sy;
    }
  }
  var_dx /= static_cast<double>(n) * n;
  var_dy /= static_cast<double>(n) * n;
  a[0] = 0.0;  // zero mean height (does not affect slopes)
  fft2d(a, n, true);

  // Expected slope variance along x is var_dx / dx^2; scale to alpha_x^2 / 2.
  f.scale = std::sqrt(0.5 * alpha_x * alpha_x * dx * dx / var_dx);
  f.var_dy_scaled = var_dy * f.scale * f.scale / (dx * dx);
  return f;
}

// The field in double (gaussian-ggx combines two fields before rounding to float).
struct GaussianField {
  std::vector<double> h;
  double var_dy_scaled = 0;
};
GaussianField gaussian_field(int n, double size, double ell_x, double ell_y, double alpha_x,
                             std::uint64_t seed, std::uint64_t stream) {
  GaussianSpectrum sp = gaussian_spectrum(n, size, ell_x, ell_y, alpha_x, seed, stream);
  GaussianField f;
  f.h.resize(sp.a.size());
  for (std::size_t k = 0; k < sp.a.size(); ++k) f.h[k] = sp.scale * sp.a[k].real();
  f.var_dy_scaled = sp.var_dy_scaled;
  return f;
}

// Correlation lengths (l_x, l_y) giving expected finite-difference slope variances in the ratio
// alpha_x^2 : alpha_y^2 on this grid. The spectrum exp(-(kx^2 lx^2 + ky^2 ly^2)/4) is
// separable, so Var[dh_y] / Var[dh_x] = g(l_y) / g(l_x) with
//   g(l) = sum_k e^{-k^2 l^2/4} 4 sin^2(k dx/2) / sum_k e^{-k^2 l^2/4},
// decreasing in l. The rougher axis keeps l (at least 4 cells by default: resolved); the
// smoother axis gets the longer length that solves the ratio (bisection). A continuum rule such
// as l_y = l alpha_x/alpha_y is not enough: a short length is under-resolved by the grid.
std::pair<double, double> anisotropic_lengths(int n, double size, double ell, double alpha_x,
                                              double alpha_y) {
  if (alpha_x == alpha_y) return {ell, ell};
  const double dx = size / n;
  auto g = [&](double l) {
    double num = 0, den = 0;
    for (int i = 0; i < n; ++i) {
      double k = 2 * kPi * ((i <= n / 2) ? i : i - n) / size;
      double w = std::exp(-k * k * l * l / 4), s = std::sin(k * dx / 2);
      num += w * 4 * s * s;
      den += w;
    }
    return num / den;
  };
  const double rough = std::max(alpha_x, alpha_y), smooth = std::min(alpha_x, alpha_y);
  const double target = g(ell) * (smooth * smooth) / (rough * rough);
  double lo = ell, hi = 0.5 * size;
  if (g(hi) > target)
    throw ParameterError("{alpha_x}/{alpha_y}: anisotropy " + std::to_string(rough / smooth) +
                         " too strong for this tile and correlation length");
  for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
    double mid = 0.5 * (lo + hi);
    if (g(mid) > target) lo = mid; else hi = mid;
  }
  const double longer = 0.5 * (lo + hi);
  return alpha_x > alpha_y ? std::make_pair(ell, longer) : std::make_pair(longer, ell);
}
}  // namespace

Microsurface generate_gaussian(const GaussianParams& p) {
  validate(p);
  const int n = p.resolution;
  const double dx = p.size / n;
  const double ell = p.correlation_length > 0 ? p.correlation_length : default_correlation_length(n, p.size);
  // Anisotropy by the spectrum's shape (exact on the grid); the x scale fixes the amplitude.
  const auto [ell_x, ell_y] = anisotropic_lengths(n, p.size, ell, p.alpha_x, p.alpha_y);
  // The float heights straight from the work array (the same rounding of the same double
  // scale * a.real() as through a double copy, without that copy's 8 bytes per cell); the work
  // array is released before the surface is returned (and written).
  std::vector<float> h;
  double var_dy_scaled = 0;
  {
    GaussianSpectrum sp = gaussian_spectrum(n, p.size, ell_x, ell_y, p.alpha_x, p.seed, 0x6A05);
    h.resize(sp.a.size());
    const double scale = sp.scale;
    const Complex* a = sp.a.data();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, h.size(), 1 << 16),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t k = r.begin(); k != r.end(); ++k)
                          h[k] = static_cast<float>(scale * a[k].real());
                      });
    var_dy_scaled = sp.var_dy_scaled;
  }
  Microsurface s = Microsurface::heightfield(n, n, p.size, p.size, std::move(h));
  s.nominal = models::Ndf::beckmann(p.alpha_x, p.alpha_y);
  s.description = {{"kind", "gaussian"},
                   {"resolution", n},
                   {"size", p.size},
                   {"correlation_length", ell},
                   {"correlation_length_x", ell_x},
                   {"correlation_length_y", ell_y},
                   {"alpha_x", p.alpha_x},
                   {"alpha_y", p.alpha_y},
                   {"seed", p.seed},
                   {"nominal_ndf", "beckmann"},
                   {"expected_slope_var_y", var_dy_scaled}};
  add_discretization(s.description, dx, p.size, std::min(ell_x, ell_y), std::max(ell_x, ell_y));
  return s;
}

Microsurface generate_gaussian_ggx(const GaussianGgxParams& p) {
  GaussianParams base;
  base.resolution = p.resolution;
  base.size = p.size;
  base.correlation_length = p.correlation_length;
  base.alpha_x = p.alpha_x;
  base.alpha_y = p.alpha_y;
  base.seed = p.seed;
  validate(base);
  require_memory(gaussian_ggx_memory_estimate(p.resolution), "{resolution} " + std::to_string(p.resolution));
  const int n = p.resolution;
  const double dx = p.size / n;
  const double ell = p.correlation_length > 0 ? p.correlation_length : default_correlation_length(n, p.size);
  const double big = p.roughness_correlation_length > 0 ? p.roughness_correlation_length
                                                        : std::min(16 * ell, 0.25 * p.size);
  if (!(big >= ell && big <= 0.5 * p.size))
    throw ParameterError("{roughness_correlation_length} must be in [correlation length, size/2] (got " +
                         std::to_string(big) + ")");
  if (!(p.tail_fraction > 0 && p.tail_fraction < 0.5))
    throw ParameterError("{tail_fraction} must be in (0, 0.5) (got " + std::to_string(p.tail_fraction) + ")");

  // g: Beckmann(alpha_x, alpha_y) field, exactly as generate_gaussian.
  const auto [ell_x, ell_y] = anisotropic_lengths(n, p.size, ell, p.alpha_x, p.alpha_y);
  GaussianField g = gaussian_field(n, p.size, ell_x, ell_y, p.alpha_x, p.seed, 0x6A05);
  // z: smooth isotropic field of correlation length L; only its ranks are used.
  GaussianField z = gaussian_field(n, p.size, big, big, 1.0, p.seed, 0x6A06);
  const std::size_t count = g.h.size();
  std::vector<std::uint32_t> order(count);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return z.h[a] < z.h[b] || (z.h[a] == z.h[b] && a < b);
  });
  // Rank r -> the (r + 1/2)/count quantile of Exp(1): E = -ln(1 - u). Over the tile, E takes
  // exactly the Exp(1) quantiles, so the pooled slope density is the GGX mixture
  // int P22_Beckmann(s; alpha/sqrt(E)) e^-E dE = P22_GGX(s; alpha) up to the floor below.
  const double e_min = -std::log1p(-p.tail_fraction);
  std::vector<float> h(count);
  for (std::size_t r = 0; r < count; ++r) {
    double u = (static_cast<double>(r) + 0.5) / static_cast<double>(count);
    double e = std::max(e_min, -std::log1p(-u));
    std::uint32_t k = order[r];
    h[k] = static_cast<float>(g.h[k] / std::sqrt(e));  // local roughness alpha / sqrt(E)
  }
  Microsurface s = Microsurface::heightfield(n, n, p.size, p.size, std::move(h));
  s.nominal = models::Ndf::ggx(p.alpha_x, p.alpha_y);
  s.description = {{"kind", "gaussian-ggx"},
                   {"resolution", n},
                   {"size", p.size},
                   {"correlation_length", ell},
                   {"roughness_correlation_length", big},
                   {"alpha_x", p.alpha_x},
                   {"alpha_y", p.alpha_y},
                   {"tail_fraction", p.tail_fraction},
                   {"max_local_alpha_factor", 1.0 / std::sqrt(e_min)},
                   {"seed", p.seed},
                   {"nominal_ndf", "ggx"}};
  add_discretization(s.description, dx, p.size, std::min(ell_x, ell_y), std::max(ell_x, ell_y));
  return s;
}

}  // namespace microsim
