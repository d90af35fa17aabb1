#include "microsim/surface/metrology.hpp"

#include <unsupported/Eigen/FFT>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <utility>

namespace microsim {

namespace {
using Complex = std::complex<double>;

// In-place 2D FFT of a w x h row-major array (rows, then columns). Every 1D transform is the
// same computation whichever thread does it, so the result does not depend on the thread count.
// Columns are gathered four at a time (four neighbouring columns share a cache line).
void fft2d(std::vector<Complex>& a, int w, int h, bool inverse) {
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 16), [&](const tbb::blocked_range<int>& r) {
    Eigen::FFT<double> fft;
    std::vector<Complex> in(w), out(w);
    for (int j = r.begin(); j != r.end(); ++j) {
      Complex* row = a.data() + static_cast<std::size_t>(j) * w;
      std::copy(row, row + w, in.begin());
      if (inverse) fft.inv(out, in); else fft.fwd(out, in);
      std::copy(out.begin(), out.end(), row);
    }
  });
  constexpr int kCols = 4;
  tbb::parallel_for(tbb::blocked_range<int>(0, (w + kCols - 1) / kCols, 4), [&](const tbb::blocked_range<int>& r) {
    Eigen::FFT<double> fft;
    std::vector<std::vector<Complex>> in(kCols, std::vector<Complex>(h));
    std::vector<Complex> out(h);
    for (int b = r.begin(); b != r.end(); ++b) {
      const int i0 = b * kCols, i1 = std::min(w, i0 + kCols);
      for (int j = 0; j < h; ++j)
        for (int i = i0; i < i1; ++i) in[i - i0][j] = a[static_cast<std::size_t>(j) * w + i];
      for (int i = i0; i < i1; ++i) {
        if (inverse) fft.inv(out, in[i - i0]); else fft.fwd(out, in[i - i0]);
        in[i - i0] = out;
      }
      for (int j = 0; j < h; ++j)
        for (int i = i0; i < i1; ++i) a[static_cast<std::size_t>(j) * w + i] = in[i - i0][j];
    }
  });
}

// Standard normal quantile by bisection on the CDF (only a few dozen calls).
double normal_quantile(double p) {
  double lo = -40, hi = 40;
  for (int it = 0; it < 200; ++it) {
    double mid = 0.5 * (lo + hi);
    if (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p) lo = mid; else hi = mid;
  }
  return 0.5 * (lo + hi);
}

// Sums over a sample in blocks of kBlock values: each block summed in order from zero (in
// parallel), the block sums then added in block order. The result does not depend on the
// thread count, and a sample of at most kBlock values is summed exactly as one serial loop.
constexpr std::size_t kBlock = std::size_t{1} << 16;

template <class Acc, class Block>
Acc block_sum(std::size_t n, const Acc& zero, const Block& block) {  // block(k0, k1, acc)
  const std::size_t nb = (n + kBlock - 1) / kBlock;
  std::vector<Acc> part(nb, zero);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) block(b * kBlock, std::min(n, (b + 1) * kBlock), part[b]);
  });
  Acc total = zero;
  for (const Acc& p : part) total += p;
  return total;
}

struct Sum2 {
  double a = 0, b = 0;
  Sum2& operator+=(const Sum2& o) {
    a += o.a;
    b += o.b;
    return *this;
  }
};
struct Sum3 {
  double a = 0, b = 0, c = 0;
  Sum3& operator+=(const Sum3& o) {
    a += o.a;
    b += o.b;
    c += o.c;
    return *this;
  }
};
struct Counts {
  std::vector<double> v;
  Counts& operator+=(const Counts& o) {
    for (std::size_t k = 0; k < v.size(); ++k) v[k] += o.v[k];
    return *this;
  }
};

