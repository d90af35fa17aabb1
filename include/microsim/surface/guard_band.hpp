// A measured patch (not periodic) measured as a finite window with a guard band: the whole
// patch is traced without wrap-around, and every estimator takes its sample points and ray
// footprints only in the interior, inset from the border by the guard width, so that masking
// near the interior's border is by real geometry. Rays that reach the patch's side walls end
// there (Tracer::first_hit): upward they count as escaped, downward as lost. Both sides of
// that rule are biases the guard keeps small; their size against the guard width is measured
// by analysis/guard_band_bias.cpp (docs/theory/discretization.md).
#pragma once
#include <string>

#include "microsim/surface/microsurface.hpp"

namespace microsim {

// Default guard width in correlation lengths l (Gaussian convention exp(-r^2/l^2), i.e.
// Sal / sqrt(ln 5)): the smallest width of the bias table whose bias is within the ray-count
// error at the default ray counts.
constexpr double kDefaultGuardCorrelationLengths = 8.0;

// The correlation length l of a heightfield's heights (from its autocorrelation's Sal, over
// the overlapping pairs: the patch is not periodic).
double patch_correlation_length(const Microsurface& s);

// Guard cells for a width in surface units: the smallest whole number of cells that covers it.
int guard_cells(double width, double cell);

// Makes a heightfield a window measured in its interior: the traced cells inset by (gx, gy)
// cells on each side. periodic = false: a non-periodic window (the measured patch);
// periodic = true: the periodic tile restricted to the same interior cells, wrap-around kept
// (the reference the guard's bias is measured against). Records "guard_band" (widths,
// cells, interior rectangle and area, the side-wall rule; `correlation_length` when > 0) in
// the description, so every record carries it. UsageError naming `option` when the guard
// leaves no interior (a guard as wide as half the patch or wider) or is negative.
void apply_guard_band(Microsurface& s, int gx, int gy, bool periodic, double correlation_length = 0,
                      const std::string& option = "{guard}");

// A heightfield loaded from a window file: its recorded guard cells, or the default width
// (kDefaultGuardCorrelationLengths l) for a description without one.
void apply_recorded_guard_band(Microsurface& s);

}  // namespace microsim
