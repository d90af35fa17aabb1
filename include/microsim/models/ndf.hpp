// Analytic microfacet theory: normal distributions (Beckmann, GGX; isotropic and anisotropic),
// Smith Lambda / G1 (closed forms and numerical, from a slope distribution or from facets),
// visible normals (evaluation and exact sampling), the four Smith joint masking-shadowing forms
// and the V-cavity model.
//
// Header-only, depends on Eigen only.
//
// Conventions: macrosurface normal n = +z; all directions point away from the surface; radians.
// Slopes follow [Heitz14, App. A]: the slope of a normal m is (-mx/mz, -my/mz), and
// m(s) = (-sx, -sy, 1) / sqrt(1 + sx^2 + sy^2).
//
// Sources (keys of docs/theory/bibliography.md): [Heitz14] for D, Lambda, G1, the G2 forms and the
// V-cavity; [TSBlog24] for GGX as the normal distribution of an ellipsoid and VNDF sampling.
//
// Edge cases (below the horizon, grazing, normal incidence):
//   * Lambda(v) = 0 at normal incidence and grows without bound toward grazing. For v.z <= 0 the
//     view sees no macrosurface (projected area cos(theta) <= 0): Lambda returns +infinity and
//     G1 returns 0; D_visible and every G2 form return 0. Callers that need the "other side" of a
//     transmissive interface must flip the direction themselves.
//   * Lambda functions of the parameter a = 1/(alpha_o tan(theta)): a = +inf -> 0, a <= 0 -> +inf.
//   * sample_visible_normal accepts v.z >= 0 (v.z == 0 is the well-defined grazing limit) and
//     throws std::invalid_argument for v.z < 0 or a zero / non-finite v.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace microsim::models {

using Vec3 = Eigen::Vector3d;

enum class Distribution { Beckmann, GGX };

inline const char* to_string(Distribution d) {
  switch (d) {
    case Distribution::Beckmann: return "beckmann";
    case Distribution::GGX: return "ggx";
  }
  return "unknown";
}

namespace detail {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kSqrtPi = 1.77245385090551602720;
inline constexpr double kInf = std::numeric_limits<double>::infinity();

// Gauss-Legendre rule on [-1, 1]: nodes are the roots of P_n, found by Newton's method on the
// three-term recurrence; weights 2 / ((1 - x^2) P_n'(x)^2).
inline std::vector<std::pair<double, double>> gauss_legendre(int n) {
  std::vector<std::pair<double, double>> rule(static_cast<std::size_t>(n));
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double x = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      // p1 = P_n(x), p0 = P_{n-1}(x)
      dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    const double w = 2.0 / ((1.0 - x * x) * dp * dp);
    rule[static_cast<std::size_t>(i)] = {-x, w};
    rule[static_cast<std::size_t>(n - 1 - i)] = {x, w};
  }
  return rule;
}

inline const std::vector<std::pair<double, double>>& gl10() {
  static const std::vector<std::pair<double, double>> rule = gauss_legendre(10);
  return rule;
}

// 10-point Gauss-Legendre on [a, b]; also accumulates the integral of |f| (for a relative test).
template <class F>
double gl_panel(const F& f, double a, double b, double* abs_sum) {
  const double c = 0.5 * (a + b), h = 0.5 * (b - a);
  double s = 0.0, sa = 0.0;
  for (const auto& [x, w] : gl10()) {
    const double v = f(c + h * x);
    s += w * v;
    sa += w * std::abs(v);
  }
  if (abs_sum) *abs_sum = sa * std::abs(h);
  return s * h;
}