// Counts of the n values value(0), ..., value(n - 1) in bins [edges[k], edges[k+1]) against
// equal expected counts n / bins. The values are computed when counted: large grids keep no
// per-facet copy of them. `each(k0, k1, f)` calls f(value) for the values k0 .. k1 - 1.
template <class Each>
HistogramFit equal_probability_fit(const std::string& model, std::vector<double> edges, std::size_t n,
                                   const Each& each, int fitted_parameters) {
  HistogramFit f;
  f.model = model;
  const int bins = static_cast<int>(edges.size()) - 1;
  // Counts are integers (exact in a double): the same for any block order.
  const Counts c = block_sum(n, Counts{std::vector<double>(bins, 0.0)},
                             [&](std::size_t k0, std::size_t k1, Counts& acc) {
                               each(k0, k1, [&](double v) {
                                 const int k = static_cast<int>(
                                     std::upper_bound(edges.begin() + 1, edges.end() - 1, v) - (edges.begin() + 1));
                                 acc.v[k] += 1;
                               });
                             });
  f.observed = c.v;
  const double e = static_cast<double>(n) / bins;
  f.expected.assign(bins, e);
  for (int k = 0; k < bins; ++k) f.chi2 += (f.observed[k] - e) * (f.observed[k] - e) / e;
  f.dof = bins - 1 - fitted_parameters;
  f.edges = std::move(edges);
  return f;
}

double at(const HeightGridView& g, int i, int j) {
  return (*g.z)[static_cast<std::size_t>(j) * g.nx + i];
}

Json fit_json(const HistogramFit& f) {
  if (f.model.empty()) return nullptr;
  Json edges = Json::array();
  for (double e : f.edges) edges.push_back(std::isfinite(e) ? Json(e) : Json("inf"));
  return {{"model", f.model}, {"chi2", f.chi2}, {"dof", f.dof}, {"chi2_per_dof", f.chi2_per_dof()},
          {"bin_edges", edges}, {"observed", f.observed}, {"expected", f.expected}};
}

// A sample of slopes held in memory.
struct ListedSlopes {
  const std::vector<std::array<double, 2>>* s;
  std::size_t size() const { return s->size(); }
  template <class F>
  void each(std::size_t k0, std::size_t k1, F&& f) const {  // f(s_x, s_y) for slopes k0 .. k1 - 1
    for (std::size_t k = k0; k < k1; ++k) f((*s)[k][0], (*s)[k][1]);
  }
};

// x / d, as a multiplication when d is a power of two (then 1 / d is exact and both give the
// same correctly rounded x 2^-k): a generated tile's cell size usually is one.
struct Divide {
  double d, inv;
  bool by_power_of_two;
  explicit Divide(double den) : d(den), inv(1.0 / den) {
    int e = 0;
    by_power_of_two = std::frexp(den, &e) == 0.5;
  }
  double operator()(double x) const { return by_power_of_two ? x * inv : x / d; }
};

// The facet slopes of a grid, computed from the heights whenever a pass needs them (16 bytes
// per facet not held): facet 2 (j cx + i) + half, in the order and with the arithmetic of
// facet_slopes. Cell by cell, row by row (one integer division per row).
struct GridSlopes {
  const HeightGridView* g;
  std::size_t cx = 0, cy = 0;  // cells
  Divide by_dx, by_dy;
  explicit GridSlopes(const HeightGridView& grid) : g(&grid), by_dx(grid.dx), by_dy(grid.dy) {
    const int x = g->periodic ? g->nx : g->nx - 1, y = g->periodic ? g->ny : g->ny - 1;
    if (x > 0 && y > 0) {
      cx = static_cast<std::size_t>(x);
      cy = static_cast<std::size_t>(y);
    }
  }
  std::size_t size() const { return 2 * cx * cy; }
  template <class F>
  void each(std::size_t k0, std::size_t k1, F&& f) const {  // f(s_x, s_y) for facets k0 .. k1 - 1
    if (k0 >= k1) return;
    const float* z = g->z->data();
    const std::size_t nx = static_cast<std::size_t>(g->nx), ny = static_cast<std::size_t>(g->ny);
    const std::size_t c1 = (k1 + 1) / 2;  // past the last cell touched
    for (std::size_t c = k0 / 2; c < c1;) {
      const std::size_t j = c / cx, end = std::min(c1, (j + 1) * cx);
      const float* r0 = z + j * nx;
      const float* r1 = z + (j + 1 == ny ? 0 : j + 1) * nx;
      for (std::size_t i = c - j * cx; c < end; ++c, ++i) {
        const std::size_t i1 = i + 1 == nx ? 0 : i + 1;
        const double z00 = r0[i], z10 = r0[i1], z01 = r1[i], z11 = r1[i1];
        // The planes of the two facets (v00, v10, v01) and (v10, v11, v01) of Microsurface::facet.
        if (2 * c >= k0) f(by_dx(z10 - z00), by_dy(z01 - z00));
        if (2 * c + 1 < k1) f(by_dx(z11 - z01), by_dy(z11 - z10));
      }
    }
  }
};

