#include "vndf_estimator.hpp"

#include "microsim/measure/sampling.hpp"
#include "microsim/measure/shards.hpp"

namespace microsim {

VndfResult start_vndf(const Vec3& v, const VndfOptions& o, double macro_area) {
  if (!(v.z() > 0)) throw ParameterError("{theta} must be in [0, 90) degrees");
  if (o.rays == 0) throw ParameterError("{rays} must be positive");
  VndfResult r;
  r.v = v.normalized();
  r.binning = vndf_binning(o);
  r.macro_area = macro_area;
  r.rays = o.rays;
  return r;
}

namespace {

// `counts` (nbins + 1, the last one below the horizon) and r.counters hold the rays `share`:
// completes them from the other processes (o.split), then fills the bin counts and totals.
void finish_vndf(VndfResult& r, const VndfOptions& o, UnitRange share, std::vector<std::uint64_t> counts) {
  const int nbins = r.binning.size();
  if (o.split) {
    // Integer bin counts and counters: the other processes' rays are added (measure/shards.hpp).
    Tallies t("vndf", r.rays, share, 0, 0, counts.size() + kCounterValues, 0);
    std::copy(counts.begin(), counts.end(), t.tail_counts.begin());
    put_counters(r.counters, t.tail_counts.data() + counts.size());
    o.split->exchange(t);
    std::copy(t.tail_counts.begin(), t.tail_counts.begin() + static_cast<std::ptrdiff_t>(counts.size()),
              counts.begin());
    r.counters = get_counters(t.tail_counts.data() + counts.size());
  }
  r.bin_hits.assign(counts.begin(), counts.begin() + nbins);
  r.hits_below = counts[nbins];
  for (auto c : counts) r.hits += c;
}

// The rays of part k from `origins` on its window, added to counts and r.counters.
void trace_vndf_part(const VndfRays& rays, std::size_t k, const std::vector<Vec2>& origins, VndfResult& r,
                     std::vector<std::uint64_t>& counts) {
  const std::unique_ptr<Scene> scene = rays.scene(k);
  const Vec3 v = rays.to_local(k, r.v);
  const RayWindow w = scene->ray_window(v);
  const int nbins = r.binning.size();
  std::vector<std::uint64_t> part;
  histogram_chunks(origins.size(), nbins, part, r.counters,
                   [&](std::uint64_t j, std::vector<std::uint64_t>& c, TraceCounters& tc) {
                     const Vec2& ab = origins[j];
                     const Vec3 org = w.origin0 + ab.x() * w.e1 + ab.y() * w.e2;
                     const TraceHit h = scene->intersect(org, -v, nullptr, tc);
                     if (scene->front_facet(h) == Scene::kNoFacet) return;
                     const int b = rays.bin(k, *scene, h);
                     ++c[b >= 0 ? b : nbins];
                   });
  for (int b = 0; b <= nbins; ++b) counts[b] += part[b];
}

}  // namespace

void trace_vndf_rays(const VndfRays& rays, VndfResult& r, const VndfOptions& o) {
  const UnitRange share = share_of(o.split, r.rays);
  std::vector<std::uint64_t> counts(static_cast<std::size_t>(r.binning.size()) + 1, 0);
  for (std::uint64_t first = 0; first < r.rays; first += rays.batch()) {
    const UnitRange batch{first, std::min(r.rays, first + rays.batch())};
    const std::vector<std::vector<Vec2>> origins = rays.origins(batch, share);
    for (std::size_t k = 0; k < rays.parts(); ++k)
      if (!origins[k].empty()) trace_vndf_part(rays, k, origins[k], r, counts);
    if (o.progress) o.progress(static_cast<double>(batch.end) / r.rays);
  }
  finish_vndf(r, o, share, std::move(counts));
}

}  // namespace microsim