// Adaptive bisection: compare the rule on [a, b] (`whole`) with the rule on both halves and
// accept the halves when they agree to tol_abs (halved at each level, so the total error stays
// below the initial tol_abs for smooth integrands) or to the rounding level of the panel.
// Depth-limited; non-finite values propagate.
template <class F>
double adaptive_gl(const F& f, double a, double b, double whole, double tol_abs, int depth) {
  const double m = 0.5 * (a + b);
  double al = 0.0, ar = 0.0;
  const double left = gl_panel(f, a, m, &al);
  const double right = gl_panel(f, m, b, &ar);
  const double halves = left + right;
  if (!std::isfinite(halves)) return halves;
  // Accept when the tolerance is met, or at the rounding level of the panel: difference below
  // 1e-13 of the panel's |f| integral, panel narrower than ~1e-11 of its abscissa (rounding of
  // the nodes then dominates), or difference below 1e-280 (near-denormal values carry no
  // precision; callers only refine functions whose integral exceeds 1e-250). Depth limit 40.
  const double diff = std::abs(halves - whole);
  if (depth >= 40 || diff <= tol_abs || diff <= 1e-13 * (al + ar) || diff <= 1e-280 ||
      (b - a) <= 1e-11 * (std::abs(a) + std::abs(b)))
    return halves;
  return adaptive_gl(f, a, m, left, 0.5 * tol_abs, depth + 1) +
         adaptive_gl(f, m, b, right, 0.5 * tol_abs, depth + 1);
}

// Integral of f over [a, +inf) to a relative accuracy ~rel (of the integral of |f|).
// Scale-free panel layout anchored at a: offsets 0, then every decade [10^k, 10^(k+1)],
// k = -7..2, split in 4 equal panels, then [a + 1e3, inf) mapped by q = a + 1e3 / (1 - t),
// t in [0, 1), which turns tails decaying like q^-2 (GGX) into a bounded integrand. A first pass
// with one 10-point rule per panel sets the absolute tolerance rel * int |f|; each panel is then
// refined adaptively. The first pass samples any point at offset d with a spacing <~ d/4, so
// features narrower than that, far from a, could be missed; the centered unimodal slope
// distributions of microfacet theory (and their marginals) are far from that limit.
template <class F>
double integrate_halfline(const F& f, double a, double rel = 1e-12) {
  const double big = 1e3;
  auto tail = [&](double t) {
    const double one_minus = 1.0 - t;
    return f(a + big / one_minus) * big / (one_minus * one_minus);
  };
  std::vector<double> edges = {0.0};
  for (int k = -7; k <= 2; ++k) {
    const double d0 = std::pow(10.0, k), d1 = std::pow(10.0, k + 1);
    for (int j = 0; j < 4; ++j) edges.push_back(d0 + (d1 - d0) * (j + 1) / 4.0);
  }
  const std::size_t np = edges.size() - 1;
  std::vector<double> whole(np + 1);
  double abs_total = 0.0;
  for (std::size_t k = 0; k < np; ++k) {
    double ab = 0.0;
    whole[k] = gl_panel(f, a + edges[k], a + edges[k + 1], &ab);
    abs_total += ab;
  }
  double ab = 0.0;
  whole[np] = gl_panel(tail, 0.0, 1.0, &ab);
  abs_total += ab;
  if (!std::isfinite(abs_total)) return abs_total;
  if (abs_total < 1e-250) {  // negligible (and near-denormal: no relative precision left)
    double sum = 0.0;
    for (double w : whole) sum += w;
    return sum;
  }
  const double tol = rel * abs_total / static_cast<double>(np + 1);
  double total = 0.0;
  for (std::size_t k = 0; k < np; ++k)
    total += adaptive_gl(f, a + edges[k], a + edges[k + 1], whole[k], tol, 0);
  total += adaptive_gl(tail, 0.0, 1.0, whole[np], tol, 0);
  return total;
}

inline void require_alpha(double ax, double ay) {
  if (!(std::isfinite(ax) && std::isfinite(ay) && ax > 0.0 && ay > 0.0))
    throw std::invalid_argument("roughness alpha must be finite and > 0 (got alpha_x=" +
                                std::to_string(ax) + ", alpha_y=" + std::to_string(ay) + ")");
}