// The isotropic GGX maximum-likelihood equation's left side at alpha^2 = a2 (below).
template <class Src>
double ggx_score(const Src& src, double mean_x, double mean_y, double a2) {
  return block_sum(src.size(), 0.0, [&](std::size_t k0, std::size_t k1, double& sum) {
    src.each(k0, k1, [&](double sx, double sy) {
      const double x = sx - mean_x, y = sy - mean_y, v = x * x + y * y;
      sum += v / (a2 + v);
    });
  });
}

// Mean slope, rms slopes per axis, Sdq and the Beckmann alphas of the moments; returns the slope
// variances (vx, vy).
template <class Src>
std::pair<double, double> fill_slope_moments(const Src& src, SlopeStats& st, const Divide& by_n) {
  const Sum3 m = block_sum(st.n, Sum3{}, [&](std::size_t k0, std::size_t k1, Sum3& a) {
    src.each(k0, k1, [&](double sx, double sy) {
      a.a += by_n(sx);
      a.b += by_n(sy);
      a.c += by_n(sx * sx + sy * sy);
    });
  });
  st.mean_x = m.a;
  st.mean_y = m.b;
  const double sg2 = m.c;
  const Sum2 var = block_sum(st.n, Sum2{}, [&](std::size_t k0, std::size_t k1, Sum2& a) {
    src.each(k0, k1, [&](double sx, double sy) {
      a.a += by_n((sx - st.mean_x) * (sx - st.mean_x));
      a.b += by_n((sy - st.mean_y) * (sy - st.mean_y));
    });
  });
  st.rms_x = std::sqrt(var.a);
  st.rms_y = std::sqrt(var.b);
  st.sdq = std::sqrt(sg2);
  // Beckmann's slope variance per axis is alpha^2 / 2 ([GeomBSDF24, eq. 1b/1c] fitted alpha).
  st.beckmann_alpha_x = std::sqrt(2.0) * st.rms_x;
  st.beckmann_alpha_y = std::sqrt(2.0) * st.rms_y;
  return {var.a, var.b};
}

