#include "microsim/statistics.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>

#include "microsim/models/ndf.hpp"  // models::detail::gauss_legendre

namespace microsim {

double sidak_alpha(double alpha, int tests) {
  if (tests < 1) tests = 1;
  return -std::expm1(std::log1p(-alpha) / tests);  // 1 - (1 - alpha)^(1/tests), no cancellation
}

bool ChiSquareResult::passed(double alpha, int tests) const {
  return error.empty() && dof >= 1 && std::isfinite(chi2) && p_value >= sidak_alpha(alpha, tests);
}

std::string ChiSquareResult::summary() const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "chi2 %.2f, dof %d, p %.3g, %d cells (%d pooled: observed %.0f, expected %.2f)",
                chi2, dof, p_value, cells, pooled, pooled_observed, pooled_expected);
  return error.empty() ? std::string(buf) : error + "; " + buf;
}

ChiSquareResult pearson_chi2(const std::vector<double>& observed, const std::vector<double>& expected,
                             double min_expected) {
  if (observed.size() != expected.size())
    throw std::invalid_argument("pearson_chi2: observed and expected differ in length");
  ChiSquareResult r;
  std::vector<std::size_t> order(expected.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return expected[a] < expected[b]; });
  auto add = [&](double o, double e) {
    r.chi2 += (o - e) * (o - e) / e;
    ++r.cells;
  };
  for (std::size_t i : order) {
    const double e = expected[i], o = observed[i];
    if (!(e >= 0) || !std::isfinite(e)) {
      r.error = "an expected count is negative or not finite";
      continue;
    }
    if (e == 0) {
      // Draws where the claimed density integrates to zero: the sampler and pdf disagree.
      if (o > 0 && r.error.empty()) r.error = "samples in a cell where the pdf integrates to zero";
      continue;
    }
    // Small cells first (sorted): they go to the pool, and the first large cell tops the pool
    // up if it is still below the threshold.
    if (e < min_expected || (r.pooled > 0 && r.pooled_expected < min_expected)) {
      r.pooled_expected += e;
      r.pooled_observed += o;
      ++r.pooled;
      continue;
    }
    add(o, e);
  }
  if (r.pooled > 0) add(r.pooled_observed, r.pooled_expected);
  r.dof = r.cells - 1;
  if (r.dof < 1 && r.error.empty()) r.error = "fewer than two cells after pooling (too few samples)";
  r.p_value = r.dof >= 1 ? chi2_p_value(r.chi2, r.dof) : 0.0;
  return r;
}

// --- domains ---------------------------------------------------------------------------------

namespace {
double wrapped_phi(const Vec3& p) {
  const double ph = std::atan2(p.y(), p.x());
  return ph < 0 ? ph + 2 * kPi : ph;
}
Vec3 from_polar(double cos_theta, double phi) {
  const double s = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
  return Vec3(s * std::cos(phi), s * std::sin(phi), cos_theta);
}
}  // namespace

ChiSquareDomain ChiSquareDomain::sphere() {
  ChiSquareDomain d;
  d.name = "sphere";
  d.point = [](double u, double v) { return from_polar(1 - 2 * u, 2 * kPi * v); };
  d.param = [](const Vec3& p, double& u, double& v) {
    const double n = p.norm();
    if (!(n > 0) || !std::isfinite(n)) return false;
    u = std::clamp(0.5 * (1 - p.z() / n), 0.0, 1.0);
    v = wrapped_phi(p) / (2 * kPi);
    return true;
  };
  d.jacobian = [](double, double) { return 4 * kPi; };
  return d;
}

ChiSquareDomain ChiSquareDomain::hemisphere() {
  ChiSquareDomain d;
  d.name = "hemisphere";
  d.point = [](double u, double v) { return from_polar(1 - u, 2 * kPi * v); };
  d.param = [](const Vec3& p, double& u, double& v) {
    const double n = p.norm();
    if (!(n > 0) || !std::isfinite(n) || p.z() < 0) return false;
    u = std::clamp(1 - p.z() / n, 0.0, 1.0);
    v = wrapped_phi(p) / (2 * kPi);
    return true;
  };
  d.jacobian = [](double, double) { return 2 * kPi; };
  return d;
}

ChiSquareDomain ChiSquareDomain::hemisphere_slopes(double s) {
  if (!(s > 0)) throw std::invalid_argument("hemisphere_slopes: the slope scale must be positive");
  ChiSquareDomain d;
  d.name = "hemisphere (slope cells)";
  // tan(theta) = s u / (1 - u): u = t / (t + s).
  d.point = [s](double u, double v) {
    const double th = std::atan2(s * u, 1 - u), ph = 2 * kPi * v;
    return Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
  };
  d.param = [s](const Vec3& p, double& u, double& v) {
    const double n = p.norm();
    if (!(n > 0) || !std::isfinite(n) || p.z() < 0) return false;
    const double r = std::hypot(p.x(), p.y());
    u = std::clamp(r / (r + s * p.z()), 0.0, 1.0);  // t / (t + s) with t = r / z
    v = wrapped_phi(p) / (2 * kPi);
    return true;
  };
  // d omega = sin(theta) dtheta dphi, dtheta/du = s / ((1 - u)^2 + s^2 u^2).
  d.jacobian = [s](double u, double) {
    const double th = std::atan2(s * u, 1 - u);
    return std::sin(th) * s / ((1 - u) * (1 - u) + s * s * u * u) * 2 * kPi;
  };
  return d;
}

