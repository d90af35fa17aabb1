// The G1 estimator of docs/theory/masking.md, written once for every scene: the tally of one
// replicate, the exact facet sums per normal bin, one ray of each estimator on a Scene, and the
// completion of the replicates' tallies (the exchange with other processes, measure/shards.hpp,
// and the counts of G1Result). A whole surface (g1_measure.cpp, with the grid fast paths of a
// heightfield) and an ensemble traced part by part (ensemble_g1.cpp) plan their rays and random
// streams their own way and count them with these.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "microsim/measure/g1_result.hpp"
#include "microsim/measure/shards.hpp"
#include "microsim/models/vgroove_multiple.hpp"
#include "microsim/tally_fields.hpp"
#include "microsim/trace/scene.hpp"

namespace microsim {

// One replicate's counts per normal bin: (a) ray-casting hits, (b) area samples and the visible
// ones. Integer counts: their sums do not depend on the order the rays are traced in.
struct G1Tally {
  std::vector<std::uint64_t> hits, samples, visible;
  TraceCounters counters;     // summed into the call's total, not per replicate
  std::size_t draw_hint = 0;  // area sampling: block of the previous draw (a search start)
  explicit G1Tally(int nbins = 0) : hits(nbins), samples(nbins), visible(nbins) {}
  // The per-replicate counts (tally_fields.hpp): summed over chunks and exchanged.
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f("hits", &G1Tally::hits);
    f("samples", &G1Tally::samples);
    f("visible", &G1Tally::visible);
  }
};

// A result for view v (unit, theta, phi) with the options' empty normal bins.
G1Result start_g1(const Vec3& v, const G1Options& o, double macro_area);

// The exact facet sums of r.bins at r.v: per bin the area, the front projected area
// sum_f A_f max(0, v.m_f), its mean normal and the V-cavity-weighted front projected area
// [Heitz14, eq. 24]; r.total_area; and Lambda(v) = sum_f A_f max(0, -v.m_f) / ((v.n) A)
// [Heitz14, App. A], `macro_projected` = (v.n) A. facet(k, m, a) sets facet k's unit normal m
// and area a and returns its bin. Deterministic sums (sum_over_facets).
template <class Facet>
void sum_g1_facets(G1Result& r, std::size_t num_facets, double macro_projected, Facet&& facet) {
  const Vec3 v = r.v;
  const int nbins = static_cast<int>(r.bins.size());
  // Per bin: area, front projected area, projected-area-weighted normal (3), V-cavity-weighted
  // front projected area; then back area.
  const std::size_t width = 6 * static_cast<std::size_t>(nbins) + 1;
  const std::vector<double> sums = sum_over_facets(num_facets, width, [&](std::size_t k, double* acc) {
    Vec3 m;
    double a;
    double* bin = acc + 6 * static_cast<std::size_t>(facet(k, m, a));
    const double proj = a * m.dot(v);  // A_f (v.m_f)
    const double front = std::max(0.0, proj);
    bin[0] += a;
    bin[1] += front;
    bin[2] += front * m.x();
    bin[3] += front * m.y();
    bin[4] += front * m.z();
    if (front > 0) bin[5] += front * models::vcavity_G1(v, m);
    acc[width - 1] += std::max(0.0, -proj);
  });
  for (int b = 0; b < nbins; ++b) {
    const double* bin = sums.data() + 6 * static_cast<std::size_t>(b);
    r.bins[b].area = bin[0];
    r.bins[b].front_projected = bin[1];
    r.bins[b].vcavity_weighted = bin[5];
    r.bins[b].mean_normal = Vec3(bin[2], bin[3], bin[4]);
    if (r.bins[b].mean_normal.norm() > 0) r.bins[b].mean_normal.normalize();
    r.total_area += bin[0];
  }
  r.lambda_numeric = sums[width - 1] / macro_projected;
}

// The point of the window at (a, b) in [0, 1]^2: a ray-casting ray's origin.
inline Vec3 window_point(const RayWindow& w, const Vec2& ab) {
  return Vec3(w.origin0 + ab.x() * w.e1 + ab.y() * w.e2);
}

// (a) One ray-casting ray from `org` along -v: a first hit on the front face of a facet of the
// scene counts in the bin bin_of(hit, facet) (-1: outside the binning, not tallied). A back face
// met first is a rounding gap (counted by the tracer), not visible area.
template <class BinOf>
void cast_g1_ray(const Scene& scene, const Vec3& org, const Vec3& v, BinOf&& bin_of, G1Tally& t) {
  const TraceHit h = scene.intersect(org, -v, nullptr, t.counters);
  const std::size_t f = scene.front_facet(h);
  if (f == Scene::kNoFacet) return;
  const int b = bin_of(h, f);
  if (b >= 0) ++t.hits[static_cast<std::size_t>(b)];
}

// (b) One area sample: the point x of a facet of bin b, drawn by front-facing projected area,
// and its occlusion ray toward v leaving the facet's plane.
inline void sample_g1_point(const Scene& scene, const Vec3& x, const Vec3& v, const SourcePlane& plane, int b,
                            G1Tally& t) {
  ++t.samples[b];
  if (!scene.occluded(x, v, &plane, t.counters)) ++t.visible[b];
}

// The rays of one replicate: what its counts can be at most.
struct G1RaysPerReplicate {
  std::uint64_t raycast = 0, samples = 0;
};

// tallies[q] holds both estimators' counts of replicate q for the replicates `reps` of this
// process (zero for the others) and `counters` their trace counters: completes them from the
// other processes (split; nullptr: none), refuses impossible counts received (UsageError), and
// sets r's per-replicate and total counts and r.counters.
void finish_g1(G1Result& r, std::vector<G1Tally>& tallies, const TraceCounters& counters, TallySplit* split,
               UnitRange reps, G1RaysPerReplicate rays);

}  // namespace microsim
