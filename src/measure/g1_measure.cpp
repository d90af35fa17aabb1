#include "microsim/measure/g1_measure.hpp"

#include "g1_estimator.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/measure/stats.hpp"
#include "microsim/surface/undersurface.hpp"
#include "microsim/trace/facet_plane.hpp"
#include "microsim/trace/ray_pipeline.hpp"

#include <sys/resource.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <memory>
#include <type_traits>

namespace microsim {

namespace {

constexpr std::uint64_t kChunk = 1 << 14;

// Runs `body(rep, j, tally)` for every replicate rep in `share` and ray j < n in parallel chunks.
// A chunk is one range of ray indices [j0, j1), taken index by index with ray j of every
// replicate in turn: rays j of all replicates start in the same stratum (or draw from the same
// stretch of the facet CDF), so consecutive rays meet the same few cells. On a large tile, where
// one replicate's consecutive rays are many cells apart, the BVH nodes and grid vertices a ray
// fetches are then reused by the next rays instead of being fetched again replicate after
// replicate (a chunk's part of the tile no longer fits in cache there). Each ray keeps its own
// random stream and the tallies are integer counts per replicate, so they are identical for any
// order, chunking and thread count.
// `chunk(j0, j1, first, active, t)` runs one chunk: rays [j0, j1) of replicates first ..
// first + active - 1 into the tallies t[0 .. active - 1].
// Not run_units (measure/replicates.hpp, the walks' and G2's driver), whose units lie inside one
// replicate and whose body sees one ray: the ray-index-major order across replicates is what keeps a large
// tile's cells in cache, and the chunk-level body is what lets Tracer::front_facets batch the
// queries of ray j of every replicate. The tallies are the same integer counts either way.
template <class Chunk>
std::vector<G1Tally> run_chunks(int R, std::uint64_t n, int nbins, TraceCounters& counters,
                                std::atomic<std::uint64_t>& done, UnitRange share, Chunk&& chunk) {
  const std::uint64_t first = std::min<std::uint64_t>(share.first, R);
  const std::uint64_t end = std::min<std::uint64_t>(share.end, R);
  const std::uint64_t active = end > first ? end - first : 0;
  const std::uint64_t span = std::max<std::uint64_t>(1, kChunk / std::max<std::uint64_t>(1, active));
  const std::uint64_t nc = active ? (n + span - 1) / span : 0;
  // Every chunk's tallies are kept until the merge: refused before the work when they would not
  // fit in memory (rather than ending in std::bad_alloc).
  require_memory(static_cast<double>(nc) * active * (sizeof(G1Tally) + 3.0 * nbins * sizeof(std::uint64_t)),
                 "{rays} " + std::to_string(static_cast<std::uint64_t>(R) * n) + " (tallies of " +
                     std::to_string(nc * active) + " chunks of " + std::to_string(nbins) + " normal bins)");
  std::vector<G1Tally> reps(R, G1Tally(nbins));
  if (nc == 0) return reps;
  // parts[c * active + q]: chunk c, replicate first + q.
  std::vector<G1Tally> parts(nc * active);
  tbb::parallel_for(std::uint64_t(0), nc, [&](std::uint64_t c) {
    const std::uint64_t j0 = c * span, j1 = std::min(n, j0 + span);
    G1Tally* t = &parts[c * active];
    for (std::uint64_t q = 0; q < active; ++q) t[q] = G1Tally(nbins);
    chunk(j0, j1, first, active, t);
    done += active * (j1 - j0);
  });
  for (std::uint64_t c = 0; c < nc; ++c)
    for (std::uint64_t q = 0; q < active; ++q) {
      const G1Tally& p = parts[c * active + q];
      add_fields(reps[first + q], p);
      counters += p.counters;
    }
  return reps;
}

template <class Body>
std::vector<G1Tally> run_replicates(int R, std::uint64_t n, int nbins, TraceCounters& counters,
                                    std::atomic<std::uint64_t>& done, UnitRange share, Body&& body) {
  return run_chunks(R, n, nbins, counters, done, share,
                    [&](std::uint64_t j0, std::uint64_t j1, std::uint64_t first,
                        std::uint64_t active, G1Tally* t) {
                      for (std::uint64_t j = j0; j < j1; ++j)
                        for (std::uint64_t q = 0; q < active; ++q)
                          body(static_cast<int>(first + q), j, t[q]);
                    });
}

// run_replicates for rays that are set up ahead of their tracing (trace/ray_pipeline.hpp):
// `prepare(rep, j)` returns a ray's state a few rays before `body(state, tally)` traces it, in
// the same order as run_replicates, so the tallies are the same.
template <class State, class Prepare, class Body>
std::vector<G1Tally> run_replicates_ahead(int R, std::uint64_t n, int nbins, TraceCounters& counters,
                                          std::atomic<std::uint64_t>& done, UnitRange share,
                                          Prepare&& prepare, Body&& body) {
  struct Slot {
    State state;
    std::uint64_t q;
  };
  // prepare(rep, j), or prepare(rep, j, tally) for one that keeps a search hint in the tally
  auto call_prepare = [&](int rep, std::uint64_t j, G1Tally& t) {
    if constexpr (std::is_invocable_v<Prepare&, int, std::uint64_t, G1Tally&>) return prepare(rep, j, t);
    else return prepare(rep, j);
  };
  return run_chunks(R, n, nbins, counters, done, share,
                    [&](std::uint64_t j0, std::uint64_t j1, std::uint64_t first,
                        std::uint64_t active, G1Tally* t) {
                      std::uint64_t j = j0, q = 0;  // the cursor of the next ray to prepare
                      run_ahead<Slot>(
                          (j1 - j0) * active,
                          [&] {
                            Slot s{call_prepare(static_cast<int>(first + q), j, t[q]), q};
                            if (++q == active) {
                              q = 0;
                              ++j;
                            }
                            return s;
                          },
                          [&](Slot& s) { body(s.state, t[s.q]); });
                    });
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// [GeomBSDF24, "Inherent Assumptions"]: the undersurface, explicitly. Traced on the mirrored,
// reversed sheet at mirror_z(v) (on `under` when given); results relabelled to v and to the
// normals -m_f.
G1Result measure_g1_undersurface(const Microsurface& s, const Vec3& v_in, const G1Options& o, const Tracer* under) {
  std::unique_ptr<Microsurface> own_surface;
  std::unique_ptr<Tracer> own_tracer;
  if (!under) {
    own_surface = std::make_unique<Microsurface>(undersurface(s));
    own_tracer = std::make_unique<Tracer>(*own_surface);
    under = own_tracer.get();
  }
  G1Result r = measure_g1(*under, mirror_z(v_in.normalized()), o, nullptr, nullptr);
  r.undersurface = true;
  r.v = v_in.normalized();
  r.theta = theta_of(r.v);
  r.phi = phi_of(r.v);
  for (auto& b : r.bins) b.mean_normal = mirror_z(b.mean_normal);  // M m' = -m
  return r;
}

// Estimator (b)'s facet weights, a block at a time: front-facing projected area A_f max(0, v.m_f).
struct FrontProjectedArea {
  const FacetTable& ft;
  Vec3 v;
  void operator()(std::size_t k0, std::size_t k1, double* w) const {
    ft.for_each_cross(k0, k1, [&](std::size_t k, const Vec3& c) { w[k - k0] = std::max(0.0, 0.5 * c.dot(v)); });
  }
};

// kAheadMinCells cells or more: a tile whose grid and table no longer fit in the caches.
bool beyond_the_caches(const Microsurface& s) { return static_cast<double>(s.nx()) * s.ny() >= kAheadMinCells; }

// One G1 measurement on a Tracer in progress: what both estimators' passes read.
struct G1Pass {
  const Tracer& tracer;
  const Scene& scene;  // of the tracer's surface (make_scene)
  const Microsurface& s;
  const FacetTable& ft;
  const G1Options& o;
  const G1Result& r;
  const ReplicatePlan& plan;
  UnitRange reps;
  std::uint64_t key;  // the direction's stream key
  TraceCounters& counters;
  std::atomic<std::uint64_t>& done;
  int R() const { return plan.replicates; }
  std::uint64_t n_rep() const { return plan.per_replicate(); }
  int nbins() const { return r.binning.size(); }
  std::size_t nf() const { return s.num_facets(); }
};

// The origins of the ray-casting rays: ray j of replicate rep, in its stratum `cell` of the
// window. Per replicate the generator's key (CounterRng::key), per ray index j its stratum
// (the same in every replicate): computed once, not per ray.
struct WindowOrigins {
  const RayWindow& w;
  const Strata& strata;
  std::vector<std::uint64_t> keys;
  Vec3 operator()(int rep, std::uint64_t j, const Strata::Cell& cell) const {
    CounterRng rng(CounterRng::Keyed{}, keys[rep], j);
    return window_point(w, strata.point(cell, rng));
  }
};

// G1RaycastRoute::GridAhead: the rays set up a few rays ahead, their grid vertices and table
// entry prefetched.
std::vector<G1Tally> raycast_grid_ahead(const G1Pass& p, const DownwardRays& down, const WindowOrigins& origin) {
  const Tracer& tracer = p.tracer;
  const FacetTable& ft = p.ft;
  const Strata& strata = p.plan.strata;
  const std::size_t nf = p.nf();
  return run_replicates_ahead<Vec3>(
      p.R(), p.n_rep(), p.nbins(), p.counters, p.done, p.reps,
      [&](int rep, std::uint64_t j) {
        const Vec3 org = origin(rep, j, strata.cell(j));
        ft.prefetch(tracer.prefetch_front(down, org));
        return org;
      },
      [&](const Vec3& org, G1Tally& t) {
        const std::size_t k = tracer.front_facet(down, org, t.counters);
        if (k >= nf) return;
        const int b = ft.bin(k);  // -1: a facet outside the binning's range (not tallied)
        if (b >= 0) ++t.hits[static_cast<std::size_t>(b)];
      });
}

// G1RaycastRoute::GridBatched: the same rays in the same order as run_replicates, ray j of every
// replicate in turn; the hits of a chunk counted in one flat array (replicate-major), read from the table's stored
// bins, and added to the tallies at the end of the chunk.
std::vector<G1Tally> raycast_grid_batched(const G1Pass& p, const DownwardRays& down, const WindowOrigins& origin) {
  const Tracer& tracer = p.tracer;
  const FacetTable& ft = p.ft;
  const Strata& strata = p.plan.strata;
  const std::uint16_t* bins16 = ft.bins16();
  const std::size_t nb = static_cast<std::size_t>(p.nbins()), nf = p.nf();
  return run_chunks(
      p.R(), p.n_rep(), p.nbins(), p.counters, p.done, p.reps,
      [&](std::uint64_t j0, std::uint64_t j1, std::uint64_t first, std::uint64_t active, G1Tally* t) {
        std::vector<std::uint64_t> hits(active * nb + 1);  // + 1: the facets without a bin
        const std::size_t nobin = active * nb;
        // Ray j of the replicates in blocks (Tracer::front_facets): origins, queries, hits.
        for (std::uint64_t j = j0; j < j1; ++j) {
          const Strata::Cell cell = strata.cell(j);
          tracer.front_facets(
              down, active, [&](std::size_t q) { return origin(static_cast<int>(first + q), j, cell); },
              [&](std::size_t q) -> TraceCounters& { return t[q].counters; },
              [&](std::size_t q, std::size_t k) {
                if (k >= nf) return;
                const int b = bins16 ? (bins16[k] == FacetTable::kNoBin16 ? -1 : bins16[k]) : ft.bin(k);
                ++hits[b < 0 ? nobin : q * nb + static_cast<std::size_t>(b)];
              });
        }
        for (std::uint64_t q = 0; q < active; ++q)
          for (std::size_t b = 0; b < nb; ++b) t[q].hits[b] += hits[q * nb + b];
      });
}

// (a) ray casting along -v: per replicate a stratified, Morton-ordered pass over the window
// (cast_g1_ray). A measured region: hits outside it (facet index >= num_facets()) are misses. A
// heightfield's bin is the table's (the same normal from the same heights, binned once); a
// mesh's table holds float normals, so its hits are binned from the exact one.
std::vector<G1Tally> raycast_g1(const G1Pass& p, const RayWindow& w) {
  WindowOrigins origin{w, p.plan.strata, std::vector<std::uint64_t>(p.R())};
  for (int q = 0; q < p.R(); ++q)
    origin.keys[q] = CounterRng::key(p.o.seed, ReplicatePlan::stream(0xA000 + p.key, q));
  const Vec3 v = p.r.v;
  const G1RaycastRoute route = g1_raycast_route(p.s, p.o);
  if (route != G1RaycastRoute::SceneFirstHit) {
    const DownwardRays down(p.tracer, v);
    return route == G1RaycastRoute::GridAhead ? raycast_grid_ahead(p, down, origin)
                                            : raycast_grid_batched(p, down, origin);
  }
  const bool table_bins = p.s.kind() == Microsurface::Kind::Heightfield;
  const auto bin_of = [&](const TraceHit& h, std::size_t f) {  // -1: out of range
    return table_bins ? p.ft.bin(f) : p.r.binning.bin_of(h.normal);
  };
  return run_replicates(p.R(), p.n_rep(), p.nbins(), p.counters, p.done, p.reps,
                        [&](int rep, std::uint64_t j, G1Tally& t) {
                          cast_g1_ray(p.scene, origin(rep, j, p.plan.strata.cell(j)), v, bin_of, t);
                        });
}

// (b) area sampling, per replicate strata along the CDF (facet order is spatially coherent).
std::vector<G1Tally> sample_g1(const G1Pass& p, const BlockFacetSampler& sampler, const FrontProjectedArea& weights) {
  const Microsurface& s = p.s;
  const FacetTable& ft = p.ft;
  const Vec3 v = p.r.v;
  const std::size_t nf = p.nf();
  const std::uint64_t n_rep = p.n_rep();
  const double total = p.r.front_projected;
  // After the draw of facet k (rng has drawn u): the sample point on k and its occlusion ray.
  auto sample_facet = [&](CounterRng& rng, std::size_t k, G1Tally& t) {
    const int b = ft.bin(k);
    if (ft.buried(k)) {  // pressed against a twin: never visible
      ++t.samples[b];
      return;
    }
    const Triangle f = facet_triangle(s, k);  // s.facet(k), without its modulos
    const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
    sample_g1_point(p.scene, f.point(r1 * (1 - r2), r1 * r2), v, SourcePlane::of(f), b, t);
  };
  // g1_draws_ahead: the block of facets found, its heights, bins and the grid leaves of its cells
  // prefetched (FacetTable::prefetch_range, Tracer::prefetch_cells).
  struct Draw {
    CounterRng rng{0, 0, 0};
    double u = 0;
    std::size_t block = 0;
  };
  const std::uint64_t stream = 0xB000 + p.key;
  if (!g1_draws_ahead(s, p.o))
    return run_replicates(p.R(), n_rep, p.nbins(), p.counters, p.done, p.reps, [&](int rep, std::uint64_t j, G1Tally& t) {
      CounterRng rng(p.o.seed, ReplicatePlan::stream(stream, rep), j);
      double u = (static_cast<double>(j) + rng.uniform()) / n_rep * total;
      sample_facet(rng, sampler.draw(u, BlockFacetSampler::Blocks{}, weights, &t.draw_hint), t);
    });
  constexpr std::size_t kB = BlockFacetSampler::kBlock;
  return run_replicates_ahead<Draw>(
      p.R(), n_rep, p.nbins(), p.counters, p.done, p.reps,
      [&](int rep, std::uint64_t j, G1Tally& t) {
        CounterRng rng(p.o.seed, ReplicatePlan::stream(stream, rep), j);
        const double u = (static_cast<double>(j) + rng.uniform()) / n_rep * total;
        const std::size_t b = sampler.block(u, &t.draw_hint);
        const std::size_t k0 = b * kB, k1 = std::min(nf, k0 + kB);
        ft.prefetch_range(k0, k1);
        const long c0 = static_cast<long>(k0 / 2), c1 = static_cast<long>((k1 - 1) / 2);
        const long j0 = c0 / s.nx();
        // a block's cells in one row (else the row the block starts in)
        p.tracer.prefetch_cells(c0 - j0 * s.nx(), c1 / s.nx() == j0 ? c1 - j0 * s.nx() : s.nx() - 1, j0);
        return Draw{rng, u, b};
      },
      [&](Draw& d, G1Tally& t) { sample_facet(d.rng, sampler.draw_in(d.block, d.u, weights), t); });
}

}  // namespace

G1RaycastRoute g1_raycast_route(const Microsurface& s, const G1Options& o) {
  if (s.kind() != Microsurface::Kind::Heightfield || !o.grid_fast_paths) return G1RaycastRoute::SceneFirstHit;
  return beyond_the_caches(s) ? G1RaycastRoute::GridAhead : G1RaycastRoute::GridBatched;
}

bool g1_draws_ahead(const Microsurface& s, const G1Options& o) {
  return o.grid_fast_paths && s.kind() == Microsurface::Kind::Heightfield && beyond_the_caches(s) &&
         s.macro().periodic && !s.macro().region;
}

G1Result measure_g1(const Tracer& tracer, const Vec3& v_in, const G1Options& o,
                    const FacetTable* table, const Tracer* under) {
  const Microsurface& s = tracer.surface();
  if (!(std::abs(v_in.z()) > 1e-12 * v_in.norm()))
    throw ParameterError("{theta} must not be 90 degrees: G1 is undefined at v.n = 0");
  if (v_in.z() < 0) {
    if (s.kind() == Microsurface::Kind::Heightfield)
      throw ParameterError("{theta} must be in [0, 90) degrees for a heightfield (theta in (90, 180], "
                           "the undersurface, is measured on meshes only)");
    return measure_g1_undersurface(s, v_in, o, under);
  }
  if (o.rays == 0) throw ParameterError("{rays} must be positive");
  auto t0 = std::chrono::steady_clock::now();
  G1Result r = start_g1(v_in, o, s.macro().area);

  // Exact facet sums per normal bin, and the CDF of projected area for estimator (b).
  auto t_facets = std::chrono::steady_clock::now();
  FacetTable own;
  const FacetTable& ft = facet_table_for(s, r.binning, table, own);
  sum_g1_facets(r, s.num_facets(), r.v.dot(s.macro().normal) * s.macro().area,
                [&](std::size_t k, Vec3& m, double& a) {
                  ft.normal_area(k, m, a);
                  return ft.bin(k);
                });
  const FrontProjectedArea weights{ft, r.v};
  const BlockFacetSampler sampler(s.num_facets(), BlockFacetSampler::Blocks{}, weights);
  r.front_projected = sampler.total();
  if (!(r.front_projected > 0)) throw RuntimeFailure("no facet faces the direction");
  r.facet_seconds = seconds_since(t_facets);

  const RayWindow w = make_ray_window(tracer, r.v);
  r.window_area_perp = w.area_perp;
  const ReplicatePlan plan(o.rays, o.replicates);
  r.replicates = plan.replicates;
  r.raycast_rays = plan.total();
  r.sample_rays = plan.total();
  const UnitRange reps = share_of(o.split, static_cast<std::uint64_t>(plan.replicates));
  const std::uint64_t total_work = 2 * plan.per_replicate() * std::max<std::uint64_t>(1, reps.size());
  std::atomic<std::uint64_t> done{0};
  TraceCounters counters;
  auto report = [&] {
    if (o.progress) o.progress(static_cast<double>(done.load()) / total_work);
  };
  const std::unique_ptr<Scene> scene = make_scene(tracer);
  const G1Pass pass{tracer, *scene, s, ft, o, r, plan, reps, direction_stream_key(r.v), counters, done};

  auto t_raycast = std::chrono::steady_clock::now();
  const double cpu_raycast = process_cpu_seconds();
  std::vector<G1Tally> ray_reps = raycast_g1(pass, w);
  report();
  r.raycast_seconds = seconds_since(t_raycast);
  r.raycast_cpu_seconds = process_cpu_seconds() - cpu_raycast;

  auto t_sample = std::chrono::steady_clock::now();
  const double cpu_sample = process_cpu_seconds();
  std::vector<G1Tally> sample_reps = sample_g1(pass, sampler, weights);
  report();
  r.sample_cpu_seconds = process_cpu_seconds() - cpu_sample;
  // (a) counts only hits and (b) only samples: their sum is one tally holding both.
  for (std::size_t q = 0; q < ray_reps.size(); ++q) add_fields(ray_reps[q], sample_reps[q]);
  finish_g1(r, ray_reps, counters, o.split, reps, {plan.per_replicate(), plan.per_replicate()});
  r.sample_seconds = seconds_since(t_sample);
  r.seconds = seconds_since(t0);
  return r;
}

}  // namespace microsim
