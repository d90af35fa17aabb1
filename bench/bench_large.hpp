// Large-tile experiments of microsim_bench (--only packets, --only layout): the bare loop's rays
// (bench_common.hpp) traced by Embree packets and streams, and against other scene layouts of
// the same grid (flags, build quality, several grid primitives, per-block instances), all
// interleaved in one process. Rates per processor second; every variant counts its hits, which
// must agree (printed) since the rays and the surface are the same.
#pragma once
#include <embree3/rtcore.h>
#include <sys/mman.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "microsim/measure/facet_table.hpp"
#include "microsim/trace/facet_plane.hpp"

namespace microsim::bench {

// How a batch of consecutive rays is handed to Embree.
enum class Batch { Single, Packet4, Packet8, Packet16, Stream };

inline const char* batch_name(Batch b) {
  switch (b) {
    case Batch::Single: return "rtcIntersect1";
    case Batch::Packet4: return "rtcIntersect4";
    case Batch::Packet8: return "rtcIntersect8";
    case Batch::Packet16: return "rtcIntersect16";
    default: return "rtcIntersect1M(64)";
  }
}

template <int N, class Packet, class Fn>
unsigned trace_packets(RTCScene scene, RTCIntersectContext& ctx, const std::vector<Vec3>& org,
                       const float dir[3], Fn&& intersect) {
  unsigned count = 0;
  for (std::size_t k0 = 0; k0 < org.size(); k0 += N) {
    alignas(64) Packet p;
    alignas(64) int valid[N];
    for (int i = 0; i < N; ++i) {
      const std::size_t k = k0 + i;
      valid[i] = k < org.size() ? -1 : 0;
      const Vec3& o = org[std::min(k, org.size() - 1)];
      p.ray.org_x[i] = float(o.x());
      p.ray.org_y[i] = float(o.y());
      p.ray.org_z[i] = float(o.z());
      p.ray.dir_x[i] = dir[0];
      p.ray.dir_y[i] = dir[1];
      p.ray.dir_z[i] = dir[2];
      p.ray.tnear[i] = 0;
      p.ray.tfar[i] = 1e30f;
      p.ray.time[i] = 0;
      p.ray.mask[i] = ~0u;
      p.ray.id[i] = 0;
      p.ray.flags[i] = 0;
      p.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
      p.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    intersect(valid, &ctx, &p);
    for (int i = 0; i < N; ++i) count += valid[i] && p.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
  }
  return count;
}

// The bare loop's rays (same origins, order and chunks as bare_g1_rays_per_second) traced on
// `scene` in batches of 64 consecutive rays, each batch as `batch` says. *hits: rays that hit.
inline Rate batch_rays_per_second(const Tracer& tracer, RTCScene scene, const Vec3& v_in,
                                  const G1Options& o, Batch batch, std::uint64_t* hits_out) {
  const Vec3 v = v_in.normalized();
  const RayWindow w = make_ray_window(tracer, v);
  const G1RayChunks rays(v, o, 0xA000);
  std::vector<unsigned> hits(rays.chunks);
  const float dir[3] = {float(-v.x()), float(-v.y()), float(-v.z())};
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = cpu_seconds();
  tbb::parallel_for(std::uint64_t(0), rays.chunks, [&](std::uint64_t c) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    if (batch != Batch::Single) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    std::vector<Vec3> org;
    org.reserve(64);
    std::vector<RTCRayHit> stream(64);
    unsigned count = 0;
    auto flush = [&] {
      switch (batch) {
        case Batch::Single:
          for (const Vec3& p : org) {
            RTCRayHit rh = bare_ray_hit(p, dir);
            rtcIntersect1(scene, &ctx, &rh);
            count += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
          }
          break;
        case Batch::Packet4:
          count += trace_packets<4, RTCRayHit4>(scene, ctx, org, dir, [&](const int* va, RTCIntersectContext* cx, RTCRayHit4* p) { rtcIntersect4(va, scene, cx, p); });
          break;
        case Batch::Packet8:
          count += trace_packets<8, RTCRayHit8>(scene, ctx, org, dir, [&](const int* va, RTCIntersectContext* cx, RTCRayHit8* p) { rtcIntersect8(va, scene, cx, p); });
          break;
        case Batch::Packet16:
          count += trace_packets<16, RTCRayHit16>(scene, ctx, org, dir, [&](const int* va, RTCIntersectContext* cx, RTCRayHit16* p) { rtcIntersect16(va, scene, cx, p); });
          break;
        case Batch::Stream: {
          for (std::size_t k = 0; k < org.size(); ++k) stream[k] = bare_ray_hit(org[k], dir);
          rtcIntersect1M(scene, &ctx, stream.data(), static_cast<unsigned>(org.size()), sizeof(RTCRayHit));
          for (std::size_t k = 0; k < org.size(); ++k) count += stream[k].hit.geomID != RTC_INVALID_GEOMETRY_ID;
          break;
        }
      }
      org.clear();
    };
    for (std::uint64_t j = rays.first(c); j < rays.end(c); ++j)
      for (int rep = 0; rep < rays.R; ++rep) {
        CounterRng rng(o.seed, rays.streams[rep], j);
        const Vec2 ab = rays.plan.strata.point(j, rng);
        org.push_back(w.origin0 + ab.x() * w.e1 + ab.y() * w.e2);
        if (org.size() == 64) flush();
      }
    flush();
    hits[c] = count;
  });
  const Rate rate = rate_since(static_cast<double>(rays.plan.total()), t0, c0);
  std::uint64_t total = 0;
  for (unsigned h : hits) total += h;
  *hits_out = total;
  return rate;
}

// Another Embree scene of a periodic heightfield's grid (padded by one cell as the Tracer's):
// `block` 0 one grid primitive; > 0 grid primitives of block x block cells in one geometry
// (`instances` false) or one sub-scene per block, each with its own compact vertex buffer,
// instanced in a top scene (`instances` true).
struct LayoutScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<std::pair<void*, std::size_t>> maps;
  std::vector<RTCScene> subs;
  double build_s = 0, mib = 0;
  LayoutScene(const Microsurface& s, bool compact, RTCBuildQuality quality, int block, bool instances) {
    const double rss0 = rss_mib();
    const auto t0 = std::chrono::steady_clock::now();
    device = rtcNewDevice("hugepages=1");
    const int gw = s.nx() + 3, gh = s.ny() + 3;  // vertices, pad 1 on each side
    const RTCSceneFlags flags = static_cast<RTCSceneFlags>(RTC_SCENE_FLAG_ROBUST | (compact ? RTC_SCENE_FLAG_COMPACT : 0));
    auto vertex_buffer = [&](int i0, int j0, int w, int h) {
      const std::size_t bytes = 12 * static_cast<std::size_t>(w) * h + 16;
      void* m = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      madvise(m, bytes, MADV_HUGEPAGE);
      maps.emplace_back(m, bytes);
      auto* f = static_cast<float*>(m);
      grid_vertices(s, i0, j0, w, h, f);
      return f;
    };
    scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, flags);
    rtcSetSceneBuildQuality(scene, quality);
    if (!instances) {
      attach_grid_blocks(device, scene, vertex_buffer(0, 0, gw, gh), gw, gh, block);
    } else {
      const int cells_x = gw - 1, cells_y = gh - 1, b = block;
      for (int jb = 0; jb * b < cells_y; ++jb)
        for (int ib = 0; ib * b < cells_x; ++ib) {
          const int w = std::min(b, cells_x - ib * b) + 1, h = std::min(b, cells_y - jb * b) + 1;
          float* v = vertex_buffer(ib * b, jb * b, w, h);
          RTCScene sub = rtcNewScene(device);
          rtcSetSceneFlags(sub, flags);
          rtcSetSceneBuildQuality(sub, quality);
          attach_grid_blocks(device, sub, v, w, h, 0);
          rtcCommitScene(sub);
          subs.push_back(sub);
          RTCGeometry inst = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
          rtcSetGeometryInstancedScene(inst, sub);
          const float id[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
          rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, id);
          rtcCommitGeometry(inst);
          rtcAttachGeometry(scene, inst);
          rtcReleaseGeometry(inst);
        }
    }
    rtcCommitScene(scene);
    build_s = seconds_since(t0);
    mib = rss_mib() - rss0;
  }
  ~LayoutScene() {
    rtcReleaseScene(scene);
    for (RTCScene s : subs) rtcReleaseScene(s);
    rtcReleaseDevice(device);
    for (auto& [m, b] : maps) munmap(m, b);
  }
  LayoutScene(const LayoutScene&) = delete;
  LayoutScene& operator=(const LayoutScene&) = delete;
};