// Beckmann visible slope along the (stretched, alpha = 1) view azimuth: density proportional to
// (mu - x) exp(-x^2) / sqrt(pi) on x < mu, mu = cot(theta') ([Heitz14, App. A] integrand with
// P2(x) = exp(-x^2)/sqrt(pi)). Its CDF in closed form:
//   C(x) = [mu erfc(-x)/2 + exp(-x^2)/(2 sqrt(pi))] / N,  N = C-numerator at x = mu = mu (1 + Lambda).
// mu = +inf (normal incidence) gives the plain Gaussian CDF erfc(-x)/2.
// Inverted by Newton's method safeguarded by bisection (bracket kept at all times).
inline double beckmann_visible_slope_quantile(double mu, double u) {
  const bool gaussian = std::isinf(mu);
  const double norm = gaussian ? 1.0 : mu * 0.5 * std::erfc(-mu) + std::exp(-mu * mu) / (2.0 * kSqrtPi);
  auto cdf = [&](double x) {
    if (gaussian) return 0.5 * std::erfc(-x);
    if (x >= mu) return 1.0;
    return (mu * 0.5 * std::erfc(-x) + std::exp(-x * x) / (2.0 * kSqrtPi)) / norm;
  };
  auto pdf = [&](double x) {
    if (gaussian) return std::exp(-x * x) / kSqrtPi;
    if (x >= mu) return 0.0;
    return (mu - x) * std::exp(-x * x) / (kSqrtPi * norm);
  };
  // Bracket [lo, hi] with cdf(lo) <= u <= cdf(hi).
  double hi = gaussian ? 1.0 : mu;
  if (gaussian)
    while (cdf(hi) < u && hi < 40.0) hi += 2.0;
  double lo = std::min(hi, 0.0) - 1.0;
  while (cdf(lo) > u && lo > -40.0) lo -= 2.0;
  double x = gaussian ? 0.0 : std::min(0.0, mu - 1e-3);  // near the mode, inside the bracket
  x = std::clamp(x, lo, hi);
  for (int it = 0; it < 200; ++it) {
    const double c = cdf(x) - u;
    if (c == 0.0) return x;
    if (c < 0.0) lo = x; else hi = x;
    const double d = pdf(x);
    double xn = (d > 0.0) ? x - c / d : 0.5 * (lo + hi);
    if (!(xn > lo && xn < hi)) xn = 0.5 * (lo + hi);  // Newton left the bracket: bisect
    if (std::abs(xn - x) <= 1e-14 * (1.0 + std::abs(x)) || hi - lo <= 1e-14 * (1.0 + std::abs(x)))
      return xn;
    x = xn;
  }
  return x;
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
// 1D Smith Lambda functions of a = 1 / (alpha_o tan(theta_o))
// ---------------------------------------------------------------------------------------------

// [Heitz14, Sec. 3.2] (Beckmann): Lambda(a) = (erf(a) - 1)/2 + exp(-a^2) / (2 a sqrt(pi)).
// erf(a) - 1 is computed as -erfc(a) to avoid cancellation at large a; the remaining difference
// of two terms of size ~exp(-a^2)/a has relative error ~ 4 a^2 * eps, i.e. < 1e-12 wherever
// the result does not underflow.
inline double beckmann_lambda(double a) {
  if (std::isnan(a)) return a;
  if (a <= 0.0) return detail::kInf;
  if (std::isinf(a)) return 0.0;
  const double r = -0.5 * std::erfc(a) + std::exp(-a * a) / (2.0 * a * detail::kSqrtPi);
  return std::max(r, 0.0);
}

// [Heitz14, Sec. 3.2]: the rational approximation of [Walter07],
// Lambda ~ (1 - 1.259 a + 0.396 a^2) / (3.535 a + 2.181 a^2) for a < 1.6, else 0.
// Note: the numerator has roots at a ~ 1.548 and a ~ 1.631, so the value is slightly negative
// (down to -6.1e-5) on [1.548, 1.6); it is returned as is (it is the published formula), and
// there is a small jump to 0 at a = 1.6.
inline double beckmann_lambda_rational(double a) {
  if (std::isnan(a)) return a;
  if (a <= 0.0) return detail::kInf;
  if (a >= 1.6) return 0.0;
  return (1.0 - 1.259 * a + 0.396 * a * a) / (3.535 * a + 2.181 * a * a);
}

// [Heitz14, Sec. 3.2] (GGX): Lambda(a) = (-1 + sqrt(1 + 1/a^2)) / 2, evaluated as
// (1/a^2) / (2 (1 + sqrt(1 + 1/a^2))) (algebraically identical, no cancellation at large a).
inline double ggx_lambda(double a) {
  if (std::isnan(a)) return a;
  if (a <= 0.0) return detail::kInf;
  if (std::isinf(a)) return 0.0;
  const double inv_a2 = 1.0 / (a * a);
  if (std::isinf(inv_a2)) return detail::kInf;
  return inv_a2 / (2.0 * (1.0 + std::sqrt(1.0 + inv_a2)));
}

// ---------------------------------------------------------------------------------------------
// Normal distribution
// ---------------------------------------------------------------------------------------------

struct Ndf {
  Distribution kind = Distribution::Beckmann;
  double alpha_x = 0.5;
  double alpha_y = 0.5;

  static Ndf beckmann(double alpha_x, double alpha_y) {
    detail::require_alpha(alpha_x, alpha_y);
    return Ndf{Distribution::Beckmann, alpha_x, alpha_y};
  }
  static Ndf ggx(double alpha_x, double alpha_y) {
    detail::require_alpha(alpha_x, alpha_y);
    return Ndf{Distribution::GGX, alpha_x, alpha_y};
  }

  bool isotropic() const { return alpha_x == alpha_y; }

  // Slope distribution P22, normalized over R^2 ([Heitz14, App. A]: P22(s) ds = (m.n) D(m) dm).
  //   Beckmann [Heitz14, Sec. 3.3]: exp(-(sx^2/ax^2 + sy^2/ay^2)) / (pi ax ay), a Gaussian with
  //     per-axis variance alpha^2 / 2.
  //   GGX [Heitz14, Sec. 3.3]: 1 / (pi ax ay (1 + sx^2/ax^2 + sy^2/ay^2)^2).
  double P22(double slope_x, double slope_y) const {
    const double ex = slope_x / alpha_x, ey = slope_y / alpha_y;
    const double r2 = ex * ex + ey * ey;
    const double c = 1.0 / (detail::kPi * alpha_x * alpha_y);
    if (kind == Distribution::Beckmann) return c * std::exp(-r2);
    const double d = 1.0 + r2;
    return c / (d * d);
  }

  // D(m) = chi+(m.n) P22(-mx/mz, -my/mz) / mz^4 ([Heitz14, App. A], footnote 4; sec. 3.3 anisotropic
  // forms). Written directly in m so that it stays finite for mz -> 0:
  //   Beckmann: exp(-(mx^2/ax^2 + my^2/ay^2) / mz^2) / (pi ax ay mz^4)
  //   GGX:      1 / (pi ax ay (mz^2 + mx^2/ax^2 + my^2/ay^2)^2)
  // (m unit. At the horizon Beckmann D -> 0 while GGX D stays finite: alpha^2 / pi when isotropic.)
  double D(const Vec3& m) const {
    const double mz = m.z();
    if (!(mz > 0.0)) return 0.0;
    const double ex = m.x() / alpha_x, ey = m.y() / alpha_y;
    const double c = 1.0 / (detail::kPi * alpha_x * alpha_y);
    if (kind == Distribution::Beckmann) {
      const double mz2 = mz * mz;
      const double e = std::exp(-(ex * ex + ey * ey) / mz2);
      if (e == 0.0) return 0.0;
      return c * e / (mz2 * mz2);
    }
    const double d = mz * mz + ex * ex + ey * ey;
    return c / (d * d);
  }

  // [Heitz14, eq. 11]: projected roughness alpha_o = sqrt(cos^2(phi) ax^2 + sin^2(phi) ay^2).
  double alpha_o(double phi) const {
    const double c = std::cos(phi), s = std::sin(phi);
    return std::sqrt(c * c * alpha_x * alpha_x + s * s * alpha_y * alpha_y);
  }

  // a = 1 / (alpha_o tan(theta)) [Heitz14, Sec. 3.3], computed without angles:
  // alpha_o^2 tan^2(theta) = (ax^2 vx^2 + ay^2 vy^2) / vz^2, so a = vz / |(ax vx, ay vy)|.
  // Scale-invariant in v. +inf at normal incidence; requires v.z > 0.
  double a_of(const Vec3& v) const {
    const double px = alpha_x * v.x(), py = alpha_y * v.y();
    const double den = std::sqrt(px * px + py * py);
    if (den == 0.0) return detail::kInf;
    return v.z() / den;
  }

  // Smith Lambda ([Heitz14, Sec. 3.2/3.3], closed forms; anisotropy by eq. (11)). Exact erf form for
  // Beckmann. 0 at normal incidence, +inf for v.z <= 0 (see header comment).
  double Lambda(const Vec3& v) const {
    if (!(v.z() > 0.0)) return detail::kInf;
    const double a = a_of(v);
    return kind == Distribution::Beckmann ? beckmann_lambda(a) : ggx_lambda(a);
  }

  // [Heitz14, eq. 10]: Smith G1(v) = 1 / (1 + Lambda(v)); 0 for v.z <= 0.
  double G1(const Vec3& v) const {
    const double l = Lambda(v);
    return std::isinf(l) ? 0.0 : 1.0 / (1.0 + l);
  }

  // [Heitz14, eq. 10]: G1(v, m) = chi+(v.m) / (1 + Lambda(v)).
  double G1(const Vec3& v, const Vec3& m) const { return v.dot(m) > 0.0 ? G1(v) : 0.0; }

  // [Heitz14, eq. 13]: D_v(m) = G1(v, m) max(0, v.m) D(m) / v.z; 0 for v.z <= 0.
  double D_visible(const Vec3& v, const Vec3& m) const {
    if (!(v.z() > 0.0)) return 0.0;
    const double vm = v.dot(m);
    if (!(vm > 0.0)) return 0.0;
    return G1(v) * vm * D(m) / v.z();
  }

  // Exact sampling of D_visible(v, .) (density w.r.t. solid angle of m), for u1, u2 in [0, 1].
  // Both distributions are stretch invariant [Heitz14, Sec. 3.3]: with A = diag(ax, ay, 1), sample
  // the isotropic alpha = 1 problem for the stretched view A v, then map back (slopes scale by
  // (ax, ay); normals by A^T, i.e. m ~ (ax n'x, ay n'y, n'z)).
  //   GGX: [TSBlog24, "GGX importance sampling"] - alpha = 1 GGX is the normal distribution of the upper
  //     half of a unit sphere; visible normals are uniform over the projection of the visible
  //     part onto the plane normal to the view: a half disk plus a half ellipse compressed by
  //     cos(theta'). Sample a unit disk, compress that half, lift onto the hemisphere.
  //   Beckmann: visible slope sampling - in the frame of the stretched view azimuth the visible
  //     slope density is (mu - x) P2(x) P2(y) on x < mu ([Heitz14, App. A] integrand), x by inversion of
  //     its closed-form CDF (Newton, see detail::beckmann_visible_slope_quantile), y Gaussian.
  Vec3 sample_visible_normal(const Vec3& v, double u1, double u2) const {
    if (!(std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z())) || v.z() < 0.0 ||
        v.squaredNorm() == 0.0)
      throw std::invalid_argument("sample_visible_normal: view direction must be finite, nonzero, v.z >= 0");
    constexpr double one_minus = 1.0 - 0x1p-53;
    u1 = std::clamp(u1, 0.0, one_minus);
    u2 = std::clamp(u2, 0.0, one_minus);
    const Vec3 vs = stretched_view(v);
    if (kind == Distribution::GGX) {
      const double lensq = vs.x() * vs.x() + vs.y() * vs.y();
      const Vec3 t1 = lensq > 0.0 ? Vec3(-vs.y(), vs.x(), 0.0) / std::sqrt(lensq) : Vec3(1.0, 0.0, 0.0);
      // t2 = vs x t1: in the plane of vs and n, on the +z side
      const Vec3 t2(vs.y() * t1.z() - vs.z() * t1.y(), vs.z() * t1.x() - vs.x() * t1.z(),
                    vs.x() * t1.y() - vs.y() * t1.x());
      const double r = std::sqrt(u1), phi = 2.0 * detail::kPi * u2;
      const double p1 = r * std::cos(phi);
      double p2 = r * std::sin(phi);
      const double h = std::sqrt(std::max(0.0, 1.0 - p1 * p1));
      const double s = 0.5 * (1.0 + vs.z());
      p2 = (1.0 - s) * h + s * p2;  // maps [-h, h] -> [-vs.z h, h] linearly (uniform density kept)
      const double p3 = std::sqrt(std::max(0.0, 1.0 - p1 * p1 - p2 * p2));
      const Vec3 nh = p1 * t1 + p2 * t2 + p3 * vs;  // point = normal on the unit hemisphere
      return Vec3(alpha_x * nh.x(), alpha_y * nh.y(), std::max(0.0, nh.z())).normalized();
    }
    // Beckmann
    const BeckmannViewFrame f = beckmann_view_frame(vs);
    const double xt = detail::beckmann_visible_slope_quantile(f.mu, std::max(u1, 1e-300));
    const double yt = detail::beckmann_visible_slope_quantile(detail::kInf, std::max(u2, 1e-300));
    return beckmann_normal_from_slopes(f, xt, yt);
  }

  // The Beckmann VNDF sampler in two halves, so that a tensor grid of (u1, u2) can invert each
  // marginal once per row / column (xt depends on u1 only, yt on u2 only): the stretched view's
  // azimuth (cphi, sphi) and mu = cot(theta'), then the normal of the slopes (xt, yt) sampled in
  // that frame. sample_visible_normal is exactly beckmann_normal_from_slopes(frame, quantiles).
  struct BeckmannViewFrame {
    double cphi = 1.0, sphi = 0.0, mu = detail::kInf;
  };
  // vs: the stretched, normalized view (alpha_x v.x, alpha_y v.y, v.z) / |...|.
  static BeckmannViewFrame beckmann_view_frame(const Vec3& vs) {
    BeckmannViewFrame f;
    const double sin_t = std::sqrt(vs.x() * vs.x() + vs.y() * vs.y());
    if (sin_t > 0.0) {
      f.cphi = vs.x() / sin_t;
      f.sphi = vs.y() / sin_t;
      f.mu = vs.z() / sin_t;  // cot(theta')
    }
    return f;
  }
  Vec3 stretched_view(const Vec3& v) const { return Vec3(alpha_x * v.x(), alpha_y * v.y(), v.z()).normalized(); }
  Vec3 beckmann_normal_from_slopes(const BeckmannViewFrame& f, double xt, double yt) const {
    // rotate back from the view-azimuth frame, then unstretch the slopes
    const double sx = alpha_x * (f.cphi * xt - f.sphi * yt);
    const double sy = alpha_y * (f.sphi * xt + f.cphi * yt);
    return Vec3(-sx, -sy, 1.0).normalized();
  }
};

