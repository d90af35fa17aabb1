#include "microsim/surface/guard_band.hpp"

#include <cmath>

#include "microsim/surface/metrology.hpp"

namespace microsim {

double patch_correlation_length(const Microsurface& s) {
  HeightGridView g = grid_view(s);
  g.periodic = false;
  const AcfStats a = acf_stats(g);
  return a.sal / std::sqrt(std::log(1.0 / a.threshold));  // Gaussian ACF: exp(-Sal^2/l^2) = s
}

int guard_cells(double width, double cell) {
  if (!(width >= 0) || !std::isfinite(width)) return -1;
  return static_cast<int>(std::ceil(width / cell - 1e-9));
}

void apply_guard_band(Microsurface& s, int gx, int gy, bool periodic, double correlation_length,
                      const std::string& option) {
  if (s.kind() != Microsurface::Kind::Heightfield) throw ParameterError(option + ": needs a heightfield");
  const int cx = periodic ? s.nx() : s.nx() - 1, cy = periodic ? s.ny() : s.ny() - 1;
  if (gx < 0 || gy < 0)
    throw ParameterError(option + ": the guard width must be >= 0");
  if (2 * gx >= cx || 2 * gy >= cy)
    throw ParameterError(option + ": a guard of " + std::to_string(gx) + " x " + std::to_string(gy) +
                         " cells leaves no interior in the " + std::to_string(cx) + " x " + std::to_string(cy) +
                         " cells of the patch (the guard must be narrower than half the patch)");
  s.set_sample_region(gx, cx - gx, gy, cy - gy, periodic);
  const Macrosurface& m = s.macro();
  Json g;
  g["cells_x"] = gx;
  g["cells_y"] = gy;
  g["width_x"] = gx * s.dx();
  g["width_y"] = gy * s.dy();
  if (correlation_length > 0) {
    g["correlation_length"] = correlation_length;
    g["width_correlation_lengths"] = std::min(gx * s.dx(), gy * s.dy()) / correlation_length;
  }
  g["interior"] = {{"x0", m.region_x0}, {"x1", m.region_x1}, {"y0", m.region_y0}, {"y1", m.region_y1},
                   {"cells_x", cx - 2 * gx}, {"cells_y", cy - 2 * gy}, {"area", m.area}};
  g["traced"] = periodic ? "periodic tile, wrap-around kept (reference)"
                         : "whole patch, no wrap-around; sample points and ray footprints in the interior";
  g["side_rule"] = "a ray reaching a side wall of the patch inside its slab ends there: escaped "
                   "upward (counted in side_exits), lost downward";
  if (!s.description.is_object()) s.description = Json::object();
  s.description["guard_band"] = g;
}

void apply_recorded_guard_band(Microsurface& s) {
  const Json& d = s.description;
  if (d.is_object() && d.contains("guard_band") && d["guard_band"].is_object()) {
    const Json& g = d["guard_band"];
    auto cells = [&](const char* key) {
      if (!g.contains(key) || !g[key].is_number_integer())
        throw UsageError(std::string("the surface's guard_band has no integer '") + key + "'");
      return g[key].get<int>();
    };
    const double l = g.value("correlation_length", 0.0);
    apply_guard_band(s, cells("cells_x"), cells("cells_y"), false, l);
    return;
  }
  const double l = patch_correlation_length(s);
  const double w = kDefaultGuardCorrelationLengths * l;
  apply_guard_band(s, guard_cells(w, s.dx()), guard_cells(w, s.dy()), false, l,
                   "the default guard band (" + std::to_string(kDefaultGuardCorrelationLengths) +
                       " correlation lengths; re-import with generate heightmap {guard})");
}

}  // namespace microsim
