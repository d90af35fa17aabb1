// The VNDF estimator ([Heitz14, eq. 13], measure/vndf_measure.hpp), written once against Scene
// for every surface it measures: a whole surface on its Tracer (one part) and an ensemble scene
// traced part by part (measure/ensemble_estimators.hpp). What differs between them is only where
// the i.i.d. ray origins are drawn and which bin a hit's normal falls in (VndfRays); the rays
// along -v, the histogram, its exchange with other processes (measure/shards.hpp) and the totals
// are these.
#pragma once
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "microsim/measure/vndf_result.hpp"
#include "microsim/trace/scene.hpp"

namespace microsim {

// Checks v (above the horizon) and the ray count, then a result with the unit direction, the
// macro area and the normal binning of the options.
VndfResult start_vndf(const Vec3& v, const VndfOptions& o, double macro_area);

// A ray origin (a, b) in [0, 1)^2 drawn as two CounterRng uniforms (multiples of 2^-53), held
// exactly in 16 bytes: `key` interleaves the 21 leading bits of a and b (b's above a's at every
// level: the Morton order of the origins for coherent rays), `rest` holds the 32 trailing bits of
// a above those of b. Comparing (key, rest) orders the origins by (Morton key, a, b), a total
// order, so a batch sorted by it is the same for any thread count.
struct VndfOrigin {
  std::uint64_t key = 0, rest = 0;
  static VndfOrigin of(double a, double b);
  Vec2 ab() const;
  bool operator<(const VndfOrigin& o) const { return key < o.key || (key == o.key && rest < o.rest); }
};

// The rays of a surface cut into parts (a whole surface is one), each traced on its own in its
// own frame: ray n of the measurement is drawn from its own counter (i.i.d. rays, so the bin
// counts are multinomial).
class VndfRays {
 public:
  virtual ~VndfRays() = default;
  virtual std::size_t parts() const = 0;
  virtual std::unique_ptr<Scene> scene(std::size_t k) const = 0;
  // A world direction in part k's frame.
  virtual Vec3 to_local(std::size_t k, const Vec3& w) const = 0;
  // Rays drawn at once (bounds the memory of their origins).
  virtual std::uint64_t batch() const = 0;
  // The origins (a, b) in [0, 1)^2 on their part's ray window (Scene::ray_window) of the rays
  // of `share` among the rays [first, end) of the measurement, per part, in tracing order.
  virtual std::vector<std::vector<VndfOrigin>> origins(UnitRange rays, UnitRange share) const = 0;
  // The normal bin (-1: none) of a front-face hit on part k's scene.
  virtual int bin(std::size_t k, const Scene& scene, const TraceHit& h) const = 0;
};

// This process's share of r.rays (o.split) traced along -r.v from their origins, the front-face
// first hits histogrammed by bin (back faces and hits outside a measured region are misses):
// sets r.bin_hits, r.hits_below, r.hits and r.counters, completed from the other processes.
// o.progress after each batch.
void trace_vndf_rays(const VndfRays& rays, VndfResult& r, const VndfOptions& o);

// Runs body(j, counts, counters) for j in [0, n) in parallel chunks; per-chunk integer counts
// (nbins + 1: the last one outside every bin) merged in chunk order (identical for any thread
// count).
template <class Body>
void histogram_chunks(std::uint64_t n, int nbins, std::vector<std::uint64_t>& counts,
                      TraceCounters& counters, Body&& body) {
  constexpr std::uint64_t kChunk = 1 << 14;
  const std::uint64_t nchunks = (n + kChunk - 1) / kChunk;
  std::vector<std::vector<std::uint64_t>> parts(nchunks);
  std::vector<TraceCounters> cparts(nchunks);
  tbb::parallel_for(std::uint64_t(0), nchunks, [&](std::uint64_t c) {
    parts[c].assign(nbins + 1, 0);
    const std::uint64_t end = std::min(n, (c + 1) * kChunk);
    for (std::uint64_t j = c * kChunk; j < end; ++j) body(j, parts[c], cparts[c]);
  });
  counts.assign(nbins + 1, 0);
  for (std::uint64_t c = 0; c < nchunks; ++c) {
    for (int b = 0; b <= nbins; ++b) counts[b] += parts[c][b];
    counters += cparts[c];
  }
}

}  // namespace microsim
