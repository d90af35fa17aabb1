#include "microsim/measure/g1_measure.hpp"
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

struct Tally {
  std::vector<std::uint64_t> hits, samples, visible;  // per normal bin
  TraceCounters counters;     // summed into the call's total, not per replicate
  std::size_t draw_hint = 0;  // area sampling: block of the previous draw (a search start)
  explicit Tally(int nbins = 0) : hits(nbins), samples(nbins), visible(nbins) {}
  // The per-replicate counts (tally_fields.hpp): summed over chunks and exchanged.
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f("hits", &Tally::hits);
    f("samples", &Tally::samples);
    f("visible", &Tally::visible);
  }
};

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
// Not run_replicate_chunks (measure/replicates.hpp), whose chunks lie inside one replicate and
// whose body sees one ray: the ray-index-major order across replicates is what keeps a large
// tile's cells in cache, and the chunk-level body is what lets Tracer::front_facets batch the
// queries of ray j of every replicate. The tallies are the same integer counts either way.
template <class Chunk>
std::vector<Tally> run_chunks(int R, std::uint64_t n, int nbins, TraceCounters& counters,
                              std::atomic<std::uint64_t>& done, UnitRange share, Chunk&& chunk) {
  const std::uint64_t first = std::min<std::uint64_t>(share.first, R);
  const std::uint64_t end = std::min<std::uint64_t>(share.end, R);
  const std::uint64_t active = end > first ? end - first : 0;
  const std::uint64_t span = std::max<std::uint64_t>(1, kChunk / std::max<std::uint64_t>(1, active));
  const std::uint64_t nc = active ? (n + span - 1) / span : 0;
  // Every chunk's tallies are kept until the merge: refused before the work when they would not
  // fit in memory (rather than ending in std::bad_alloc).
  require_memory(static_cast<double>(nc) * active * (sizeof(Tally) + 3.0 * nbins * sizeof(std::uint64_t)),
                 "{rays} " + std::to_string(static_cast<std::uint64_t>(R) * n) + " (tallies of " +
                     std::to_string(nc * active) + " chunks of " + std::to_string(nbins) + " normal bins)");
  std::vector<Tally> reps(R, Tally(nbins));
  if (nc == 0) return reps;
  // parts[c * active + q]: chunk c, replicate first + q.
  std::vector<Tally> parts(nc * active);
  tbb::parallel_for(std::uint64_t(0), nc, [&](std::uint64_t c) {
    const std::uint64_t j0 = c * span, j1 = std::min(n, j0 + span);
    Tally* t = &parts[c * active];
    for (std::uint64_t q = 0; q < active; ++q) t[q] = Tally(nbins);
    chunk(j0, j1, first, active, t);
    done += active * (j1 - j0);
  });
  for (std::uint64_t c = 0; c < nc; ++c)
    for (std::uint64_t q = 0; q < active; ++q) {
      const Tally& p = parts[c * active + q];
      add_fields(reps[first + q], p);
      counters += p.counters;
    }
  return reps;
}

template <class Body>
std::vector<Tally> run_replicates(int R, std::uint64_t n, int nbins, TraceCounters& counters,
                                  std::atomic<std::uint64_t>& done, UnitRange share, Body&& body) {
  return run_chunks(R, n, nbins, counters, done, share,
                    [&](std::uint64_t j0, std::uint64_t j1, std::uint64_t first,
                        std::uint64_t active, Tally* t) {
                      for (std::uint64_t j = j0; j < j1; ++j)
                        for (std::uint64_t q = 0; q < active; ++q)
                          body(static_cast<int>(first + q), j, t[q]);
                    });
}