ChiSquareDomain ChiSquareDomain::rectangle(double x0, double x1, double y0, double y1) {
  if (!(x1 > x0) || !(y1 > y0)) throw std::invalid_argument("rectangle: empty");
  ChiSquareDomain d;
  d.name = "rectangle";
  d.point = [=](double u, double v) { return Vec3(x0 + (x1 - x0) * u, y0 + (y1 - y0) * v, 0.0); };
  d.param = [=](const Vec3& p, double& u, double& v) {
    if (!(p.x() >= x0 && p.x() <= x1 && p.y() >= y0 && p.y() <= y1)) return false;
    u = (p.x() - x0) / (x1 - x0);
    v = (p.y() - y0) / (y1 - y0);
    return true;
  };
  const double area = (x1 - x0) * (y1 - y0);
  d.jacobian = [area](double, double) { return area; };
  return d;
}

// --- the harness -----------------------------------------------------------------------------

ChiSquareTest::ChiSquareTest(ChiSquareDomain domain, Sampler sampler, Pdf pdf, Options options)
    : domain_(std::move(domain)), sampler_(std::move(sampler)), pdf_(std::move(pdf)), opt_(options) {
  if (opt_.res_u < 1 || opt_.res_v < 1 || opt_.samples < 1 || opt_.quadrature < 1)
    throw std::invalid_argument("ChiSquareTest: resolution, samples and quadrature must be positive");
}

ChiSquareTest::ChiSquareTest(ChiSquareDomain domain, std::vector<Vec3> points, Pdf pdf, Options options)
    : domain_(std::move(domain)), points_(std::move(points)), pdf_(std::move(pdf)), opt_(options) {
  if (points_.empty()) throw std::invalid_argument("ChiSquareTest: no points");
  opt_.samples = points_.size();
  if (opt_.res_u < 1 || opt_.res_v < 1 || opt_.quadrature < 1)
    throw std::invalid_argument("ChiSquareTest: resolution and quadrature must be positive");
}

void ChiSquareTest::draw() {
  if (drawn_) return;
  const int nu = opt_.res_u, nv = opt_.res_v;
  const std::size_t cells = static_cast<std::size_t>(nu) * nv;
  // Integer counts per thread, summed: the histogram does not depend on the thread count.
  tbb::enumerable_thread_specific<std::vector<std::uint64_t>> local(
      [&] { return std::vector<std::uint64_t>(cells + 1, 0); });
  tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, opt_.samples, 4096),
                    [&](const tbb::blocked_range<std::uint64_t>& range) {
                      auto& h = local.local();
                      for (std::uint64_t k = range.begin(); k != range.end(); ++k) {
                        std::optional<Vec3> p;
                        if (points_.empty()) {
                          CounterRng rng(opt_.seed, 0xC41507E57ull, k);
                          p = sampler_(rng);
                        } else {
                          p = points_[k];
                        }
                        double u, v;
                        if (!p || !domain_.param(*p, u, v) || !(u >= 0 && u <= 1 && v >= 0 && v <= 1)) {
                          ++h[cells];
                          continue;
                        }
                        const int iu = std::min(nu - 1, static_cast<int>(u * nu));
                        const int iv = std::min(nv - 1, static_cast<int>(v * nv));
                        ++h[static_cast<std::size_t>(iv) * nu + iu];
                      }
                    });
  observed_.assign(cells + 1, 0.0);
  for (const auto& h : local)
    for (std::size_t c = 0; c <= cells; ++c) observed_[c] += static_cast<double>(h[c]);
  drawn_ = true;
}