// ---------------------------------------------------------------------------------------------
// Numerical Smith Lambda
// ---------------------------------------------------------------------------------------------

// [Heitz14, App. A]: Lambda = (1/mu) * int_mu^inf (q - mu) P2(q) dq, mu = cot(theta), P2 the 1D marginal
// slope density along the view azimuth. Adaptive Gauss-Legendre (relative accuracy ~1e-11 for
// smooth P2). mu = +inf -> 0; mu <= 0 -> +inf (grazing or below: Lambda diverges like 1/mu).
inline double lambda_from_slope_marginal(const std::function<double(double)>& P2, double mu) {
  if (std::isnan(mu)) return mu;
  if (std::isinf(mu) && mu > 0) return 0.0;
  if (mu <= 0.0) return detail::kInf;
  auto f = [&](double q) { return (q - mu) * P2(q); };
  return detail::integrate_halfline(f, mu) / mu;
}

// [Heitz14, App. A] from a 2D slope density: project onto the view azimuth phi,
// P2(q) = int P22(q cos(phi) - p sin(phi), q sin(phi) + p cos(phi)) dp, then the 1D formula with
// mu = v.z / |v_xy|. Lambda = 0 at normal incidence, +inf for v.z <= 0.
inline double lambda_from_slope_distribution(const std::function<double(double, double)>& P22,
                                             const Vec3& v) {
  if (!(v.z() > 0.0)) return detail::kInf;
  const double r = std::sqrt(v.x() * v.x() + v.y() * v.y());
  if (r == 0.0) return 0.0;
  const double c = v.x() / r, s = v.y() / r;
  const double mu = v.z() / r;
  auto P2 = [&](double q) {
    auto plus = [&](double p) { return P22(q * c - p * s, q * s + p * c); };
    auto minus = [&](double p) { return P22(q * c + p * s, q * s - p * c); };
    return detail::integrate_halfline(plus, 0.0) + detail::integrate_halfline(minus, 0.0);
  };
  return lambda_from_slope_marginal(P2, mu);
}