// --only packets: single rays, packets of 4/8/16 and coherent streams of 64 on the same rays.
inline void print_packet_rows(const Tracer& tracer, const Vec3& v, const G1Options& o, int repeat,
                              int res, double theta_deg) {
  const Batch all[] = {Batch::Single, Batch::Packet4, Batch::Packet8, Batch::Packet16, Batch::Stream};
  Rate best[5];
  std::uint64_t hits[5] = {};
  for (int k = 0; k < repeat; ++k)
    for (int b = 0; b < 5; ++b) best[b].best_of(batch_rays_per_second(tracer, tracer.scene(), v, o, all[b], &hits[b]));
  std::printf("%5d^2 %3.0fdeg", res, theta_deg);
  for (int b = 0; b < 5; ++b) std::printf("  %s %.2f (%.2f)", batch_name(all[b]), best[b].cpu / 1e6, best[b].cpu / best[0].cpu);
  std::printf("  hits %llu%s\n", static_cast<unsigned long long>(hits[0]),
              std::all_of(hits, hits + 5, [&](std::uint64_t h) { return h == hits[0]; }) ? "" : " (DIFFER)");
  std::fflush(stdout);
}

// --only layout: the Tracer's scene against other layouts of the same grid, bare single rays.
inline void print_layout_rows(const Tracer& tracer, const Vec3& v, const G1Options& o, int repeat,
                              int res, double theta_deg) {
  struct L {
    const char* name;
    bool compact;
    RTCBuildQuality q;
    int block;
    bool inst;
  };
  const L layouts[] = {{"no COMPACT", false, RTC_BUILD_QUALITY_HIGH, 0, false},
                       {"MEDIUM", true, RTC_BUILD_QUALITY_MEDIUM, 0, false},
                       {"grids 256^2", true, RTC_BUILD_QUALITY_HIGH, 256, false},
                       {"instances 256^2", true, RTC_BUILD_QUALITY_HIGH, 256, true},
                       {"instances 64^2", true, RTC_BUILD_QUALITY_HIGH, 64, true}};
  const double nf = 2.0 * res * res;
  for (const L& l : layouts) {
    LayoutScene alt(tracer.surface(), l.compact, l.q, l.block, l.inst);
    Rate base, other;
    std::uint64_t h0 = 0, h1 = 0;
    for (int k = 0; k < repeat; ++k) {
      base.best_of(batch_rays_per_second(tracer, tracer.scene(), v, o, Batch::Single, &h0));
      other.best_of(batch_rays_per_second(tracer, alt.scene, v, o, Batch::Single, &h1));
    }
    std::printf("%5d^2 %3.0fdeg %-16s build %.1f s, %.1f B/facet: %.2f against the Tracer's %.2f (%.2f)  hits %llu / %llu\n",
                res, theta_deg, l.name, alt.build_s, alt.mib * 1048576.0 / nf, other.cpu / 1e6, base.cpu / 1e6,
                other.cpu / base.cpu, static_cast<unsigned long long>(h1), static_cast<unsigned long long>(h0));
    std::fflush(stdout);
  }
}

