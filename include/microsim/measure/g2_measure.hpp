// Masking-shadowing G2(o, m, i) measured on an explicit microsurface ([GeomBSDF24, eq. 16a],
// docs/theory/g2.md): per facet, the fraction of its area visible from both o and i (symmetric in o and i,
// [GeomBSDF24, eq. 16b]). Over a normal bin or all normals the facets are weighted by
//   w_f = A_f (max(0, o.m_f) + max(0, i.m_f)) / 2   over the facets facing both (else 0),
// symmetric in (o, i), equal to G1's projected-area weight A_f max(0, v.m_f) at o = i = v (so
// G2(v, m, v) = G1(v, m) bin by bin and on average, [GeomBSDF24, eq. 16]) and to the BRDF's A_f (i.m) at
// the half vector m = h (where o.h = i.h). Points are drawn with density proportional to w_f
// and two occlusion rays, toward o and toward i, are traced from each:
//   G2(o, m, i) = sum_{f in B} w_f V_f(o, i) / sum_{f in B} w_f,
// and g1_o, g1_i the same ratio with the visibility toward o alone and toward i alone, from the
// same points and weights (at o = i they are G2 itself, and G1(v, m) of the area-sampling G1).
// Facets facing only one direction have G2 = 0 by definition and carry no weight.
//
// Models beside it, averaged with the estimator's own weights:
//  * the four Smith forms [Heitz14, eq. 20-23] do not depend on m beyond chi+(o.m) chi+(i.m), so
//    their average over the facets facing both is their value; they are evaluated with
//    Lambda from the surface's own facets (docs/theory/masking.md) and, when the surface has one, with its
//    nominal NDF [Heitz14, Sec. 3];
//  * the same four forms built per bin from the measured G1(o, m) and G1(i, m) of the bin
//    (Lambda = 1/G1 - 1): they isolate the correlation each form assumes between the two
//    visibilities from the m-dependence of masking that Smith ignores;
//  * the V-cavity G2 depends on m: it is averaged over the surface's own facets facing both,
//    with the weights w_f, exactly like the measurement.
// Standard errors: the rays are split into independent replicates (measure/replicates.hpp).
#pragma once
#include <functional>

#include <nlohmann/json.hpp>

#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/g2_result.hpp"
#include "microsim/measure/table.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

// o and i must have o.n > 0 and i.n > 0 (UsageError otherwise). The random points depend on
// the seed and on the unordered pair {o, i} (and the weights are symmetric): swapping o and i
// traces the same points, so the
// symmetry G2(o, m, i) = G2(i, m, o) [GeomBSDF24, eq. 16b] holds sample for sample. `table` (from
// build_facet_table with g2_normal_binning(options)) saves recomputing the facets.
G2Result measure_g2(const Tracer& tracer, const Vec3& o, const Vec3& i, const G2Options& options,
                    const FacetTable* table = nullptr);

// The table of G2 over direction pairs (measure/table.hpp), and the row of one pair appended to
// it: directions, g2 and g1_o, g1_i with standard errors, the models and the bins.
Table g2_table();
Json& add_row(Table& t, const G2Result& r, const Microsurface& s);

}  // namespace microsim
