// Areal surface-texture parameters of a heightfield, as a metrologist reads them (ISO 25178-2
// style: Sq, Sa, Sdq, Sal, Str), beside the microfacet view: slope moments (the Beckmann alpha of
// [GeomBSDF24, eq. 1b/1c]'s slope variances), the maximum-likelihood GGX alpha of the facet slopes, and
// histograms of heights and slopes against Gaussian, Beckmann and GGX with a chi^2 per degree of
// freedom.
//
// Heights are taken on the grid vertices, slopes on the triangle facets of the heightfield
// (every facet has the same projected area, dx dy / 2, so the facet list is a uniform sample of
// the surface's slope distribution over its projected area). A periodic tile wraps around; a
// non-periodic window uses only the facets and lags inside it.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// A height grid: z(i, j) at x = i dx, y = j dy, row-major in j (as Microsurface::heights()).
struct HeightGridView {
  int nx = 0, ny = 0;
  double dx = 1, dy = 1;
  const std::vector<float>* z = nullptr;
  bool periodic = true;
};
HeightGridView grid_view(const Microsurface& heightfield);

// Observed and expected counts in equal-probability bins of a model (expected = n / bins each).
struct HistogramFit {
  std::string model;
  std::vector<double> edges;      // bins + 1 edges in the histogrammed variable (+inf last)
  std::vector<double> observed;   // counts
  std::vector<double> expected;   // counts under the model
  double chi2 = 0;
  int dof = 0;                    // bins - 1 - fitted parameters
  double chi2_per_dof() const { return dof > 0 ? chi2 / dof : 0; }
};

// Slope statistics of a uniform sample of slopes (s_x, s_y) = (dz/dx, dz/dy).
struct SlopeStats {
  std::size_t n = 0;
  double mean_x = 0, mean_y = 0;
  double rms_x = 0, rms_y = 0;      // standard deviations of s_x, s_y
  double sdq = 0;                   // sqrt(mean |grad z|^2)  (ISO 25178 Sdq)
  double beckmann_alpha_x = 0, beckmann_alpha_y = 0;  // sqrt(2) rms: Beckmann's slope variance alpha^2/2
  double ggx_alpha_x = 0, ggx_alpha_y = 0;            // maximum likelihood, anisotropic GGX slopes
  double ggx_alpha = 0;                               // maximum likelihood, isotropic GGX
  int ggx_iterations = 0;
  HistogramFit beckmann_fit, ggx_fit;                 // of the normalized slope radius
};
// GGX slope density (D mapped to slope space, P(s) = D(m) cos^4 theta_m, [Heitz14, App. A]):
// P(s) = 1 / (pi ax ay (1 + q^2)^2),
// q^2 = (sx/ax)^2 + (sy/ay)^2. Its maximum-likelihood (ax, ay) solve ax^2 = (4/n) sum sx^2/(1+q^2)
// (a bivariate Student t with 2 degrees of freedom; the fixed point is its EM iteration).
// Sums run in blocks of 65536 slopes, in parallel, the block sums added in block order: the
// result is the same for any thread count (and, up to 65536 slopes, that of one serial loop).
SlopeStats slope_stats(const std::vector<std::array<double, 2>>& slopes, int bins = 20);
// The same for the facet slopes of a grid (facet_slopes(g)), computed from the heights in every
// pass instead of held (16 bytes per facet).
SlopeStats slope_stats(const HeightGridView& g, int bins = 20);

// Heights against a Gaussian of the sample mean and Sq, in equal-probability bins.
HistogramFit gaussian_height_fit(const std::vector<double>& heights, int bins = 20);

// Autocorrelation (from the FFT): Sal = shortest lag length at which the normalized ACF first
// falls to s = 0.2 along any direction; Str = Sal / the longest such length (1 = isotropic,
// -> 0 = strongly directional). A direction that never decays within half the grid counts as
// its half-grid length and sets `decayed_in_every_direction` to false.
struct AcfStats {
  double sal = 0, str = 0;
  double longest = 0;             // the decay length along the slowest direction
  double slowest_direction_deg = 0;  // of the longest decay length (the lay), from +x
  bool decayed = false;           // the ACF reaches s in some direction
  bool decayed_in_every_direction = false;
  double threshold = 0.2;
};
AcfStats acf_stats(const HeightGridView& g, double threshold = 0.2);
// Normalized autocorrelation at integer lags (di, dj), di in [0, nx), dj in [0, ny) (circular for a
// periodic grid; for a window, over the overlapping pairs only, lags beyond half the window 0).
std::vector<double> autocorrelation(const HeightGridView& g);

struct Metrology {
  bool textured = false;                    // false: constant heights (only points, mean filled)
  std::size_t points = 0;
  double mean = 0, sq = 0, sa = 0, sz = 0;  // Sz = max - min
  double skewness = 0, kurtosis = 0;        // Ssk, Sku
  SlopeStats slopes;
  AcfStats acf;
  double cells_per_correlation_length = 0;  // Sal / max(dx, dy)
  // The same in units of l of a Gaussian ACF exp(-r^2/l^2) (generate gaussian's
  // --correlation-length), which decays to 0.2 at Sal = l sqrt(ln 5).
  double cells_per_gaussian_length = 0;
  HistogramFit height_fit;
};
// Throws UsageError for grids smaller than 2 x 2.
Metrology measure_metrology(const HeightGridView& g);
// Bytes measure_metrology holds at its peak on an nx x ny grid, its float heights included (4 per
// vertex): the ACF's transform, a complex<double> (16 bytes) per lag, over nx ny lags on a
// periodic grid and over the zero-padded 2 nx x 2 ny on a window (64 bytes per vertex).
double metrology_bytes(double nx, double ny, bool periodic);
Json metrology_to_json(const Metrology& m);

// The facet slopes of a grid (two per cell, the cell split as Microsurface::facet does).
std::vector<std::array<double, 2>> facet_slopes(const HeightGridView& g);

}  // namespace microsim