// run_replicates for rays that are set up ahead of their tracing (trace/ray_pipeline.hpp):
// `prepare(rep, j)` returns a ray's state a few rays before `body(state, tally)` traces it, in
// the same order as run_replicates, so the tallies are the same.
template <class State, class Prepare, class Body>
std::vector<Tally> run_replicates_ahead(int R, std::uint64_t n, int nbins, TraceCounters& counters,
                                        std::atomic<std::uint64_t>& done, UnitRange share,
                                        Prepare&& prepare, Body&& body) {
  struct Slot {
    State state;
    std::uint64_t q;
  };
  // prepare(rep, j), or prepare(rep, j, tally) for one that keeps a search hint in the tally
  auto call_prepare = [&](int rep, std::uint64_t j, Tally& t) {
    if constexpr (std::is_invocable_v<Prepare&, int, std::uint64_t, Tally&>) return prepare(rep, j, t);
    else return prepare(rep, j);
  };
  return run_chunks(R, n, nbins, counters, done, share,
                    [&](std::uint64_t j0, std::uint64_t j1, std::uint64_t first,
                        std::uint64_t active, Tally* t) {
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

double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double per_replicate(std::uint64_t total, int R) { return static_cast<double>(total) / R; }

// Completes the replicates' tallies from the other processes (measure/shards.hpp): per
// replicate the ray-casting hits and the area samples and visible samples of every bin. The
// ray-casting pass counts only hits and the area-sampling pass only samples, so their sum is one
// row holding both.
// Counts received from other processes (or read back from a merge's parts) must be possible:
// per replicate at most n rays hit or are sampled, and no bin has more visible samples than
// samples. UsageError naming the field otherwise (a part edited by hand, or damaged).
void require_possible_g1_counts(const Tally& t, std::size_t q, std::uint64_t n) {
  std::uint64_t hits = 0, samples = 0;
  for (std::size_t b = 0; b < t.samples.size(); ++b) {
    if (t.visible[b] > t.samples[b])
      throw UsageError("g1 tallies of replicate " + std::to_string(q) + ": visible[" + std::to_string(b) + "] = " +
                       std::to_string(t.visible[b]) + " exceeds samples[" + std::to_string(b) + "] = " +
                       std::to_string(t.samples[b]) + " (a damaged or edited part)");
    hits += t.hits[b];
    samples += t.samples[b];
    if (hits > n || samples > n)
      throw UsageError("g1 tallies of replicate " + std::to_string(q) + ": " + (hits > n ? "hits" : "samples") +
                       " exceed its " + std::to_string(n) + " rays (a damaged or edited part)");
  }
}

void exchange_g1(TallySplit& split, UnitRange reps, std::vector<Tally>& ray_reps,
                 std::vector<Tally>& sample_reps, TraceCounters& counters, int nbins, std::uint64_t n) {
  const std::size_t R = ray_reps.size();
  Tallies t("g1", R, reps, field_sizes(Tally(nbins)).counts, 0, kCounterValues, 0);
  for (std::size_t q = 0; q < R; ++q) {
    Tally both = ray_reps[q];
    add_fields(both, sample_reps[q]);
    pack_fields(both, t.count_row(q));
  }
  put_counters(counters, t.tail_counts.data());
  split.exchange(t);
  for (std::size_t q = 0; q < R; ++q) {
    unpack_fields(ray_reps[q], t.count_row(q));
    require_possible_g1_counts(ray_reps[q], q, n);
    sample_reps[q] = ray_reps[q];
  }
  counters = get_counters(t.tail_counts.data());
}

}  // namespace

Estimate G1Result::g1_area_sampling() const {
  return replicate_mean(sample_visible_r, 1.0 / per_replicate(sample_rays, replicates));
}

Estimate G1Result::g1_raycast() const {
  const double k = front_projected > 0 ? window_area_perp / front_projected : 0;
  return replicate_mean(raycast_hits_r, k / per_replicate(raycast_rays, replicates));
}

Estimate G1Result::visible_area_ratio() const {
  const double denom = std::abs(v.z()) * total_area_macro();  // |v.n| A (undersurface: v.n < 0)
  const double k = denom > 0 ? window_area_perp / denom : 0;
  return replicate_mean(raycast_hits_r, k / per_replicate(raycast_rays, replicates));
}

Estimate G1Result::bin_g1_area_sampling(int b) const {
  // visible / samples of the bin: a ratio whose denominator varies between replicates.
  return replicate_ratio(bins[b].visible_r, bins[b].samples_r);
}

Estimate G1Result::bin_g1_raycast(int b) const {
  const double k = bins[b].front_projected > 0 ? window_area_perp / bins[b].front_projected : 0;
  Estimate e = replicate_mean(bins[b].raycast_hits_r, k / per_replicate(raycast_rays, replicates));
  e.n = bins[b].raycast_hits;
  return e;
}

// Per-replicate totals and per-bin counts from the replicates' tallies.
void set_g1_counts(G1Result& r, const std::vector<Tally>& ray_reps, const std::vector<Tally>& sample_reps) {
  const int R = r.replicates, nbins = r.binning.size();
  r.raycast_hits_r.assign(R, 0);
  r.sample_visible_r.assign(R, 0);
  r.raycast_hits = r.sample_visible = 0;
  for (int b = 0; b < nbins; ++b) {
    G1NormalBin& nb = r.bins[b];
    nb.raycast_hits_r.assign(R, 0);
    nb.samples_r.assign(R, 0);
    nb.visible_r.assign(R, 0);
    nb.raycast_hits = nb.samples = nb.visible = 0;
    for (int q = 0; q < R; ++q) {
      nb.raycast_hits_r[q] = ray_reps[q].hits[b];
      nb.samples_r[q] = sample_reps[q].samples[b];
      nb.visible_r[q] = sample_reps[q].visible[b];
      nb.raycast_hits += nb.raycast_hits_r[q];
      nb.samples += nb.samples_r[q];
      nb.visible += nb.visible_r[q];
      r.raycast_hits_r[q] += nb.raycast_hits_r[q];
      r.sample_visible_r[q] += nb.visible_r[q];
    }
    r.raycast_hits += nb.raycast_hits;
    r.sample_visible += nb.visible;
  }
}

namespace {

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

// The exact facet sums of r.bins at r.v (area, front projected area, mean normal, V-cavity
// weighted area), r.total_area and r.lambda_numeric.
void sum_facets_per_bin(G1Result& r, const FacetTable& ft, const Microsurface& s) {
  const Vec3 v = r.v;
  const int nbins = static_cast<int>(r.bins.size());
  // Per bin: area, front projected area, projected-area-weighted normal (3), V-cavity-weighted
  // front projected area; then back area.
  using Sums = std::vector<double>;
  const std::size_t width = 6 * static_cast<std::size_t>(nbins) + 1;
  Sums sums = sum_over_facets(s.num_facets(), width, [&](std::size_t k, double* acc) {
    Vec3 m;
    double a;
    ft.normal_area(k, m, a);
    const double proj = a * m.dot(v);  // A_f (v.m_f)
    const double front = std::max(0.0, proj);
    double* bin = acc + 6 * static_cast<std::size_t>(ft.bin(k));
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
  // Lambda(v) = sum_f A_f max(0, -v.m_f) / ((v.n) A)   [Heitz14, App. A]
  r.lambda_numeric = sums[width - 1] / (v.dot(s.macro().normal) * s.macro().area);
}

}  // namespace

DirectionBinning g1_normal_binning(const G1Options& o) {
  return DirectionBinning(o.normal_theta_bins, o.normal_phi_bins, kPi);
}

namespace {

// Estimator (b)'s facet weights, a block at a time: front-facing projected area A_f max(0, v.m_f).
struct FrontProjectedArea {
  const FacetTable& ft;
  Vec3 v;
  void operator()(std::size_t k0, std::size_t k1, double* w) const {
    ft.for_each_cross(k0, k1, [&](std::size_t k, const Vec3& c) { w[k - k0] = std::max(0.0, 0.5 * c.dot(v)); });
  }
};

// One G1 measurement on a Tracer in progress: what both estimators' passes read.
struct G1Pass {
  const Tracer& tracer;
  const Microsurface& s;
  const FacetTable& ft;
  const G1Options& o;
  const G1Result& r;
  const ReplicatePlan& plan;
  UnitRange reps;
  std::uint64_t key;  // the direction's stream key
  bool heightfield, ahead;
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
    const Vec2 ab = strata.point(cell, rng);
    return Vec3(w.origin0 + ab.x() * w.e1 + ab.y() * w.e2);
  }
};

// A large heightfield's rays are set up a few rays ahead, their grid vertices and table
// entry prefetched (Tracer::prefetch_front): on tiles larger than the caches the memory reads
// of consecutive rays then overlap.
std::vector<Tally> raycast_grid_ahead(const G1Pass& p, const DownwardRays& down, const WindowOrigins& origin) {
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
      [&](const Vec3& org, Tally& t) {
        const std::size_t k = tracer.front_facet(down, org, t.counters);
        if (k >= nf) return;
        const int b = ft.bin(k);  // -1: a facet outside the binning's range (not tallied)
        if (b >= 0) ++t.hits[static_cast<std::size_t>(b)];
      });
}

// The same rays in the same order as run_replicates, ray j of every replicate in turn; the
// hits of a chunk counted in one flat array (replicate-major), read from the table's stored
// bins, and added to the tallies at the end of the chunk.
std::vector<Tally> raycast_grid_batched(const G1Pass& p, const DownwardRays& down, const WindowOrigins& origin) {
  const Tracer& tracer = p.tracer;
  const FacetTable& ft = p.ft;
  const Strata& strata = p.plan.strata;
  const std::uint16_t* bins16 = ft.bins16();
  const std::size_t nb = static_cast<std::size_t>(p.nbins()), nf = p.nf();
  return run_chunks(
      p.R(), p.n_rep(), p.nbins(), p.counters, p.done, p.reps,
      [&](std::uint64_t j0, std::uint64_t j1, std::uint64_t first, std::uint64_t active, Tally* t) {
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

// (a) ray casting along -v: per replicate a stratified, Morton-ordered pass over the window.
// Hits on back faces (counted in counters) are left out of the visible area: a ray that meets
// a facet from behind crossed the surface through a rounding gap. A measured region: hits
// outside it (facet index >= num_facets()) are misses. A heightfield's bin is the table's (the
// same normal from the same heights, binned once), its hit decoded by the lean primary-ray path
// (Tracer::front_facet); a mesh's table holds float normals, so its hits (traced on its Scene)
// are binned from the exact one.
std::vector<Tally> raycast_g1(const G1Pass& p, const RayWindow& w) {
  WindowOrigins origin{w, p.plan.strata, std::vector<std::uint64_t>(p.R())};
  for (int q = 0; q < p.R(); ++q)
    origin.keys[q] = CounterRng::key(p.o.seed, ReplicatePlan::stream(0xA000 + p.key, q));
  const Vec3 v = p.r.v;
  const DownwardRays down(p.tracer, v);
  if (p.heightfield && p.ahead) return raycast_grid_ahead(p, down, origin);
  if (p.heightfield) return raycast_grid_batched(p, down, origin);
  const std::unique_ptr<Scene> scene = make_scene(p.tracer);
  return run_replicates(p.R(), p.n_rep(), p.nbins(), p.counters, p.done, p.reps,
                        [&](int rep, std::uint64_t j, Tally& t) {
                          const TraceHit h = scene->intersect(
                              origin(rep, j, p.plan.strata.cell(j)), -v, nullptr, t.counters);
                          if (scene->front_facet(h) == Scene::kNoFacet) return;
                          const int b = p.r.binning.bin_of(h.normal);  // -1: out of range
                          if (b >= 0) ++t.hits[static_cast<std::size_t>(b)];
                        });
}

// (b) area sampling, per replicate strata along the CDF (facet order is spatially coherent).
std::vector<Tally> sample_g1(const G1Pass& p, const BlockFacetSampler& sampler, const FrontProjectedArea& weights) {
  const Microsurface& s = p.s;
  const Tracer& tracer = p.tracer;
  const FacetTable& ft = p.ft;
  const Vec3 v = p.r.v;
  const std::size_t nf = p.nf();
  const std::uint64_t n_rep = p.n_rep();
  const double total = p.r.front_projected;
  // After the draw of facet k (rng has drawn u): the sample point on k and its occlusion ray.
  auto sample_facet = [&](CounterRng& rng, std::size_t k, Tally& t) {
    const int b = ft.bin(k);
    if (ft.buried(k)) {  // pressed against a twin: never visible
      ++t.samples[b];
      return;
    }
    const Triangle f = facet_triangle(s, k);  // s.facet(k), without its modulos
    double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
    Vec3 x = f.point(r1 * (1 - r2), r1 * r2);
    SourcePlane plane = SourcePlane::of(f);
    ++t.samples[b];
    if (!tracer.occluded(x, v, &plane, t.counters)) ++t.visible[b];
  };
  // A large periodic heightfield's draws are set up a few rays ahead (as (a)'s rays): the block
  // of facets found, its heights, bins and the grid leaves of its cells prefetched
  // (FacetTable::prefetch_range, Tracer::prefetch_cells); the same draws in the same order.
  struct Draw {
    CounterRng rng{0, 0, 0};
    double u = 0;
    std::size_t block = 0;
  };
  const std::uint64_t stream = 0xB000 + p.key;
  if (!(p.heightfield && p.ahead && s.macro().periodic && !s.macro().region))
    return run_replicates(p.R(), n_rep, p.nbins(), p.counters, p.done, p.reps, [&](int rep, std::uint64_t j, Tally& t) {
      CounterRng rng(p.o.seed, ReplicatePlan::stream(stream, rep), j);
      double u = (static_cast<double>(j) + rng.uniform()) / n_rep * total;
      sample_facet(rng, sampler.draw(u, BlockFacetSampler::Blocks{}, weights, &t.draw_hint), t);
    });
  constexpr std::size_t kB = BlockFacetSampler::kBlock;
  return run_replicates_ahead<Draw>(
      p.R(), n_rep, p.nbins(), p.counters, p.done, p.reps,
      [&](int rep, std::uint64_t j, Tally& t) {
        CounterRng rng(p.o.seed, ReplicatePlan::stream(stream, rep), j);
        const double u = (static_cast<double>(j) + rng.uniform()) / n_rep * total;
        const std::size_t b = sampler.block(u, &t.draw_hint);
        const std::size_t k0 = b * kB, k1 = std::min(nf, k0 + kB);
        ft.prefetch_range(k0, k1);
        const long c0 = static_cast<long>(k0 / 2), c1 = static_cast<long>((k1 - 1) / 2);
        const long j0 = c0 / s.nx();
        // a block's cells in one row (else the row the block starts in)
        tracer.prefetch_cells(c0 - j0 * s.nx(), c1 / s.nx() == j0 ? c1 - j0 * s.nx() : s.nx() - 1, j0);
        return Draw{rng, u, b};
      },
      [&](Draw& d, Tally& t) { sample_facet(d.rng, sampler.draw_in(d.block, d.u, weights), t); });
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

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
  G1Result r;
  r.v = v_in.normalized();
  r.theta = theta_of(r.v);
  r.phi = phi_of(r.v);
  r.macro_area = s.macro().area;
  r.binning = g1_normal_binning(o);
  const int nbins = r.binning.size();
  r.bins.assign(nbins, G1NormalBin{});

  // Exact facet sums per normal bin, and the CDF of projected area for estimator (b).
  auto t_facets = std::chrono::steady_clock::now();
  FacetTable own;
  const FacetTable& ft = facet_table_for(s, r.binning, table, own);
  sum_facets_per_bin(r, ft, s);
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
  const std::uint64_t key = static_cast<std::uint64_t>(r.theta * 1e6) * 7919 +
                            static_cast<std::uint64_t>(r.phi * 1e6);
  const G1Pass pass{tracer, s, ft, o, r, plan, reps, key, s.kind() == Microsurface::Kind::Heightfield,
                    static_cast<double>(s.nx()) * s.ny() >= kAheadMinCells, counters, done};

  auto t_raycast = std::chrono::steady_clock::now();
  const double cpu_raycast = process_cpu_seconds();
  std::vector<Tally> ray_reps = raycast_g1(pass, w);
  report();
  r.raycast_seconds = seconds_since(t_raycast);
  r.raycast_cpu_seconds = process_cpu_seconds() - cpu_raycast;

  auto t_sample = std::chrono::steady_clock::now();
  const double cpu_sample = process_cpu_seconds();
  std::vector<Tally> sample_reps = sample_g1(pass, sampler, weights);
  report();
  r.sample_cpu_seconds = process_cpu_seconds() - cpu_sample;
  if (o.split) exchange_g1(*o.split, reps, ray_reps, sample_reps, counters, nbins, plan.per_replicate());
  set_g1_counts(r, ray_reps, sample_reps);
  r.counters = counters;
  r.sample_seconds = seconds_since(t_sample);
  r.seconds = seconds_since(t0);
  return r;
}

Table g1_table() {
  Table t;
  t.error = ErrorKind::Replicates;
  const ErrorKind R = ErrorKind::Replicates, N = ErrorKind::None;
  t.spec.columns = {
      {"theta_deg", Merge::Copy, N, "deg", "view zenith angle, from the macrosurface normal (> 90: the undersurface of a mesh)"},
      {"phi_deg", Merge::Copy, N, "deg", "view azimuth"},
      {"surfaces", Merge::Count, N, "count", "number of surfaces K averaged (ensembles only), with t_dof = K - 1 after it"},
      {"replicates", Merge::Copy, N, "count", "independent randomized replicates the rays are split into"},
      {"g1", Merge::Measured, R, "1",
       "G1 by area sampling: fraction of points, drawn by projected area A_f max(0, v.m_f), unoccluded toward v"},
      {"g1_raycast", Merge::Measured, R, "1",
       "G1 by ray casting: visible projected area of the first hits along -v / sum_f A_f max(0, v.m_f)"},
      {"visible_area_ratio", Merge::Measured, R, "1",
       "visible projected area / ((v.n) A), A the macrosurface area; 1 at theta = 0 for a valid periodic surface"},
      {"smith_numeric", Merge::Spread, N, "1",
       "Smith G1 = 1 / (1 + Lambda) with Lambda from the surface's own facets, sum_f A_f max(0, -v.m_f) / ((v.n) A)"},
      {"smith_nominal", Merge::Copy, N, "1", "Smith G1 of the generator's nominal NDF (null without one)"}};
  t.spec.comparisons = {
      {"g1", "smith_nominal", ModelKind::Nominal, "z_nominal", "rel_dev_nominal", "p_nominal"},
      {"g1", "smith_numeric", ModelKind::Facets, "z_numeric", "", ""}};
  t.spec.bin_columns = {
      {"theta_m_range_deg", Merge::Key, N, "deg", "zenith range [lo, hi] of the normal bin"},
      {"phi_m_range_deg", Merge::Key, N, "deg", "azimuth range [lo, hi] of the normal bin"},
      {"m", Merge::Direction, N, "1", "mean unit normal [x, y, z] of the bin's facets"},
      {"area_fraction", Merge::Mean, N, "1", "the bin's share of the surface's facet area"},
      {"g1", Merge::Spread, R, "1", "G1 of the bin's facets by area sampling (0 where they all face away from v)"},
      {"g1_raycast", Merge::Spread, R, "1", "G1 of the bin's facets by ray casting"}};
  t.spec.row_fields = {
      {"visible_projected_area", Merge::Copy, R, "length^2", "visible projected area, perpendicular to v, in the surface's units"},
      {"macro_projected_area", Merge::Copy, N, "length^2", "|v.n| A"},
      {"eq_2b", Merge::Copy, R, "1",
       "theta = 0 only: visible_area_ratio, which is the integral of (n.m) G1(n, m) D(m) over the sphere (1 for a "
       "valid periodic surface)"},
      {"lambda_numeric", Merge::Copy, N, "1", "Smith Lambda(v) from the surface's own facets"},
      {"rays", Merge::Copy, N, "count", "rays cast by the ray-casting estimator"},
      {"area_samples", Merge::Copy, N, "count", "points drawn by the area-sampling estimator"},
      {"border_crossings", Merge::Copy, N, "count", "periodic wrap-arounds of the rays"},
      {"bins_dof", Merge::Copy, N, "count", "normal bins with area-sampling points (facing v)"},
      {"bins_chi2_smith", Merge::Copy, N, "1",
       "sum over those bins of ((g1 - smith_numeric) / error)^2, the error at least the resolution of the bin's points"},
      {"bins_chi2_vcavity", Merge::Copy, N, "1", "the same against the bins' vcavity_numeric"},
      {"bins_mad_smith", Merge::Copy, N, "1",
       "mean |g1 - smith_numeric| over the bins, weighted by their projected area facing v"},
      {"bins_mad_vcavity", Merge::Copy, N, "1", "the same against vcavity_numeric"},
      {"bins_mad_noise", Merge::Copy, N, "1", "the same mean of the bins' errors times sqrt(2 / pi): what noise alone gives"},
      {"max_abs_z_estimators", Merge::Copy, N, "1", "largest |z_estimators| over the bins"},
      {"undersurface", Merge::Copy, N, "", "true on rows of the undersurface of a mesh (theta > 90)"},
      {"g1_reverse_v", Merge::Copy, R, "1", "undersurface rows: the surface's own G1 at -v, an approximation of g1"},
      {"g1_reflect_v", Merge::Copy, R, "1",
       "undersurface rows: the surface's own G1 at v reflected across the macrosurface, the other approximation"},
      {"z_reverse_v", Merge::Copy, N, "1", "(g1_reverse_v - g1) / their combined error (rel_dev_reverse_v: / g1)"},
      {"z_reflect_v", Merge::Copy, N, "1", "(g1_reflect_v - g1) / their combined error (rel_dev_reflect_v: / g1)"}};
  for (const Column& c : tracer_count_fields(true)) t.spec.row_fields.push_back(c);
  t.spec.bin_fields = {
      {"z_estimators", Merge::Copy, N, "1", "(g1 - g1_raycast) / their combined error"},
      {"smith_numeric", Merge::Copy, N, "1", "the row's smith_numeric (Smith G1 does not depend on m)"},
      {"vcavity_numeric", Merge::Copy, N, "1", "V-cavity G1 averaged over the bin's facets by projected area facing v"}};
  return t;
}

namespace {

// The row's estimates: G1 by both estimators, the visible area and the models beside them.
void put_g1_estimates(Json& row, const G1Result& r, const Microsurface& s) {
  Estimate g = r.g1_area_sampling(), gr = r.g1_raycast(), var = r.visible_area_ratio();
  row["g1"] = g.mean;
  row["g1_stderr"] = g.stderr_;
  row["g1_raycast"] = gr.mean;
  row["g1_raycast_stderr"] = gr.stderr_;
  row["visible_area_ratio"] = var.mean;
  row["visible_area_ratio_stderr"] = var.stderr_;
  // In absolute units (surface units squared), perpendicular to v: hits / rays x window area.
  {
    const Estimate p = replicate_mean(r.raycast_hits_r, 1.0 / per_replicate(r.raycast_rays, r.replicates));
    row["visible_projected_area"] = p.mean * r.window_area_perp;
    row["visible_projected_area_stderr"] = p.stderr_ * r.window_area_perp;
    row["macro_projected_area"] = std::abs(r.v.z()) * r.macro_area;  // |v.n| A
  }
  if (r.theta == 0.0) {  // [GeomBSDF24, eq. 2b]: int (n.m) G1(n, m) D(m) dm = visible area along n / A
    row["eq_2b"] = var.mean;
    row["eq_2b_stderr"] = var.stderr_;
  }
  row["lambda_numeric"] = r.lambda_numeric;
  double smith_numeric = 1.0 / (1.0 + r.lambda_numeric);
  row["smith_numeric"] = smith_numeric;
  row["z_numeric"] = z_json(g.mean, smith_numeric, g.stderr_);
  if (s.nominal) {
    // Undersurface rows: the nominal model with v reversed [GeomBSDF24, "Inherent Assumptions"].
    double model = s.nominal->G1(r.undersurface ? Vec3(-r.v) : r.v);
    row["smith_nominal"] = model;
    row["rel_dev_nominal"] = (g.mean - model) / model;
  } else {
    row["smith_nominal"] = nullptr;
    row["rel_dev_nominal"] = nullptr;
  }
}

// The rays and what the tracer counted of them.
void put_g1_ray_counts(Json& row, const G1Result& r, const Microsurface& s) {
  row["rays"] = r.raycast_rays;
  row["area_samples"] = r.sample_rays;
  row["replicates"] = r.replicates;
  if (s.macro().region) {  // a measured window: rays that met its side walls (Tracer rule)
    row["side_exits"] = r.counters.side_exits;
    row["side_entries"] = r.counters.side_entries;
  }
  if (!s.macro().finite_object()) {
    row["lost_rays"] = r.counters.lost_below + r.counters.unresolved;
  } else {
    // A finite object: window rays that pass beside it are misses, not losses.
    row["lost_rays"] = r.counters.unresolved;
    row["missed_rays"] = r.counters.lost_below;
  }
  row["backface_hits"] = r.counters.backface_hits;
  row["border_crossings"] = r.counters.border_crossings;
  row["trace_counters"] = fields_json(r.counters);  // every counter, as TraceCounters declares them
  row["seconds"] = r.seconds;
}

// The deviations of the bins' G1 from the models on their own facets (bins_* fields).
struct BinDeviations {
  double chi2_smith = 0, chi2_vcav = 0, mad_smith = 0, mad_vcav = 0, mad_noise = 0, max_abs_z = 0;
  int dof = 0;
};

// Bin b (holding facets) with its estimates and models, added to the deviations `d` (weights
// w of projected area facing v over `wsum`).
Json g1_bin_json(const G1Result& r, int b, double wsum, BinDeviations& d) {
  const G1NormalBin& nb = r.bins[b];
  Json jb;
  jb["m"] = {nb.mean_normal.x(), nb.mean_normal.y(), nb.mean_normal.z()};
  int it = b / r.binning.n_phi(), ip = b % r.binning.n_phi();
  if (r.undersurface)  // labelled by the undersurface normal -m (theta measured from +z)
    jb["theta_m_range_deg"] = {180 - deg(r.binning.theta_hi(it)), 180 - deg(r.binning.theta_lo(it))};
  else
    jb["theta_m_range_deg"] = {deg(r.binning.theta_lo(it)), deg(r.binning.theta_hi(it))};
  jb["phi_m_range_deg"] = {deg(r.binning.phi_lo(ip)), deg(r.binning.phi_hi(ip))};
  jb["area_fraction"] = nb.area / r.total_area;
  if (!(nb.front_projected > 0 && nb.samples > 0)) {
    jb["g1"] = 0.0;  // back-facing to v: G1(v, m) = 0 by definition
    jb["g1_stderr"] = 0.0;
    return jb;
  }
  Estimate eb = r.bin_g1_area_sampling(b), ea = r.bin_g1_raycast(b);
  jb["g1"] = eb.mean;
  jb["g1_stderr"] = eb.stderr_;
  jb["g1_raycast"] = ea.mean;
  jb["g1_raycast_stderr"] = ea.stderr_;
  const double z = z_score(eb.mean, ea.mean, std::hypot(eb.stderr_, ea.stderr_));
  jb["z_estimators"] = z_json(eb.mean, ea.mean, std::hypot(eb.stderr_, ea.stderr_));
  if (std::isfinite(z)) d.max_abs_z = std::max(d.max_abs_z, std::abs(z));
  const double smith = 1.0 / (1.0 + r.lambda_numeric);     // [GeomBSDF24, eq. 3Xc]: W1, no m dependence
  const double vcav = nb.vcavity_weighted / nb.front_projected;  // [Heitz14, eq. 24], bin average
  jb["smith_numeric"] = smith;
  jb["vcavity_numeric"] = vcav;
  const double w = nb.front_projected / wsum;
  d.mad_smith += w * std::abs(eb.mean - smith);
  d.mad_vcav += w * std::abs(eb.mean - vcav);
  d.mad_noise += w * eb.stderr_ * std::sqrt(2 / kPi);
  // A bin whose samples are all visible (or none) has a zero error: use the resolution of
  // its n samples instead (stats.hpp proportion_floor), so that chi^2 stays finite and honest.
  const double sb = std::max(eb.stderr_, proportion_floor(nb.samples));
  d.chi2_smith += std::pow((eb.mean - smith) / sb, 2);
  d.chi2_vcav += std::pow((eb.mean - vcav) / sb, 2);
  ++d.dof;
  return jb;
}

// Per-bin models on the bin's own facets, and the deviation of the measurement from each.
void put_g1_bins(Json& row, const G1Result& r) {
  Json bins = Json::array();
  BinDeviations d;
  double wsum = 0;
  for (int b = 0; b < r.binning.size(); ++b)
    if (r.bins[b].samples > 0) wsum += r.bins[b].front_projected;
  for (int b = 0; b < r.binning.size(); ++b)
    if (r.bins[b].area > 0) bins.push_back(g1_bin_json(r, b, wsum, d));
  row["bins_dof"] = d.dof;
  row["bins_chi2_smith"] = d.chi2_smith;
  row["bins_chi2_vcavity"] = d.chi2_vcav;
  row["bins_mad_smith"] = d.mad_smith;
  row["bins_mad_vcavity"] = d.mad_vcav;
  row["bins_mad_noise"] = d.mad_noise;
  row["max_abs_z_estimators"] = d.max_abs_z;
  row["bins"] = bins;
}

}  // namespace

Json& add_row(Table& t, const G1Result& r, const Microsurface& s) {
  t.rows.push_back(Json::object());
  Json& row = t.rows.back();
  row["theta_deg"] = deg(r.theta);
  row["phi_deg"] = deg(r.phi);
  put_g1_estimates(row, r, s);
  put_g1_ray_counts(row, r, s);
  put_g1_bins(row, r);
  return row;
}

void add_undersurface_approximations(Json& row, const G1Result& under, const G1Result& reverse_v,
                                     const G1Result& reflect_v) {
  row["undersurface"] = true;
  const Estimate g = under.g1_area_sampling();
  for (auto [name, e] : {std::pair<std::string, Estimate>{"reverse_v", reverse_v.g1_area_sampling()},
                         std::pair<std::string, Estimate>{"reflect_v", reflect_v.g1_area_sampling()}}) {
    row["g1_" + name] = e.mean;
    row["g1_" + name + "_stderr"] = e.stderr_;
    row["z_" + name] = z_json(e.mean, g.mean, std::hypot(g.stderr_, e.stderr_));
    row["rel_dev_" + name] = rel_dev_json(e.mean, g.mean);
  }
}

}  // namespace microsim
