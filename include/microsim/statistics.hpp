// Statistics of the library and its tests in one place: the distributions (chi-square tail and
// quantile, Student's t, Sidak thresholds: measure/stats.hpp) and a chi-square goodness-of-fit
// harness for samplers.
//
// The harness (the idea of Mitsuba's ChiSquareTest; Pearson's test of a multinomial histogram):
// a sampler draws N points of a 2-D domain (a rectangle, the sphere or the hemisphere of
// directions), the domain's parameter rectangle [0,1]^2 is cut into cells, and the observed
// counts are compared with N times the pdf integrated over each cell by adaptive Gauss-Legendre
// quadrature. Cells expected to hold fewer than 5 samples are pooled (smallest first), samples the
// sampler refuses or that fall outside the domain form one more cell with expectation
// N (1 - integral of the pdf), and the p-value P(chi2_dof >= chi2) is compared with a Sidak-
// corrected level 1 - (1 - alpha)^(1/tests) so that a family of tests keeps its false-alarm rate.
// A sample in a cell where the pdf integrates to zero, or a pdf whose integral exceeds 1, fails
// outright (no statistics needed).
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/measure/stats.hpp"

namespace microsim {

// Per-test level that keeps the family-wise false-alarm rate `alpha` over `tests` independent
// tests (Sidak): 1 - (1 - alpha)^(1/tests).
double sidak_alpha(double alpha, int tests);

// Pearson's chi-square of observed counts against expected counts (both per cell, same length;
// the expectations sum to the number of draws). Cells with expectation below `min_expected` are
// pooled, smallest first, until the pool reaches it; dof = cells after pooling - 1.
struct ChiSquareResult {
  double chi2 = 0;
  int dof = 0;
  double p_value = 1;
  int cells = 0;          // cells in the statistic, the pool counted once
  int pooled = 0;         // cells merged into the pool
  double pooled_expected = 0, pooled_observed = 0;
  std::string error;      // a failure no statistic can excuse (empty: none)
  // True iff there is no error, dof >= 1 and p >= sidak_alpha(alpha, tests).
  bool passed(double alpha = 0.01, int tests = 1) const;
  std::string summary() const;  // one line: chi2, dof, p, cells, pooled, error
};
ChiSquareResult pearson_chi2(const std::vector<double>& observed, const std::vector<double>& expected,
                             double min_expected = 5.0);

// A 2-D domain as the image of the parameter rectangle [0,1]^2: `point` maps (u, v) to a point
// (a direction, or (x, y, 0) on a plane), `param` maps a point back (false: not in the domain),
// and `jacobian` is the domain's measure (solid angle or area) per unit parameter area.
struct ChiSquareDomain {
  std::string name;
  std::function<Vec3(double u, double v)> point;
  std::function<bool(const Vec3& p, double& u, double& v)> param;
  std::function<double(double u, double v)> jacobian;

  // Unit sphere, equal-area: cos(theta) = 1 - 2u, phi = 2 pi v (jacobian 4 pi).
  static ChiSquareDomain sphere();
  // Upper hemisphere (z >= 0), equal-area: cos(theta) = 1 - u, phi = 2 pi v (jacobian 2 pi).
  static ChiSquareDomain hemisphere();
  // Upper hemisphere with cells that follow a lobe of slope width `s` around +z:
  // u = tan(theta) / (tan(theta) + s), phi = 2 pi v.
  static ChiSquareDomain hemisphere_slopes(double s);
  // The rectangle [x0, x1] x [y0, y1] of the plane z = 0 (jacobian = its area).
  static ChiSquareDomain rectangle(double x0, double x1, double y0, double y1);
};

// The harness. The sampler draws one point from its own counter-based stream (any number of
// uniforms), or returns nothing when it refuses (a direction below a horizon, a failed warp);
// the pdf is the density it claims, with respect to the domain's measure.
class ChiSquareTest {
 public:
  using Sampler = std::function<std::optional<Vec3>(CounterRng& rng)>;
  using Pdf = std::function<double(const Vec3& p)>;
  struct Options {
    int res_u = 32, res_v = 64;       // cells of the parameter rectangle
    std::uint64_t samples = 1000000;  // N
    std::uint64_t seed = 1;
    double min_expected = 5.0;        // pooling threshold
    int quadrature = 4;               // Gauss-Legendre points per side of a (sub)rectangle
    int max_depth = 7;                // adaptive bisections per cell
    double tolerance = 1e-2;          // quadrature error allowed per cell, in Poisson sd of its count
  };

  ChiSquareTest(ChiSquareDomain domain, Sampler sampler, Pdf pdf, Options options);
  // A fixed set of draws made elsewhere (e.g. a generator's random normals); options.samples
  // and options.seed are ignored.
  ChiSquareTest(ChiSquareDomain domain, std::vector<Vec3> points, Pdf pdf, Options options);

  // Draws the samples and integrates the pdf (once each, cached), then the statistic.
  const ChiSquareResult& run();
  // The same samples against another pdf (power checks: a deliberately wrong density);
  // `normalize` rescales it to the integral of the test's own pdf over the domain (a wrong shape,
  // not a wrong mass).
  ChiSquareResult run_against(const Pdf& other, bool normalize = false);

  // Row-major res_v x res_u tables, u fastest; the extra last entry is the "refused or outside"
  // cell. Valid after run().
  const std::vector<double>& observed() const { return observed_; }
  const std::vector<double>& expected() const { return expected_; }
  double pdf_integral() const { return integral_; }  // of the pdf over the whole domain
  const ChiSquareResult& result() const { return result_; }
  // The result plus the cells that contribute most to chi2 (for failure messages).
  std::string describe(int worst = 5) const;

 private:
  void draw();
  std::vector<double> integrate(const Pdf& pdf, double* total) const;
  ChiSquareResult finish(const std::vector<double>& expected, double total) const;

  ChiSquareDomain domain_;
  Sampler sampler_;
  std::vector<Vec3> points_;
  Pdf pdf_;
  Options opt_;
  bool drawn_ = false;
  std::vector<double> observed_, expected_;
  double integral_ = 0;
  ChiSquareResult result_;
};

}  // namespace microsim