// Isotropic GGX by maximum likelihood: d/d alpha log L = 0 <=> sum r^2 / (alpha^2 + r^2) = n/2,
// whose left side decreases with alpha (bisection on log alpha). r^2 is recomputed in every
// pass rather than stored: 8 bytes per facet less at the peak. Unset (0) when half the slopes
// or more sit at the mean: the likelihood has no maximum then.
template <class Src>
void fit_isotropic_ggx(const Src& src, SlopeStats& st) {
  const double n = static_cast<double>(st.n);
  const std::size_t nonzero = static_cast<std::size_t>(
      block_sum(st.n, 0.0, [&](std::size_t k0, std::size_t k1, double& c) {
        src.each(k0, k1, [&](double sx, double sy) {
          const double x = sx - st.mean_x, y = sy - st.mean_y;
          c += x * x + y * y > 0;
        });
      }));
  if (!(2 * nonzero > st.n)) return;
  double lo = std::log(1e-12 + 1e-6 * st.sdq), hi = std::log(1e6 * (st.sdq + 1e-300));
  // Once a midpoint repeats an end that an earlier pass set, that pass's answer repeats too
  // and (lo, hi) stays as it is: the remaining passes of the 200 are skipped.
  bool lo_set = false, hi_set = false;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi), a2 = std::exp(2 * mid);
    if ((mid == lo && lo_set) || (mid == hi && hi_set)) break;
    if (ggx_score(src, st.mean_x, st.mean_y, a2) > 0.5 * n) {
      lo = mid;
      lo_set = true;
    } else {
      hi = mid;
      hi_set = true;
    }
  }
  st.ggx_alpha = std::exp(0.5 * (lo + hi));
}

// Anisotropic GGX: EM fixed point of the bivariate t with 2 degrees of freedom, started from
// the Beckmann moments (variances vx, vy); each step raises the likelihood. Returns (ax^2, ay^2).
template <class Src>
std::pair<double, double> fit_anisotropic_ggx(const Src& src, SlopeStats& st, double vx, double vy,
                                              const Divide& by_n) {
  double ax2 = vx * 2, ay2 = vy * 2;
  for (st.ggx_iterations = 1; st.ggx_iterations <= 2000; ++st.ggx_iterations) {
    const Sum2 e = block_sum(st.n, Sum2{}, [&](std::size_t k0, std::size_t k1, Sum2& a) {
      src.each(k0, k1, [&](double sx, double sy) {
        const double x = sx - st.mean_x, y = sy - st.mean_y;
        const double w = 4.0 / (1.0 + x * x / ax2 + y * y / ay2);
        a.a += by_n(w * x * x);
        a.b += by_n(w * y * y);
      });
    });
    const double nx2 = e.a, ny2 = e.b;
    const bool done = std::abs(nx2 - ax2) <= 1e-12 * ax2 && std::abs(ny2 - ay2) <= 1e-12 * ay2;
    ax2 = nx2;
    ay2 = ny2;
    if (done) break;
  }
  st.ggx_alpha_x = std::sqrt(ax2);
  st.ggx_alpha_y = std::sqrt(ay2);
  return {ax2, ay2};
}

// Goodness of fit of the Beckmann moments (variances vx, vy) and of the anisotropic GGX (ax2,
// ay2) on the normalized slope radius q, in `bins` classes of equal model probability:
// Beckmann q^2 ~ Exp(1), CDF 1 - exp(-q^2); GGX CDF q^2 / (1 + q^2).
template <class Src>
void fit_slope_radius(const Src& src, SlopeStats& st, double vx, double vy, double ax2, double ay2, int bins) {
  const auto qb = [&](std::size_t k0, std::size_t k1, const auto& f) {
    src.each(k0, k1, [&](double sx, double sy) {
      const double x = sx - st.mean_x, y = sy - st.mean_y;
      f(std::sqrt(x * x / (2 * vx) + y * y / (2 * vy)));
    });
  };
  const auto qg = [&](std::size_t k0, std::size_t k1, const auto& f) {
    src.each(k0, k1, [&](double sx, double sy) {
      const double x = sx - st.mean_x, y = sy - st.mean_y;
      f(std::sqrt(x * x / ax2 + y * y / ay2));
    });
  };
  std::vector<double> eb(bins + 1), eg(bins + 1);
  for (int k = 0; k <= bins; ++k) {
    const double p = static_cast<double>(k) / bins;
    eb[k] = k == bins ? std::numeric_limits<double>::infinity() : std::sqrt(-std::log1p(-p));
    eg[k] = k == bins ? std::numeric_limits<double>::infinity() : std::sqrt(p / (1 - p));
  }
  st.beckmann_fit = equal_probability_fit("beckmann", eb, st.n, qb, 2);
  st.ggx_fit = equal_probability_fit("ggx", eg, st.n, qg, 2);
}

