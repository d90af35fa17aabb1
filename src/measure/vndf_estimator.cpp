#include "vndf_estimator.hpp"

#include "microsim/measure/sampling.hpp"
#include "microsim/measure/shards.hpp"
#include "part_passes.hpp"

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
constexpr double kTwo53 = 9007199254740992.0;  // CounterRng::uniform's 53 bits
}  // namespace

VndfOrigin VndfOrigin::of(double a, double b) {
  const auto ka = static_cast<std::uint64_t>(a * kTwo53), kb = static_cast<std::uint64_t>(b * kTwo53);
  return {morton_encode(static_cast<std::uint32_t>(ka >> 32), static_cast<std::uint32_t>(kb >> 32)),
          ((ka & 0xFFFFFFFFull) << 32) | (kb & 0xFFFFFFFFull)};
}

Vec2 VndfOrigin::ab() const {
  std::uint32_t ha, hb;
  morton_decode(key, ha, hb);
  const std::uint64_t ka = (static_cast<std::uint64_t>(ha) << 32) | (rest >> 32);
  const std::uint64_t kb = (static_cast<std::uint64_t>(hb) << 32) | (rest & 0xFFFFFFFFull);
  return Vec2(static_cast<double>(ka) / kTwo53, static_cast<double>(kb) / kTwo53);
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

constexpr std::uint64_t kChunk = 1 << 14;  // rays of one work unit
constexpr std::size_t kUnitsPerPass = 64;  // work units of a pass (the scenes of its parts live while it runs)

// A work unit: the rays [first, end) of part k's origins.
struct VndfUnit {
  std::size_t part;
  UnitRange rays;
};

// One batch's rays, from their origins per part, added to counts (nbins + 1: the last one
// outside every bin) and r.counters.
void trace_vndf_batch(const VndfRays& rays, const std::vector<std::vector<VndfOrigin>>& origins, VndfResult& r,
                      std::vector<std::uint64_t>& counts) {
  std::vector<VndfUnit> units;
  for (std::size_t k = 0; k < origins.size(); ++k)
    for (std::uint64_t j = 0; j < origins[k].size(); j += kChunk)
      units.push_back({k, {j, std::min<std::uint64_t>(origins[k].size(), j + kChunk)}});
  const int nbins = r.binning.size();
  std::vector<std::vector<std::uint64_t>> c(units.size());
  std::vector<TraceCounters> tc(units.size());
  run_part_passes(
      units.size(), kUnitsPerPass, [&](std::size_t u) { return units[u].part; },
      [&](std::size_t k) { return rays.scene(k); },
      [&](std::size_t u, const Scene& scene) {
        const std::size_t k = units[u].part;
        const Vec3 v = rays.to_local(k, r.v);
        const RayWindow w = scene.ray_window(v);
        c[u].assign(static_cast<std::size_t>(nbins) + 1, 0);
        for (std::uint64_t j = units[u].rays.first; j < units[u].rays.end; ++j) {
          const Vec2 ab = origins[k][j].ab();
          const TraceHit h = scene.intersect(w.origin0 + ab.x() * w.e1 + ab.y() * w.e2, -v, nullptr, tc[u]);
          if (scene.front_facet(h) == Scene::kNoFacet) continue;  // a back face, or outside the region
          const int b = rays.bin(k, scene, h);
          ++c[u][b >= 0 ? b : nbins];
        }
      },
      [](std::size_t) {});
  for (std::size_t u = 0; u < units.size(); ++u) {
    for (int b = 0; b <= nbins; ++b) counts[b] += c[u][b];
    r.counters += tc[u];
  }
}

}  // namespace

void trace_vndf_rays(const VndfRays& rays, VndfResult& r, const VndfOptions& o) {
  const UnitRange share = share_of(o.split, r.rays);
  std::vector<std::uint64_t> counts(static_cast<std::size_t>(r.binning.size()) + 1, 0);
  for (std::uint64_t first = 0; first < r.rays; first += rays.batch()) {
    const UnitRange batch{first, std::min(r.rays, first + rays.batch())};
    const std::vector<std::vector<VndfOrigin>> origins = rays.origins(batch, share);
    trace_vndf_batch(rays, origins, r, counts);
    if (o.progress) o.progress(static_cast<double>(batch.end) / r.rays);
  }
  finish_vndf(r, o, share, std::move(counts));
}

}  // namespace microsim
