// The normal distribution D of a microsurface, measured exactly from its facets
// (docs/theory/ndf.md), with a between-region standard error from spatial blocks.
#pragma once
#include <nlohmann/json.hpp>

#include "microsim/io/output.hpp"
#include "microsim/measure/binning.hpp"
#include "microsim/measure/table.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {

struct NdfOptions {
  int n_theta = 90;  // over the whole sphere: 2 degree rings
  int n_phi = 72;    // 5 degree sectors
  int blocks = 8;    // blocks x blocks spatial regions for the standard error
};

struct NdfResult {
  DirectionBinning bins{1, 1, kPi};
  std::vector<double> d, d_stderr;   // per bin
  std::vector<double> ring_d, ring_d_stderr;  // per theta ring (phi-averaged)
  FacetSums sums;
  double macro_area = 1;
  int blocks = 1;
};

// D over bin B = sum_{f in B} A_f / (A * solid_angle(B)). The standard error is the spread of
// the same estimate over blocks x blocks regions of the tile (by facet centroid), divided by
// the square root of their number: the region-to-region fluctuation of the surface statistics,
// the error bar that matters against a nominal model.
NdfResult measure_ndf(const Microsurface& s, const NdfOptions& options);

// One row per theta ring (D averaged over phi) with its block error, beside the nominal model.
Table ndf_table(const NdfResult& r, const Microsurface& s);
// Its columns (no rows); one surface at a time (no ensembles).
Table ndf_table_spec();
ExrTable ndf_to_exr(const NdfResult& r, const Microsurface& s);

// Summary of the [GeomBSDF24, eq. 1b/1c] identities and of the slope statistics ("fitted alpha").
Json surface_checks_json(const FacetSums& f, const Microsurface& s);

}  // namespace microsim