// docs/theory/masking.md ([Heitz14, App. A] with the facets' own slopes):
// Lambda(v) = sum_f A_f max(0, -v.m_f) / ((v.n) A). Scale-invariant in v; normals must be unit.
// +inf for v.z <= 0. Throws std::invalid_argument if sizes differ or macro_area <= 0.
inline double lambda_from_facets(const std::vector<Vec3>& normals, const std::vector<double>& areas,
                                 const Vec3& v, double macro_area) {
  if (normals.size() != areas.size())
    throw std::invalid_argument("lambda_from_facets: normals and areas differ in size");
  if (!(macro_area > 0.0)) throw std::invalid_argument("lambda_from_facets: macro_area must be > 0");
  if (!(v.z() > 0.0)) return detail::kInf;
  double back = 0.0;
  for (std::size_t f = 0; f < normals.size(); ++f) back += areas[f] * std::max(0.0, -v.dot(normals[f]));
  return back / (v.z() * macro_area);
}

// ---------------------------------------------------------------------------------------------
// V-cavity
// ---------------------------------------------------------------------------------------------

// [Heitz14, eq. 24] with chi+(v.m): G1 = min(1, 2 (m.n)(v.n) / (v.m)); 0 if v.m <= 0, v.z <= 0 or
// m.z <= 0 (V-cavity facets face up).
inline double vcavity_G1(const Vec3& v, const Vec3& m) {
  const double vm = v.dot(m);
  if (!(vm > 0.0) || !(v.z() > 0.0) || !(m.z() > 0.0)) return 0.0;
  return std::min(1.0, 2.0 * m.z() * v.z() / vm);
}

