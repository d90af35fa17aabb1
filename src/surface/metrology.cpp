#include "microsim/surface/metrology.hpp"

#include <unsupported/Eigen/FFT>

#include "microsim/surface/heightmap_import.hpp"

#include <complex>
#include <limits>

namespace microsim {

namespace {
using Complex = std::complex<double>;

// In-place 2D FFT of a w x h row-major array (rows, then columns).
void fft2d(std::vector<Complex>& a, int w, int h, bool inverse) {
  Eigen::FFT<double> fft;
  std::vector<Complex> in(w), out(w);
  for (int j = 0; j < h; ++j) {
    std::copy(a.begin() + static_cast<std::size_t>(j) * w, a.begin() + static_cast<std::size_t>(j + 1) * w,
              in.begin());
    if (inverse) fft.inv(out, in); else fft.fwd(out, in);
    std::copy(out.begin(), out.end(), a.begin() + static_cast<std::size_t>(j) * w);
  }
  in.resize(h);
  out.resize(h);
  for (int i = 0; i < w; ++i) {
    for (int j = 0; j < h; ++j) in[j] = a[static_cast<std::size_t>(j) * w + i];
    if (inverse) fft.inv(out, in); else fft.fwd(out, in);
    for (int j = 0; j < h; ++j) a[static_cast<std::size_t>(j) * w + i] = out[j];
  }
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

// Counts of the n values value(0), ..., value(n - 1) in bins [edges[k], edges[k+1]) against
// equal expected counts n / bins. The values are computed when counted: large grids keep no
// per-facet copy of them.
template <class Value>
HistogramFit equal_probability_fit(const std::string& model, std::vector<double> edges, std::size_t n,
                                   const Value& value, int fitted_parameters) {
  HistogramFit f;
  f.model = model;
  const int bins = static_cast<int>(edges.size()) - 1;
  f.observed.assign(bins, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double v = value(i);
    int k = static_cast<int>(std::upper_bound(edges.begin() + 1, edges.end() - 1, v) - (edges.begin() + 1));
    f.observed[k] += 1;
  }
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
  std::vector<std::array<double, 2>> out;
  const int cx = g.periodic ? g.nx : g.nx - 1, cy = g.periodic ? g.ny : g.ny - 1;
  if (cx <= 0 || cy <= 0) return out;
  out.reserve(2 * static_cast<std::size_t>(cx) * cy);
  for (int j = 0; j < cy; ++j)
    for (int i = 0; i < cx; ++i) {
      const int i1 = (i + 1) % g.nx, j1 = (j + 1) % g.ny;
      const double z00 = at(g, i, j), z10 = at(g, i1, j), z01 = at(g, i, j1), z11 = at(g, i1, j1);
      // The planes of the two facets (v00, v10, v01) and (v10, v11, v01) of Microsurface::facet.
      out.push_back({(z10 - z00) / g.dx, (z01 - z00) / g.dy});
      out.push_back({(z11 - z01) / g.dx, (z11 - z10) / g.dy});
    }
  return out;
}

SlopeStats slope_stats(const std::vector<std::array<double, 2>>& slopes, int bins) {
  SlopeStats st;
  st.n = slopes.size();
  if (st.n == 0) return st;
  const double n = static_cast<double>(st.n);
  double sg2 = 0;
  for (const auto& s : slopes) {
    st.mean_x += s[0] / n;
    st.mean_y += s[1] / n;
    sg2 += (s[0] * s[0] + s[1] * s[1]) / n;
  }
  double vx = 0, vy = 0;
  for (const auto& s : slopes) {
    vx += (s[0] - st.mean_x) * (s[0] - st.mean_x) / n;
    vy += (s[1] - st.mean_y) * (s[1] - st.mean_y) / n;
  }
  st.rms_x = std::sqrt(vx);
  st.rms_y = std::sqrt(vy);
  st.sdq = std::sqrt(sg2);
  // Beckmann's slope variance per axis is alpha^2 / 2 (000 eq. 1b/1c fitted alpha).
  st.beckmann_alpha_x = std::sqrt(2.0) * st.rms_x;
  st.beckmann_alpha_y = std::sqrt(2.0) * st.rms_y;
  if (!(vx > 0) || !(vy > 0)) return st;  // a profile along one axis: no 2D slope model fits

  // Isotropic GGX by maximum likelihood: d/d alpha log L = 0 <=> sum r^2 / (alpha^2 + r^2) = n/2,
  // whose left side decreases with alpha (bisection on log alpha). r^2 is recomputed in every
  // pass (the same value each time) rather than stored: 8 bytes per facet less at the peak.
  const auto r2 = [&](std::size_t k) {
    const double x = slopes[k][0] - st.mean_x, y = slopes[k][1] - st.mean_y;
    return x * x + y * y;
  };
  std::size_t nonzero = 0;
  for (std::size_t k = 0; k < st.n; ++k) nonzero += r2(k) > 0;
  if (2 * nonzero > st.n) {
    double lo = std::log(1e-12 + 1e-6 * st.sdq), hi = std::log(1e6 * (st.sdq + 1e-300));
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi), a2 = std::exp(2 * mid);
      double sum = 0;
      for (std::size_t k = 0; k < st.n; ++k) {
        const double v = r2(k);
        sum += v / (a2 + v);
      }
      const double lo0 = lo, hi0 = hi;
      if (sum > 0.5 * n) lo = mid; else hi = mid;
      // A pass that moved neither end is a fixed point (the next pass is the same): stop. The
      // interval reaches adjacent doubles after about 60 of the 200 passes; same result.
      if (lo == lo0 && hi == hi0) break;
    }
    st.ggx_alpha = std::exp(0.5 * (lo + hi));
  }
  // Anisotropic GGX: EM fixed point of the bivariate t with 2 degrees of freedom, started from
  // the Beckmann moments; each step raises the likelihood.
  double ax2 = vx * 2, ay2 = vy * 2;
  for (st.ggx_iterations = 1; st.ggx_iterations <= 2000; ++st.ggx_iterations) {
    double nx2 = 0, ny2 = 0;
    for (const auto& s : slopes) {
      const double x = s[0] - st.mean_x, y = s[1] - st.mean_y;
      const double w = 4.0 / (1.0 + x * x / ax2 + y * y / ay2);
      nx2 += w * x * x / n;
      ny2 += w * y * y / n;
    }
    const bool done = std::abs(nx2 - ax2) <= 1e-12 * ax2 && std::abs(ny2 - ay2) <= 1e-12 * ay2;
    ax2 = nx2;
    ay2 = ny2;
    if (done) break;
  }
  st.ggx_alpha_x = std::sqrt(ax2);
  st.ggx_alpha_y = std::sqrt(ay2);

