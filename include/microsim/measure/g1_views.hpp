// G1 of one surface over a list of view directions, whatever the surface's kind: the rows of the
// G1 table (g1_table, add_row) in the order of the views.
//  * a V-cavity ensemble (is_vcavity) is traced groove by groove (measure_g1 on its
//    vcavity_grooves, [Heitz14, Sec. 6.1] made explicit);
//  * a view below the horizon (v.n < 0, meshes only) measures the undersurface explicitly, beside
//    the surface's own G1 at -v and at v reflected across the macrosurface, the two
//    approximations of [GeomBSDF24, "Inherent Assumptions"] (add_undersurface_approximations);
//  * otherwise one tracer and one facet table serve every view.
#pragma once
#include <functional>
#include <vector>

#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/table.hpp"

namespace microsim {

struct G1Views {
  Table table;                // one row per view
  TraceCounters counters;     // every traced ray, the approximations' included
  double build_seconds = 0;   // scene builds (the surface, and its undersurface)
  bool vcavity = false;       // measured groove by groove
};

// Throws UsageError for views below the horizon of a heightfield or a V-cavity ensemble, and
// for views in the horizon. `progress` (optional) gets the number of views done, fractional.
G1Views measure_g1_views(const Microsurface& s, const std::vector<Vec3>& views, G1Options options,
                         const std::function<void(double views_done)>& progress = {});

}  // namespace microsim
