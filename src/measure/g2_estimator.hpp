// The G2 estimator ([GeomBSDF24, eq. 16], measure/g2_measure.hpp), written once against Scene
// for every surface it measures: a whole surface on its Tracer (one part) and an ensemble scene
// traced part by part (measure/ensemble_estimators.hpp). What differs between them is only how
// their facets are listed and summed and where the stratified draws put the points (G2Points);
// the per-facet weights and models, the points, the two occlusion rays, the tallies, their
// exchange with other processes (measure/shards.hpp) and the totals are these.
#pragma once
#include <algorithm>
#include <cstdint>
#include <memory>

#include "microsim/measure/g2_result.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/models/ndf.hpp"
#include "microsim/trace/scene.hpp"

namespace microsim {

// One facet's terms of the exact sums at (o, i): whether it faces both directions, its weight
// w_f = A_f (o.m + i.m) / 2 over the facets facing both (else 0; symmetric in (o, i), G1's
// A_f (v.m) at o = i = v), w_f times the V-cavity G2 [Heitz14, eq. 24 and Sec. 6], and its
// back-facing projected areas toward o and toward i (Smith Lambda from the facets, [Heitz14,
// App. A]).
struct G2FacetTerms {
  bool front = false;
  double weight = 0, vcavity = 0, back_o = 0, back_i = 0;
};
inline G2FacetTerms g2_facet_terms(const Vec3& o, const Vec3& i, const Vec3& m, double a) {
  const double om = o.dot(m), im = i.dot(m);
  G2FacetTerms t;
  t.front = om > 0 && im > 0;
  t.weight = t.front ? 0.5 * a * (om + im) : 0.0;
  if (t.front) t.vcavity = t.weight * models::vcavity_G2(o, i, m);
  t.back_o = a * std::max(0.0, -om);
  t.back_i = a * std::max(0.0, -im);
  return t;
}

// Checks o, i (above the horizon) and the sample count (UsageError naming the option), then a
// result with the unit directions, the macro area and the empty normal bins of the options.
G2Result start_g2(const Vec3& o, const Vec3& i, const G2Options& opt, double macro_area);

// The random stream of the unordered pair {o, i}: swapping the directions draws the same points.
std::uint64_t pair_stream(const Vec3& o, const Vec3& i, std::uint64_t salt);

// The replicates of opt.rays area samples (sets r.replicates and r.samples).
ReplicatePlan plan_g2(G2Result& r, const G2Options& opt);

// Where the points fall and the scenes they are traced in: a surface cut into parts (a whole
// surface is one), each traced on its own in its own frame. Point j of replicate q has the
// generator CounterRng(seed, ReplicatePlan::stream(stream(), q), j); its first draw places it on
// a facet along the CDF of w_f (stratified: within a replicate the facet index does not decrease
// with j), the next two on the facet (Scene::facet_point).
class G2Points {
 public:
  virtual ~G2Points() = default;
  virtual std::uint64_t stream() const = 0;
  virtual std::size_t parts() const = 0;
  virtual std::unique_ptr<Scene> scene(std::size_t k) const = 0;
  // A world direction in part k's frame.
  virtual Vec3 to_local(std::size_t k, const Vec3& w) const = 0;
  // The facets [first, end) of part k; facet f is facet f - first of its scene.
  virtual UnitRange facets(std::size_t k) const = 0;
  // The points [first, end) of replicate q that land on the facets `f`.
  virtual UnitRange points_on(int q, UnitRange f) const = 0;
  // The facet of point j of replicate q, drawn with the point's generator (one draw).
  virtual std::size_t place(int q, std::uint64_t j, CounterRng& rng) const = 0;
  // The normal bin of facet f.
  virtual int bin(std::size_t f) const = 0;
  // A facet pressed against an opposite-facing twin (touching walls, [GeomBSDF24, Fig. 6],
  // FacetTable::buried): hidden from every direction, its occlusion rays not traced (they would
  // start inside the neighbour and skip the twin at distance zero).
  virtual bool buried(std::size_t) const { return false; }
};

// The points of this process's replicates (opt.split) traced with two occlusion rays each,
// toward r.o and toward r.i, in their part's scene: sets the per-replicate counts of r.bins and
// r.counters, completes them from the other processes and sums the totals. opt.progress after
// each pass of work units.
void trace_g2_points(const G2Points& points, G2Result& r, const G2Options& opt, const ReplicatePlan& plan);

}  // namespace microsim