// V-cavity masking-shadowing (the Cook-Torrance form, [Heitz14, Sec. 6]): min(1, 2(n.m)(n.o)/(o.m),
// 2(n.m)(n.i)/(i.m)) with chi+(o.m) chi+(i.m) = min(vcavity_G1(o, m), vcavity_G1(i, m)).
inline double vcavity_G2(const Vec3& o, const Vec3& i, const Vec3& m) {
  return std::min(vcavity_G1(o, m), vcavity_G1(i, m));
}

// ---------------------------------------------------------------------------------------------
// Smith joint masking-shadowing [Heitz14, Sec. 5]. o = outgoing/view, i = incoming/light, m normal.
// Each form includes chi+(o.m) chi+(i.m); 0 if o.z <= 0 or i.z <= 0.
// ---------------------------------------------------------------------------------------------

// Azimuth difference between o and i in [0, pi] (0 if either is vertical).
inline double azimuth_difference(const Vec3& o, const Vec3& i) {
  const double cross = o.x() * i.y() - o.y() * i.x();
  const double dot = o.x() * i.x() + o.y() * i.y();
  return std::atan2(std::abs(cross), dot);
}

// [Heitz14, Sec. 5], van Ginneken et al. empirical factor: lambda(phi) = 4.41 phi / (4.41 phi + 1).
inline double van_ginneken_lambda(double phi) { return 4.41 * phi / (4.41 * phi + 1.0); }

