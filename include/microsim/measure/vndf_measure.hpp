// Distribution of visible normals ([GeomBSDF24, eq. 3b], [Heitz14, eq. 13]) measured on an explicit surface:
// parallel rays along -v from the ray window, the first-hit normals histogrammed over
// direction bins of m. The estimate of the bin average of D_v is
//   D_v(B) = (hits in B / front-face hits) / solid_angle(B),
// a probability density over visible normals (normalized by the hits, which for a periodic
// heightfield are all the rays; for a finite object such as the ellipsoid the normalization
// is that of [Heitz14, eq. 13] by construction).
//
// Beside it: the analytic D_v of the surface's nominal NDF (bin integrals by quadrature), and
// Smith's D_v with the surface's own facets, (v.m)+ D_facets / int (v.m)+ D_facets (visibility
// independent of m). A chi-square goodness-of-fit test and per-bin z-scores (Sidak-corrected
// threshold) compare the histogram with each.
//
// The VNDF sampler of models/ndf.hpp (Beckmann and GGX, anisotropic) is tested the same way:
// its samples histogrammed over the same bins against the bin integrals of D_v.
#pragma once
#include <functional>
#include <optional>

#include <nlohmann/json.hpp>

#include "microsim/measure/binning.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/table.hpp"
#include "microsim/measure/vndf_result.hpp"
#include "microsim/models/ndf.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

// Bin integrals P_B = int_B f(m) dm of a density over the bins' solid angles: each bin cut into
// 4 x 4 sub-bins with 8 x 8 Gauss-Legendre points (DirectionBinning::bin_average).
std::vector<double> bin_integrals(const DirectionBinning& bins,
                                  const std::function<double(const Vec3&)>& f);

// Goodness of fit of a histogram (counts of `total` draws) against bin probabilities.
struct GofResult {
  double chi2 = 0;
  int dof = 0;
  double p_value = 1;
  int cells = 0;          // bins with expected count >= 5, plus the pooled rest when >= 1
  int bins_tested = 0;    // bins in the per-bin z test (expected count >= 5)
  double max_abs_z = 0;   // |count - N p| / sqrt(N p (1-p)) over those bins
  double sidak_z = 0;     // threshold for the family-wise rate
  bool pass() const { return max_abs_z < sidak_z; }
};
GofResult histogram_gof(const std::vector<std::uint64_t>& counts, std::uint64_t total,
                        const std::vector<double>& probabilities, double family_alpha);

VndfResult measure_vndf(const Tracer& tracer, const Vec3& v, const VndfOptions& options,
                        const FacetTable* table = nullptr);

// The VNDF sampler of `ndf` for view v: `n` samples histogrammed over `bins`, against the bin
// integrals of ndf.D_visible(v, .).
struct SamplerTest {
  std::vector<std::uint64_t> counts;
  std::uint64_t n = 0, outside = 0;  // samples that fell in no bin
  std::vector<double> probabilities;
  GofResult gof;
};
SamplerTest test_vndf_sampler(const models::Ndf& ndf, const Vec3& v, std::uint64_t n,
                              const DirectionBinning& bins, std::uint64_t seed,
                              double family_alpha = 0.0027);

// The table of the VNDF over view directions (measure/table.hpp; an ensemble's verdict is the
// Sidak-corrected Student t test of its bins at family_alpha), and the row of one direction
// appended to it: direction, tests against the nominal and Smith-numeric VNDF, the sampler's
// test (when run), and the bins.
Table vndf_table(double family_alpha);
Json& add_row(Table& t, const VndfResult& r, const Microsurface& s, const VndfOptions& options,
              const std::optional<SamplerTest>& sampler);

}  // namespace microsim