template <class Src>
SlopeStats slope_stats_of(const Src& src, int bins) {
  SlopeStats st;
  st.n = src.size();
  if (st.n == 0) return st;
  const Divide by_n(static_cast<double>(st.n));  // 2 nx ny facets: a power of two on most tiles
  const auto [vx, vy] = fill_slope_moments(src, st, by_n);
  if (!(vx > 0) || !(vy > 0)) return st;  // a profile along one axis: no 2D slope model fits
  fit_isotropic_ggx(src, st);
  const auto [ax2, ay2] = fit_anisotropic_ggx(src, st, vx, vy, by_n);
  fit_slope_radius(src, st, vx, vy, ax2, ay2, bins);
  return st;
}
}  // namespace

HeightGridView grid_view(const Microsurface& s) {
  if (s.kind() != Microsurface::Kind::Heightfield)
    throw RuntimeFailure("metrology needs a heightfield");
  HeightGridView g;
  g.nx = s.nx();
  g.ny = s.ny();
  g.dx = s.dx();
  g.dy = s.dy();
  g.z = &s.heights();
  g.periodic = s.macro().periodic && !is_window(s);
  return g;
}

std::vector<std::array<double, 2>> facet_slopes(const HeightGridView& g) {
  const GridSlopes src(g);
  std::vector<std::array<double, 2>> out;
  out.reserve(src.size());
  src.each(0, src.size(), [&](double sx, double sy) { out.push_back({sx, sy}); });
  return out;
}

SlopeStats slope_stats(const std::vector<std::array<double, 2>>& slopes, int bins) {
  return slope_stats_of(ListedSlopes{&slopes}, bins);
}

SlopeStats slope_stats(const HeightGridView& g, int bins) { return slope_stats_of(GridSlopes(g), bins); }

namespace {
// Float heights (a grid) or doubles (a sample): each value is used as a double.
template <class T>
HistogramFit height_fit(const std::vector<T>& heights, int bins) {
  const double n = static_cast<double>(heights.size());
  double mean = 0, var = 0;
  const Divide by_n(n);
  for (double h : heights) mean += by_n(h);
  for (double h : heights) var += by_n((h - mean) * (h - mean));
  const double sd = std::sqrt(var);
  std::vector<double> edges(bins + 1);
  edges[0] = -std::numeric_limits<double>::infinity();
  edges[bins] = std::numeric_limits<double>::infinity();
  for (int k = 1; k < bins; ++k) edges[k] = mean + sd * normal_quantile(static_cast<double>(k) / bins);
  return equal_probability_fit(
      "gaussian", edges, heights.size(),
      [&](std::size_t k0, std::size_t k1, const auto& f) {
        for (std::size_t k = k0; k < k1; ++k) f(static_cast<double>(heights[k]));
      },
      2);
}
}  // namespace

HistogramFit gaussian_height_fit(const std::vector<double>& heights, int bins) {
  return height_fit(heights, bins);
}