  // Normalized slope radius q: Beckmann q^2 ~ Exp(1), CDF 1 - exp(-q^2); GGX CDF q^2 / (1 + q^2).
  const auto qb = [&](std::size_t k) {
    const double x = slopes[k][0] - st.mean_x, y = slopes[k][1] - st.mean_y;
    return std::sqrt(x * x / (2 * vx) + y * y / (2 * vy));
  };
  const auto qg = [&](std::size_t k) {
    const double x = slopes[k][0] - st.mean_x, y = slopes[k][1] - st.mean_y;
    return std::sqrt(x * x / ax2 + y * y / ay2);
  };
  std::vector<double> eb(bins + 1), eg(bins + 1);
  for (int k = 0; k <= bins; ++k) {
    const double p = static_cast<double>(k) / bins;
    eb[k] = k == bins ? std::numeric_limits<double>::infinity() : std::sqrt(-std::log1p(-p));
    eg[k] = k == bins ? std::numeric_limits<double>::infinity() : std::sqrt(p / (1 - p));
  }
  st.beckmann_fit = equal_probability_fit("beckmann", eb, st.n, qb, 2);
  st.ggx_fit = equal_probability_fit("ggx", eg, st.n, qg, 2);
  return st;
}

namespace {
// Float heights (a grid) or doubles (a sample): each value is used as a double.
template <class T>
HistogramFit height_fit(const std::vector<T>& heights, int bins) {
  const double n = static_cast<double>(heights.size());
  double mean = 0, var = 0;
  for (double h : heights) mean += h / n;
  for (double h : heights) var += (h - mean) * (h - mean) / n;
  const double sd = std::sqrt(var);
  std::vector<double> edges(bins + 1);
  edges[0] = -std::numeric_limits<double>::infinity();
  edges[bins] = std::numeric_limits<double>::infinity();
  for (int k = 1; k < bins; ++k) edges[k] = mean + sd * normal_quantile(static_cast<double>(k) / bins);
  return equal_probability_fit("gaussian", edges, heights.size(),
                               [&](std::size_t k) { return static_cast<double>(heights[k]); }, 2);
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
  std::vector<double> v;
  double operator()(long i, long j) const {
    i = ((i % w) + w) % w;
    j = ((j % h) + h) % h;
    return v[static_cast<std::size_t>(j) * w + i];
  }
};

AcfTable acf_table(const HeightGridView& g) {
  AcfTable t;
  t.w = g.periodic ? g.nx : 2 * g.nx;
  t.h = g.periodic ? g.ny : 2 * g.ny;
  double mean = 0;
  for (float z : *g.z) mean += z;
  mean /= static_cast<double>(g.z->size());
  std::vector<Complex> a(static_cast<std::size_t>(t.w) * t.h, 0.0);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) a[static_cast<std::size_t>(j) * t.w + i] = at(g, i, j) - mean;
  fft2d(a, t.w, t.h, false);
  for (auto& c : a) c = std::norm(c);  // Wiener-Khinchin: ACF = F^-1 |F z|^2
  fft2d(a, t.w, t.h, true);
  t.v.resize(a.size());
  for (int j = 0; j < t.h; ++j)
    for (int i = 0; i < t.w; ++i) {
      double v = a[static_cast<std::size_t>(j) * t.w + i].real();
      if (!g.periodic) {
        const int li = i < g.nx ? i : t.w - i, lj = j < g.ny ? j : t.h - j;  // |lag|
        const double pairs = static_cast<double>(g.nx - li) * (g.ny - lj);
        v = pairs > 0 ? v / pairs : 0;
      }
      t.v[static_cast<std::size_t>(j) * t.w + i] = v;
    }
  const double c0 = t.v[0];
  for (auto& v : t.v) v = c0 > 0 ? v / c0 : 0;
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

Metrology measure_metrology(const HeightGridView& g) {
  if (g.nx < 2 || g.ny < 2 || !g.z || g.z->size() != static_cast<std::size_t>(g.nx) * g.ny)
    throw UsageError("metrology needs a grid of at least 2 x 2 heights");
  Metrology m;
  m.points = g.z->size();
  const double n = static_cast<double>(m.points);
  double lo = (*g.z)[0], hi = lo;
  for (float z : *g.z) {
    m.mean += z / n;
    lo = std::min<double>(lo, z);
    hi = std::max<double>(hi, z);
  }
  m.sz = hi - lo;
  if (!(m.sz > 0)) return m;
  m.textured = true;
  double m2 = 0, m3 = 0, m4 = 0;
  for (float z : *g.z) {
    const double d = z - m.mean;
    m.sa += std::abs(d) / n;
    m2 += d * d / n;
    m3 += d * d * d / n;
    m4 += d * d * d * d / n;
  }
  m.sq = std::sqrt(m2);
  m.skewness = m3 / (m2 * m.sq);
  m.kurtosis = m4 / (m2 * m2);
  m.height_fit = height_fit(*g.z, 20);  // the grid's own floats, no copy
  m.slopes = slope_stats(facet_slopes(g));
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