std::vector<double> ChiSquareTest::integrate(const Pdf& pdf, double* total) const {
  const int nu = opt_.res_u, nv = opt_.res_v;
  const auto gl = models::detail::gauss_legendre(opt_.quadrature);
  const double n = static_cast<double>(opt_.samples);
  // Gauss-Legendre product rule on [u0, u1] x [v0, v1] of pdf(point) * jacobian.
  auto rule = [&](double u0, double u1, double v0, double v1) {
    double s = 0;
    for (const auto& [xa, wa] : gl)
      for (const auto& [xb, wb] : gl) {
        const double u = 0.5 * (u0 + u1) + 0.5 * (u1 - u0) * xa;
        const double v = 0.5 * (v0 + v1) + 0.5 * (v1 - v0) * xb;
        s += wa * wb * pdf(domain_.point(u, v)) * domain_.jacobian(u, v);
      }
    return s * 0.25 * (u1 - u0) * (v1 - v0);
  };
  // Adaptive: a rectangle is accepted when its four quarters agree with it within `tol`
  // (an absolute probability, shared equally by the quarters when they are refined).
  std::function<double(double, double, double, double, double, double, int)> adapt =
      [&](double u0, double u1, double v0, double v1, double whole, double tol, int depth) {
        const double um = 0.5 * (u0 + u1), vm = 0.5 * (v0 + v1);
        const double q[4] = {rule(u0, um, v0, vm), rule(um, u1, v0, vm), rule(u0, um, vm, v1),
                             rule(um, u1, vm, v1)};
        const double sum = q[0] + q[1] + q[2] + q[3];
        if (depth >= opt_.max_depth || std::abs(sum - whole) <= tol) return sum;
        return adapt(u0, um, v0, vm, q[0], tol / 4, depth + 1) + adapt(um, u1, v0, vm, q[1], tol / 4, depth + 1) +
               adapt(u0, um, vm, v1, q[2], tol / 4, depth + 1) + adapt(um, u1, vm, v1, q[3], tol / 4, depth + 1);
      };
  const std::size_t cells = static_cast<std::size_t>(nu) * nv;
  std::vector<double> p(cells + 1, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      const int iu = static_cast<int>(c % nu), iv = static_cast<int>(c / nu);
      const double u0 = double(iu) / nu, u1 = double(iu + 1) / nu, v0 = double(iv) / nv, v1 = double(iv + 1) / nv;
      // Allowed error: `tolerance` Poisson standard deviations of the cell's count, so that
      // quadrature adds at most ~tolerance^2 per cell to chi2.
      const double whole = rule(u0, u1, v0, v1);
      const double tol = opt_.tolerance * std::sqrt(std::max(1.0, n * std::abs(whole))) / n;
      p[c] = adapt(u0, u1, v0, v1, whole, tol, 0);
    }
  });
  double sum = 0;
  for (std::size_t c = 0; c < cells; ++c) sum += p[c];
  *total = sum;
  // Expected counts; the last cell takes the mass the pdf leaves outside the domain.
  for (std::size_t c = 0; c < cells; ++c) p[c] *= n;
  p[cells] = n * std::max(0.0, 1.0 - sum);
  return p;
}

ChiSquareResult ChiSquareTest::finish(const std::vector<double>& expected, double total) const {
  ChiSquareResult r = pearson_chi2(observed_, expected, opt_.min_expected);
  // The pdf may leave mass outside the domain (refused samples), never claim more than 1.
  if (total > 1 + 1e-3 && r.error.empty()) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "the pdf integrates to %.6f > 1 over the %s", total, domain_.name.c_str());
    r.error = buf;
  }
  return r;
}

const ChiSquareResult& ChiSquareTest::run() {
  draw();
  if (expected_.empty()) expected_ = integrate(pdf_, &integral_);
  result_ = finish(expected_, integral_);
  return result_;
}

ChiSquareResult ChiSquareTest::run_against(const Pdf& other, bool normalize) {
  draw();
  if (expected_.empty()) expected_ = integrate(pdf_, &integral_);
  double total = 0;
  std::vector<double> e = integrate(other, &total);
  if (normalize && total > 0) {
    for (std::size_t c = 0; c + 1 < e.size(); ++c) e[c] *= integral_ / total;
    e.back() = expected_.back();
    total = integral_;
  }
  return finish(e, total);
}

std::string ChiSquareTest::describe(int worst) const {
  std::string s = domain_.name + ", " + std::to_string(opt_.samples) + " samples, " +
                  std::to_string(opt_.res_u) + " x " + std::to_string(opt_.res_v) + " cells: " +
                  result_.summary();
  if (observed_.empty() || expected_.empty()) return s;
  std::vector<std::size_t> order(observed_.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  auto term = [&](std::size_t c) {
    const double e = expected_[c], o = observed_[c];
    return e > 0 ? (o - e) * (o - e) / e : (o > 0 ? HUGE_VAL : 0.0);
  };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return term(a) > term(b); });
  const std::size_t cells = observed_.size() - 1;
  for (int k = 0; k < worst && k < static_cast<int>(order.size()); ++k) {
    const std::size_t c = order[k];
    char buf[160];
    if (c == cells) {
      std::snprintf(buf, sizeof buf, "\n  refused/outside: observed %.0f expected %.2f", observed_[c], expected_[c]);
    } else {
      const int iu = static_cast<int>(c % opt_.res_u), iv = static_cast<int>(c / opt_.res_u);
      const Vec3 p = domain_.point((iu + 0.5) / opt_.res_u, (iv + 0.5) / opt_.res_v);
      std::snprintf(buf, sizeof buf, "\n  cell (%d, %d) at (%.3f, %.3f, %.3f): observed %.0f expected %.2f", iu, iv,
                    p.x(), p.y(), p.z(), observed_[c], expected_[c]);
    }
    s += buf;
  }
  return s;
}

}  // namespace microsim