namespace {
// The normalized ACF on a w x h table of integer lags, indexed circularly: a periodic grid's
// circular ACF (w, h = nx, ny), or a window's linear ACF zero-padded to w, h = 2 nx, 2 ny (lag
// -t at w - t), each lag divided by its number of overlapping pairs.
struct AcfTable {
  int w = 0, h = 0;
  // The values in the real parts of the transform's own array: no second table of doubles
  // (8 bytes per cell less at the peak of `info`).
  std::vector<Complex> v;
  double operator()(long i, long j) const {
    i = ((i % w) + w) % w;
    j = ((j % h) + h) % h;
    return v[static_cast<std::size_t>(j) * w + i].real();
  }
};

AcfTable acf_table(const HeightGridView& g) {
  AcfTable t;
  t.w = g.periodic ? g.nx : 2 * g.nx;
  t.h = g.periodic ? g.ny : 2 * g.ny;
  double mean = 0;
  for (float z : *g.z) mean += z;
  mean /= static_cast<double>(g.z->size());
  std::vector<Complex>& a = t.v;
  a.assign(static_cast<std::size_t>(t.w) * t.h, 0.0);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) a[static_cast<std::size_t>(j) * t.w + i] = at(g, i, j) - mean;
  fft2d(a, t.w, t.h, false);
  for (auto& c : a) c = std::norm(c);  // Wiener-Khinchin: ACF = F^-1 |F z|^2
  fft2d(a, t.w, t.h, true);
  for (int j = 0; j < t.h; ++j)
    for (int i = 0; i < t.w; ++i) {
      Complex& c = a[static_cast<std::size_t>(j) * t.w + i];
      double v = c.real();
      if (!g.periodic) {
        const int li = i < g.nx ? i : t.w - i, lj = j < g.ny ? j : t.h - j;  // |lag|
        const double pairs = static_cast<double>(g.nx - li) * (g.ny - lj);
        v = pairs > 0 ? v / pairs : 0;
      }
      c = v;
    }
  const double c0 = a[0].real();
  for (auto& c : a) c = c0 > 0 ? c.real() / c0 : 0;
  return t;
}
}  // namespace

std::vector<double> autocorrelation(const HeightGridView& g) {
  AcfTable t = acf_table(g);
  std::vector<double> out(static_cast<std::size_t>(g.nx) * g.ny);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) out[static_cast<std::size_t>(j) * g.nx + i] = t(i, j);
  return out;
}

AcfStats acf_stats(const HeightGridView& g, double threshold) {
  AcfStats st;
  st.threshold = threshold;
  const AcfTable t = acf_table(g);
  auto value = [&](double fx, double fy) {  // bilinear between integer lags (in cells)
    const long i0 = static_cast<long>(std::floor(fx)), j0 = static_cast<long>(std::floor(fy));
    const double tx = fx - i0, ty = fy - j0;
    return (1 - tx) * (1 - ty) * t(i0, j0) + tx * (1 - ty) * t(i0 + 1, j0) +
           (1 - tx) * ty * t(i0, j0 + 1) + tx * ty * t(i0 + 1, j0 + 1);
  };
  // March outward along 720 directions over half a turn (ACF(-t) = ACF(t)) up to half the grid,
  // in steps of a quarter cell; the crossing of the threshold is interpolated linearly.
  const int directions = 720;
  const double step = 0.25 * std::min(g.dx, g.dy);
  st.sal = std::numeric_limits<double>::infinity();
  st.decayed_in_every_direction = true;
  for (int d = 0; d < directions; ++d) {
    const double th = kPi * d / directions, c = std::cos(th), s = std::sin(th);
    double rmax = std::numeric_limits<double>::infinity();
    if (std::abs(c) > 1e-12) rmax = std::min(rmax, 0.5 * g.nx * g.dx / std::abs(c));
    if (std::abs(s) > 1e-12) rmax = std::min(rmax, 0.5 * g.ny * g.dy / std::abs(s));
    double prev_r = 0, prev_v = 1, cross = -1;
    for (double r = step; r <= rmax + 1e-12; r += step) {
      const double v = value(r * c / g.dx, r * s / g.dy);
      if (v <= threshold) {
        cross = prev_r + (r - prev_r) * (prev_v - threshold) / (prev_v - v);
        break;
      }
      prev_r = r;
      prev_v = v;
    }
    if (cross < 0) {
      st.decayed_in_every_direction = false;
      cross = rmax;
    } else {
      st.decayed = true;
      st.sal = std::min(st.sal, cross);
    }
    if (cross > st.longest) {
      st.longest = cross;
      st.slowest_direction_deg = deg(th);
    }
  }
  if (!st.decayed) st.sal = 0;
  st.str = st.decayed && st.longest > 0 ? st.sal / st.longest : 0;
  return st;
}