namespace detail {
inline bool g2_front(const Vec3& o, const Vec3& i, const Vec3& m) {
  return o.z() > 0.0 && i.z() > 0.0 && o.dot(m) > 0.0 && i.dot(m) > 0.0;
}
}  // namespace detail

// [Heitz14, eq. 20]: G1(o, m) G1(i, m).
inline double G2_separable(const Ndf& ndf, const Vec3& o, const Vec3& i, const Vec3& m) {
  if (!detail::g2_front(o, i, m)) return 0.0;
  return ndf.G1(o) * ndf.G1(i);
}

// [Heitz14, eq. 21]: chi+ chi+ / (1 + Lambda(o) + Lambda(i)).
inline double G2_height_correlated(const Ndf& ndf, const Vec3& o, const Vec3& i, const Vec3& m) {
  if (!detail::g2_front(o, i, m)) return 0.0;
  return 1.0 / (1.0 + ndf.Lambda(o) + ndf.Lambda(i));
}
// The same with lambda_i = ndf.Lambda(i) given (a quadrature over o for one i computes it once).
inline double G2_height_correlated(const Ndf& ndf, const Vec3& o, const Vec3& i, const Vec3& m, double lambda_i) {
  if (!detail::g2_front(o, i, m)) return 0.0;
  return 1.0 / (1.0 + ndf.Lambda(o) + lambda_i);
}