// Estimator (b)'s rays as measure_g1 draws and traces them (same streams, draws, sample points
// and occlusion rays, replicates interleaved in chunks), without tallies: `ahead` false draws
// and traces each ray in turn (measure_g1 below kAheadMinCells cells), true sets each draw up 8
// rays ahead with its block's heights, bins and grid leaves prefetched (measure_g1 from
// kAheadMinCells on a periodic heightfield). *visible: rays not occluded (must agree).
inline Rate sample_rays_per_second(const Tracer& tracer, const FacetTable& ft, const Vec3& v_in,
                                   const G1Options& o, bool ahead, std::uint64_t* visible) {
  const Vec3 v = v_in.normalized();
  const Microsurface& s = tracer.surface();
  const std::size_t nf = s.num_facets();
  const auto weights = [&](std::size_t k0, std::size_t k1, double* w) {
    ft.for_each_cross(k0, k1, [&](std::size_t k, const Vec3& c) { w[k - k0] = std::max(0.0, 0.5 * c.dot(v)); });
  };
  const BlockFacetSampler sampler(nf, BlockFacetSampler::Blocks{}, weights);
  const double total = sampler.total();
  const G1RayChunks rays(v, o, 0xB000);
  const int R = rays.R;
  const std::uint64_t n = rays.n;
  const std::vector<std::uint64_t>& streams = rays.streams;
  std::vector<unsigned> vis(rays.chunks);
  struct Draw {
    CounterRng rng{0, 0, 0};
    double u = 0;
    std::size_t block = 0;
  };
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = cpu_seconds();
  tbb::parallel_for(std::uint64_t(0), rays.chunks, [&](std::uint64_t c) {
    TraceCounters counters;
    unsigned count = 0;
    std::vector<std::size_t> hint(R, 0);
    auto finish = [&](CounterRng& rng, std::size_t k) {
      const Triangle f = facet_triangle(s, k);
      const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
      const Vec3 p = f.point(r1 * (1 - r2), r1 * r2);
      const SourcePlane plane = SourcePlane::of(f);
      count += ft.bin(k) >= -1 && !tracer.occluded(p, v, &plane, counters);
    };
    const std::uint64_t j0 = rays.first(c), j1 = rays.end(c);
    if (!ahead) {
      for (std::uint64_t j = j0; j < j1; ++j)
        for (int rep = 0; rep < R; ++rep) {
          CounterRng rng(o.seed, streams[rep], j);
          const double u = (static_cast<double>(j) + rng.uniform()) / n * total;
          finish(rng, sampler.draw(u, BlockFacetSampler::Blocks{}, weights, &hint[rep]));
        }
    } else {
      std::uint64_t j = j0;
      int rep = 0;
      constexpr std::size_t kB = BlockFacetSampler::kBlock;
      run_ahead<Draw>(
          (j1 - j0) * R,
          [&] {
            CounterRng rng(o.seed, streams[rep], j);
            const double u = (static_cast<double>(j) + rng.uniform()) / n * total;
            const std::size_t b = sampler.block(u, &hint[rep]);
            const std::size_t k0 = b * kB, k1 = std::min(nf, k0 + kB);
            ft.prefetch_range(k0, k1);
            const long cc0 = static_cast<long>(k0 / 2), cc1 = static_cast<long>((k1 - 1) / 2);
            const long row = cc0 / s.nx();
            tracer.prefetch_cells(cc0 - row * s.nx(), cc1 / s.nx() == row ? cc1 - row * s.nx() : s.nx() - 1, row);
            if (++rep == R) {
              rep = 0;
              ++j;
            }
            return Draw{rng, u, b};
          },
          [&](Draw& d) { finish(d.rng, sampler.draw_in(d.block, d.u, weights)); });
    }
    vis[c] = count;
  });
  const Rate rate = rate_since(static_cast<double>(rays.plan.total()), t0, c0);
  std::uint64_t t = 0;
  for (unsigned x : vis) t += x;
  *visible = t;
  return rate;
}

// --only sample: estimator (b)'s rays with and without the look-ahead, interleaved.
inline void print_sample_rows(const Tracer& tracer, const FacetTable& ft, const Vec3& v, const G1Options& o,
                              int repeat, int res, double theta_deg) {
  Rate plain, ahead;
  std::uint64_t v0 = 0, v1 = 0;
  for (int k = 0; k < repeat; ++k) {
    plain.best_of(sample_rays_per_second(tracer, ft, v, o, false, &v0));
    ahead.best_of(sample_rays_per_second(tracer, ft, v, o, true, &v1));
  }
  std::printf("%5d^2 %3.0fdeg (b) rays without look-ahead %.2f  with %.2f (%.2f)  visible %llu / %llu\n", res,
              theta_deg, plain.cpu / 1e6, ahead.cpu / 1e6, ahead.cpu / plain.cpu,
              static_cast<unsigned long long>(v0), static_cast<unsigned long long>(v1));
  std::fflush(stdout);
}

}  // namespace microsim::bench