double metrology_bytes(double nx, double ny, bool periodic) {
  return nx * ny * (sizeof(float) + sizeof(Complex) * (periodic ? 1 : 4));
}

Metrology measure_metrology(const HeightGridView& g) {
  if (g.nx < 2 || g.ny < 2 || !g.z || g.z->size() != static_cast<std::size_t>(g.nx) * g.ny)
    throw UsageError("metrology needs a grid of at least 2 x 2 heights");
  Metrology m;
  m.points = g.z->size();
  const double n = static_cast<double>(m.points);
  const Divide by_n(n);
  double lo = (*g.z)[0], hi = lo;
  for (float z : *g.z) {
    m.mean += by_n(z);
    lo = std::min<double>(lo, z);
    hi = std::max<double>(hi, z);
  }
  m.sz = hi - lo;
  if (!(m.sz > 0)) return m;
  m.textured = true;
  double m2 = 0, m3 = 0, m4 = 0;
  for (float z : *g.z) {
    const double d = z - m.mean;
    m.sa += by_n(std::abs(d));
    m2 += by_n(d * d);
    m3 += by_n(d * d * d);
    m4 += by_n(d * d * d * d);
  }
  m.sq = std::sqrt(m2);
  m.skewness = m3 / (m2 * m.sq);
  m.kurtosis = m4 / (m2 * m2);
  m.height_fit = height_fit(*g.z, 20);  // the grid's own floats, no copy
  m.slopes = slope_stats(g);  // slopes from the heights, pass by pass: no per-facet array
  m.acf = acf_stats(g);
  m.cells_per_correlation_length = m.acf.sal / std::max(g.dx, g.dy);
  m.cells_per_gaussian_length = m.cells_per_correlation_length / std::sqrt(std::log(1.0 / m.acf.threshold));
  return m;
}

Json metrology_to_json(const Metrology& m) {
  Json j;
  j["points"] = m.points;
  j["textured"] = m.textured;
  j["mean_height"] = m.mean;
  j["sq"] = m.sq;
  j["sa"] = m.sa;
  j["sz"] = m.sz;
  j["ssk"] = m.skewness;
  j["sku"] = m.kurtosis;
  if (!m.textured) return j;
  const SlopeStats& s = m.slopes;
  j["sdq"] = s.sdq;
  j["slope_rms_x"] = s.rms_x;
  j["slope_rms_y"] = s.rms_y;
  j["slope_mean_x"] = s.mean_x;
  j["slope_mean_y"] = s.mean_y;
  j["beckmann_alpha_x"] = s.beckmann_alpha_x;
  j["beckmann_alpha_y"] = s.beckmann_alpha_y;
  j["ggx_alpha"] = s.ggx_alpha;
  j["ggx_alpha_x"] = s.ggx_alpha_x;
  j["ggx_alpha_y"] = s.ggx_alpha_y;
  j["sal"] = m.acf.sal;
  j["str"] = m.acf.str;
  j["acf_threshold"] = m.acf.threshold;
  j["acf_longest_decay_length"] = m.acf.longest;
  j["acf_slowest_direction_deg"] = m.acf.slowest_direction_deg;
  j["acf_decayed"] = m.acf.decayed;
  j["acf_decayed_in_every_direction"] = m.acf.decayed_in_every_direction;
  j["cells_per_correlation_length"] = m.cells_per_correlation_length;
  j["cells_per_gaussian_correlation_length"] = m.cells_per_gaussian_length;
  j["height_fit"] = fit_json(m.height_fit);
  j["slope_fit_beckmann"] = fit_json(s.beckmann_fit);
  j["slope_fit_ggx"] = fit_json(s.ggx_fit);
  return j;
}

}  // namespace microsim
