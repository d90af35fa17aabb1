// The yardstick for the BSDF walks: a plain single-ray Embree walk tracer, as a competent user
// would script it for a periodic heightfield tile. Its own scene over the same float heights
// (one grid geometry with a one-cell periodic border, default scene flags and build quality:
// no ROBUST, no filter), rtcIntersect1 per segment, wrap-around at the tile border, mirror
// reflection about Embree's normalised geometric normal (dielectric: Fresnel choice between
// reflection and refraction, total internal reflection), self-intersection avoided by moving
// the new origin a small distance off the facet along the normal, and the outgoing directions
// of each thread counted in a plain histogram. The same origins as measure_bsdf (stratified,
// Morton-ordered, the same replicates and random streams), the same paths count and incidence.
// Not exact (the offset skips concave corners closer than it; float arithmetic throughout):
// a speed reference only.
#pragma once
#include <embree3/rtcore.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "bench_common.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim::bench {

struct PlainWalkStats {
  std::uint64_t paths = 0, segments = 0, queries = 0;  // segments: rays between events
  std::uint64_t reflected = 0, transmitted = 0, lost = 0;
  double albedo_r = 0, albedo_t = 0;  // fractions of the paths
};

class PlainWalker {
 public:
  // A periodic heightfield only (the benchmark's Gaussian tiles).
  // `robust`: RTC_SCENE_FLAG_ROBUST (as the Tracer's scene), to measure what it costs.
  explicit PlainWalker(const Microsurface& s, bool robust = false) : s_(s) {
    if (s.kind() != Microsurface::Kind::Heightfield || !s.macro().periodic)
      throw std::runtime_error("PlainWalker: periodic heightfields only");
    device_ = rtcNewDevice(nullptr);
    scene_ = rtcNewScene(device_);
    if (robust) rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_GRID);
    const int nx = s.nx(), ny = s.ny(), w = nx + 3, h = ny + 3;
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), std::size_t(w) * h + 1));
    grid_vertices(s, 0, 0, w, h, v);  // periodic heights, one cell around
    float zmin = 1e30f, zmax = -1e30f;
    for (std::size_t k = 0; k < std::size_t(w) * h; ++k) {
      zmin = std::min(zmin, v[3 * k + 2]);
      zmax = std::max(zmax, v[3 * k + 2]);
    }
    auto* grid = static_cast<RTCGrid*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_GRID, 0, RTC_FORMAT_GRID,
                                                               sizeof(RTCGrid), 1));
    grid->startVertexID = 0;
    grid->stride = unsigned(w);
    grid->width = static_cast<unsigned short>(w);
    grid->height = static_cast<unsigned short>(h);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene_, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene_);
    hx_ = float(0.5 * s.macro().size_x);
    hy_ = float(0.5 * s.macro().size_y);
    cell_ = float(std::min(s.dx(), s.dy()));
    eps_ = 1e-6f * float(std::max(s.macro().size_x, s.macro().size_y));
    ztop_ = zmax + eps_;
    zbot_ = zmin - eps_;
  }
  ~PlainWalker() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  PlainWalker(const PlainWalker&) = delete;
  PlainWalker& operator=(const PlainWalker&) = delete;
  RTCScene scene() const { return scene_; }

  // `paths` walks at incidence wi (light direction, wi.z > 0) from the ray window of `tracer`
  // (measure_bsdf's); eta 0: mirror, else a dielectric of that index. Histogram: per thread,
  // 2 x 64 x 64 cells over (x, y) of the outgoing direction, up and down.
  PlainWalkStats run(const Tracer& tracer, const Vec3& wi, std::uint64_t paths, double eta,
                     std::uint64_t seed = 1, int replicates = kDefaultReplicates, int max_events = 10000) const {
    const RayWindow window = make_ray_window(tracer, wi);
    const ReplicatePlan plan(paths, replicates);
    const std::uint64_t n = plan.per_replicate(), chunk = 4096, nc = (n + chunk - 1) / chunk;
    struct Local {
      std::vector<std::uint32_t> hist = std::vector<std::uint32_t>(2 * 64 * 64, 0);
      std::uint64_t segments = 0, queries = 0, refl = 0, trans = 0, lost = 0;
    };
    tbb::enumerable_thread_specific<Local> locals;
    tbb::parallel_for(std::uint64_t(0), nc * std::uint64_t(plan.replicates), [&](std::uint64_t c) {
      Local& L = locals.local();
      const int rep = int(c / nc);
      const std::uint64_t stream = ReplicatePlan::stream(0x9A1Full, rep);
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      for (std::uint64_t i = (c % nc) * chunk; i < std::min(n, (c % nc + 1) * chunk); ++i) {
        CounterRng rng(seed, stream, i);
        const Vec2 ab = plan.strata.point(i, rng);
        const Vec3 o0 = window.origin0 + ab.x() * window.e1 + ab.y() * window.e2;
        float o[3] = {float(o0.x()), float(o0.y()), float(o0.z())};
        float d[3] = {float(-wi.x()), float(-wi.y()), float(-wi.z())};
        bool inside = false;
        int end = 2;  // 0 reflected, 1 transmitted, 2 lost
        for (int event = 0; event <= max_events; ++event) {
          ++L.segments;
          RTCRayHit rh;
          if (!trace(ctx, o, d, rh, L.queries)) {
            if (!inside && d[2] > 0) end = 0;
            else if (inside && d[2] < 0) end = 1;
            break;
          }
          if (event == max_events) break;
          // Unit normal facing the incoming ray.
          float nn[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
          const float inv = 1.0f / std::sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
          float cosi = -(nn[0] * d[0] + nn[1] * d[1] + nn[2] * d[2]) * inv;
          const float sgn = cosi < 0 ? -inv : inv;
          for (float& x : nn) x *= sgn;
          cosi = std::abs(cosi);
          const float t = rh.ray.tfar;
          float p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
          bool refract = false;
          float td[3];
          if (eta > 0) {
            const float r = inside ? float(eta) : float(1.0 / eta);  // near over far index
            const float k = 1.0f - r * r * (1.0f - cosi * cosi);
            float F = 1.0f;
            if (k > 0) {
              const float ct = std::sqrt(k);
              const float rs = (r * cosi - ct) / (r * cosi + ct), rp = (cosi - r * ct) / (cosi + r * ct);
              F = 0.5f * (rs * rs + rp * rp);
              if (float(rng.uniform()) >= F) {
                refract = true;
                for (int a = 0; a < 3; ++a) td[a] = r * d[a] + (r * cosi - ct) * nn[a];
              }
            }
          }
          const float off = refract ? -eps_ : eps_;
          for (int a = 0; a < 3; ++a) {
            d[a] = refract ? td[a] : d[a] + 2 * cosi * nn[a];
            o[a] = p[a] + off * nn[a];
          }
          if (refract) inside = !inside;
        }
        if (end == 2) {
          ++L.lost;
          continue;
        }
        (end == 0 ? L.refl : L.trans) += 1;
        const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const int bx = std::min(63, int((d[0] / len + 1) * 32)), by = std::min(63, int((d[1] / len + 1) * 32));
        ++L.hist[std::size_t(end) * 4096 + std::size_t(by) * 64 + std::size_t(std::max(0, bx))];
      }
    });
    PlainWalkStats st;
    st.paths = plan.total();
    for (const Local& L : locals) {
      st.segments += L.segments;
      st.queries += L.queries;
      st.reflected += L.refl;
      st.transmitted += L.trans;
      st.lost += L.lost;
    }
    st.albedo_r = double(st.reflected) / double(st.paths);
    st.albedo_t = double(st.transmitted) / double(st.paths);
    return st;
  }

 private:
  // First hit from o along d, wrapping at the tile border; false when the ray leaves the slab.
  bool trace(RTCIntersectContext& ctx, float o[3], const float d[3], RTCRayHit& rh, std::uint64_t& queries) const {
    for (int seg = 0; seg < 100000; ++seg) {
      float t_exit = 1e30f;
      if (d[0] > 0) t_exit = std::min(t_exit, (hx_ - o[0]) / d[0]);
      if (d[0] < 0) t_exit = std::min(t_exit, (-hx_ - o[0]) / d[0]);
      if (d[1] > 0) t_exit = std::min(t_exit, (hy_ - o[1]) / d[1]);
      if (d[1] < 0) t_exit = std::min(t_exit, (-hy_ - o[1]) / d[1]);
      t_exit = std::max(t_exit, 0.0f);
      const float t_slab = d[2] > 0 ? (ztop_ - o[2]) / d[2] : d[2] < 0 ? (zbot_ - o[2]) / d[2] : 1e30f;
      if (t_slab < 0) return false;
      const float dxy = std::max(std::abs(d[0]), std::abs(d[1]));
      const float margin = dxy > 0 ? 0.5f * cell_ / dxy : 0.0f;  // into the periodic border
      rh.ray.org_x = o[0];
      rh.ray.org_y = o[1];
      rh.ray.org_z = o[2];
      rh.ray.dir_x = d[0];
      rh.ray.dir_y = d[1];
      rh.ray.dir_z = d[2];
      rh.ray.tnear = 0;
      rh.ray.tfar = std::min(t_exit + margin, t_slab);
      rh.ray.mask = ~0u;
      rh.ray.flags = 0;
      rh.ray.time = 0;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      ++queries;
      rtcIntersect1(scene_, &ctx, &rh);
      if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) return true;
      if (t_slab <= t_exit) return false;
      for (int a = 0; a < 3; ++a) o[a] += t_exit * d[a];
      const float tol = 1e-6f * hx_;
      if (d[0] > 0 && o[0] >= hx_ - tol) o[0] -= 2 * hx_;
      else if (d[0] < 0 && o[0] <= -hx_ + tol) o[0] += 2 * hx_;
      if (d[1] > 0 && o[1] >= hy_ - tol) o[1] -= 2 * hy_;
      else if (d[1] < 0 && o[1] <= -hy_ + tol) o[1] += 2 * hy_;
    }
    return false;
  }

  const Microsurface& s_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  float hx_ = 0, hy_ = 0, cell_ = 0, eps_ = 0, ztop_ = 0, zbot_ = 0;
};

}  // namespace microsim::bench