// [Heitz14, eq. 22]: lambda(phi) G1(o,m) G1(i,m) + (1 - lambda(phi)) min(G1(o,m), G1(i,m)),
// with the van Ginneken lambda(phi) and phi the azimuth difference of o and i.
inline double G2_direction_correlated(const Ndf& ndf, const Vec3& o, const Vec3& i, const Vec3& m) {
  if (!detail::g2_front(o, i, m)) return 0.0;
  const double go = ndf.G1(o), gi = ndf.G1(i);
  const double l = van_ginneken_lambda(azimuth_difference(o, i));
  return l * go * gi + (1.0 - l) * std::min(go, gi);
}

// [Heitz14, eq. 23]: chi+ chi+ / (1 + max(Lo, Li) + lambda(phi) min(Lo, Li)), van Ginneken lambda.
inline double G2_height_direction_correlated(const Ndf& ndf, const Vec3& o, const Vec3& i,
                                             const Vec3& m) {
  if (!detail::g2_front(o, i, m)) return 0.0;
  const double lo = ndf.Lambda(o), li = ndf.Lambda(i);
  const double l = van_ginneken_lambda(azimuth_difference(o, i));
  return 1.0 / (1.0 + std::max(lo, li) + l * std::min(lo, li));
}

}  // namespace microsim::models
