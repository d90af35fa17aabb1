// Ray tracing of a microsurface with Embree 3: first hits and occlusion, periodic wrap-around,
// and self-intersection handled by rejecting the plane of the facet a ray leaves.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <embree3/rtcore.h>

#include "microsim/surface/microsurface.hpp"
#include "microsim/tally_fields.hpp"
#include "microsim/trace/facet_plane.hpp"
#include "microsim/trace/source_plane.hpp"
#include "microsim/trace/tile_border.hpp"
#include "microsim/trace/trace_counters.hpp"

namespace microsim {

// The fields of an Embree ray after its origin and direction: [0, tfar] (infinite when tfar is
// not finite), every geometry, no motion blur.
inline void set_ray_extent(RTCRay& ray, double tfar) {
  ray.tnear = 0.0f;
  ray.tfar = std::isfinite(tfar) ? static_cast<float>(tfar) : std::numeric_limits<float>::infinity();
  ray.mask = 0xFFFFFFFFu;
  ray.flags = 0;
  ray.time = 0;
  ray.id = 0;
}

// The facet a ray leaves, for the walks: its index and its unit normal as the tracer reported it
// (TraceHit::normal, within kReportedNormalSlack of SourcePlane::of's normal of the same facet).
// The filter decides with that normal that a candidate hit is not parallel to the plane left
// (nearly always) and forms the exact plane (FacetPlanes, trace/facet_plane.hpp) only for a
// candidate too near parallel to tell: the same decisions as with the plane, without forming it
// at every event.
struct SourceFacet {
  std::size_t facet;
  Vec3 normal;
};
// Bound on |TraceHit::normal - SourcePlane::of(facet).normal| for the same facet: both normalise
// the facet's cross product, the tracer's with the cell sizes dx, dy, the plane's with the
// differences of the corners' x, y, which differ from dx, dy by the rounding of coordinates
// (relative 2^-51 of the tile size: below 3e-11 of a cell for grids up to 65535 cells wide).
// Checked on tiles in tests/test_trace.cpp.
constexpr double kReportedNormalSlack = 1e-7;

// The filter's test that a candidate with Embree normal ng is not parallel to the plane left
// (normal n): |ng.n| / |ng| < 1 - 1e-6, with a = |ng.n| and len2 = |ng|^2 (exactly the
// quotient's rounding). not_parallel_clearly(a, len2, slack) is true only where that holds for
// every normal within `slack` of n (and the quotient's rounding): decided on squares, without
// the square root and the division. Elsewhere (near parallel, or too near the threshold to
// tell) the caller evaluates not_parallel_exactly with the exact normal.
inline bool not_parallel_exactly(double a, double len2) { return a / std::sqrt(len2) < 1.0 - 1e-6; }
inline bool not_parallel_clearly(double a, double len2, double slack, double margin = 1e-9) {
  // a / |ng| < c - slack with c = (1 - 1e-6)(1 - margin): the exact a' = |ng.n'| is below
  // c |ng| for |n' - n| <= slack, and c is 1e-9 below the threshold, far beyond the relative
  // rounding (a few 1e-16) of the squares and of the quotient. Squares are compared only where
  // they are normal numbers (len2 >= 1e-280).
  const double c = (1.0 - 1e-6) * (1.0 - margin) - slack;
  return len2 >= 1e-280 && a * a < c * c * len2;
}

// The side of the surface a ray travels on. Front: above the surface / outside a solid (every
// ray of D, G1, and the BSDF of opaque materials); hits are expected on front faces. Back: below
// the surface / inside a solid (light refracted into a dielectric); hits are expected on back
// faces (the underside), and leaving the slab downward is an exit (TraceHit::exit_below), not a
// loss.
enum class RaySide { Front, Back };

struct TraceHit {
  bool hit = false;
  bool exit_below = false;  // Back-side ray: left the slab downward without a hit (transmitted)
  Vec3 point = Vec3::Zero();   // periodic surfaces: the copy inside the tile
  Vec3 normal = Vec3::Zero();  // unit facet normal (exact, from the surface's own facet)
  std::size_t facet = 0;
  bool backface = false;  // the ray met the facet from behind (rounding at silhouettes)
};

class Tracer;

// Parallel rays along -v (v.n > 0) that start above the surface: the primary rays of the G1
// ray-casting estimator. Tracer::front_facet(rays, org, c) gives the same Embree queries and
// the same answer as first_hit(org, -v, nullptr, c) reduced to "which facet, if its front face
// was met first", with everything that depends only on v computed once here. On a periodic
// heightfield it decodes the hit from Embree's grid (u, v) and vertex buffer alone, with no
// TraceHit, hit point or normalized normal; anything else takes first_hit.
struct DownwardRays {
  static constexpr std::size_t kNone = ~static_cast<std::size_t>(0);
  DownwardRays(const Tracer& tracer, const Vec3& v);  // v: unit, v.n > 0
  Vec3 dir;                  // -v
  float fdir[3] = {0, 0, 0};  // the float direction Embree sees
  double margin = 0;         // past the tile border (Tracer::trace)
  double run_x = 0, run_y = 0;  // xy travelled per unit of height descended (prefetch_front)
  bool lean = false;         // the dedicated path applies (periodic heightfield)
  // Constants of the lean path, so that a ray costs no division in the common case:
  double z0 = 0, t_slab0 = 0;   // the window's height (Tracer::z_top) and the distance from it
                                // to the slab bottom along dir
  double cells_x = 0, cells_y = 0;  // cells of Embree's grid (its hit u, v run over them)
  // Decoding a hit (Tracer::front_facet). Grid coordinates u (cells_x) and v (cells_y) further
  // than `band` cells from their cell's borders and diagonal name the cell and the half directly
  // (Embree rounds them within a few 1e-7 of the grid size, see DownwardRays()); and when
  // (Ng.dir)^2 > graze |Ng|^2 the sign of Embree's float normal Ng along dir is that of the
  // facet's exact normal. Anything closer takes the checked decoding (the facet whose normal is
  // aligned with Ng, the back face from the exact normal). exact_decode: always the checked one.
  double band = 0, graze = 0;
  bool exact_decode = false;
  // The tile, read once here instead of from the surface on every ray: cells, the padding of
  // Embree's grid, half sizes, the slab bottom; region: facets are numbered by a sample region.
  long nx = 0, ny = 0, pad = 0;
  double hx = 0, hy = 0, z_bottom = 0;
  bool region = false;
};

class Tracer {
 public:
  explicit Tracer(const Microsurface& surface);
  ~Tracer();
  Tracer(const Tracer&) = delete;
  Tracer& operator=(const Tracer&) = delete;

  // First hit along org + t dir, t > 0, following periodic wrap-around. `source`, when given,
  // is the plane the ray leaves. `side`: see RaySide (Back rays should always pass `source`).
  // A non-periodic heightfield window (a measured patch) is traced as it is, without wrap: a
  // ray starting outside its footprint starts where it enters the footprint (a side wall if
  // it is low, counted in side_entries); a ray that reaches a side wall inside the slab ends
  // there without a hit (counted in side_exits): upward it has escaped (the rule for the
  // unmeasured surroundings; its bias is what the guard band keeps small), downward it is
  // lost. occluded() likewise: a ray leaving through a side wall is not occluded.
  TraceHit first_hit(const Vec3& org, const Vec3& dir, const SourcePlane* source,
                     TraceCounters& counters, RaySide side = RaySide::Front) const;
  // The same for a ray leaving facet `source.facet` (SourceFacet): exactly first_hit with
  // SourcePlane::of that facet (the same hits and counters, bit for bit).
  TraceHit first_hit(const Vec3& org, const Vec3& dir, const SourceFacet& source,
                     TraceCounters& counters, RaySide side = RaySide::Front) const;
  // True when anything blocks the ray before it leaves the surface's slab upward (or, for a
  // finite object, before infinity).
  bool occluded(const Vec3& org, const Vec3& dir, const SourcePlane* source,
                TraceCounters& counters) const;

  const Microsurface& surface() const { return surface_; }
  double z_top() const { return z_top_; }
  double z_bottom() const { return z_bottom_; }
  RTCScene scene() const { return scene_; }
  // Heightfields: Embree's grid vertices (x, y, z floats), null for meshes; the facet planes
  // formed from them (FacetPlanes, the same triangles as the surface's facets).
  const float* grid_vertices() const { return grid_vertices_; }
  FacetPlanes facet_planes() const { return FacetPlanes(surface_, grid_vertices_); }
  double build_seconds() const { return build_seconds_; }

  // Benchmarks: while a log is set on a thread, every Embree query that thread's traces make
  // is appended to it (ray as passed, before the query), so that a bare loop can replay the
  // very same queries. Null (the default) logs nothing.
  static void log_rays_on_this_thread(std::vector<RTCRay>* log);

  // The facet whose front face the ray from org along rays.dir meets first, or
  // DownwardRays::kNone (nothing met, or a back face first; counted as first_hit counts them).
  std::size_t front_facet(const DownwardRays& rays, const Vec3& org, TraceCounters& c) const;
  // front_facet for n rays, traced a block of kBatch rays at a time: the block's origins are set
  // up (origin(i), in order), then its Embree queries made one after the other, then its hits
  // decoded, use(i, facet) called in order with what front_facet(rays, origin(i), counters(i))
  // returns. The same queries and answers (one decoding, shared with front_facet), only the
  // order of the queries of different rays changes (a ray's further segments are traced when
  // its first one is decoded); each phase's loop is short. Not a periodic heightfield: ray by
  // ray.
  template <std::size_t kBatch = 32, class Origin, class Counters, class Use>
  void front_facets(const DownwardRays& rays, std::size_t n, Origin&& origin, Counters&& counters,
                    Use&& use) const;
  // A hint, no effect on any result: starts loading the grid vertices near where the ray from
  // org along rays.dir is expected to meet the surface (where it crosses the mean height), so
  // that a front_facet call a few rays later finds them in cache. On large tiles consecutive
  // rays rarely share vertices and each ray otherwise waits for its own memory reads. Returns
  // the facet expected there (for the caller's own per-facet data), or DownwardRays::kNone.
  std::size_t prefetch_front(const DownwardRays& rays, const Vec3& org) const;
  // The same hint for rays that start on the surface: the vertex rows of the grid leaves that
  // hold cells i0 .. i1 of tile row j (0 <= i0 <= i1 < nx, 0 <= j < ny; a few cells, e.g. a
  // block of facets drawn from). No effect on any result; nothing for other surfaces.
  void prefetch_cells(long i0, long i1, long j) const;

  // Which of the surface's facets a raw Embree hit refers to, and (optionally) its exact unit
  // normal.
  std::size_t facet_of_hit(unsigned prim_id, float u, float v, const Vec3& ng,
                           Vec3* normal = nullptr) const;

 private:
  friend struct DownwardRays;
  // The constructor's geometry of a heightfield (an Embree grid) or of a mesh (triangles).
  RTCGeometry new_grid_geometry();
  RTCGeometry new_mesh_geometry();
  // Heightfields: cell (i, j) (tile indices, unwrapped), half and unnormalised normal c of the
  // facet that grid coordinates (u, v) name; true when c is aligned with Embree's Ng (else a
  // rounding at a cell border named a neighbour: facet_of_hit searches around).
  bool grid_facet_guess(float u, float v, const Vec3& ng, long& i, long& j, int& half,
                        Vec3& c) const;
  // The lean path (front_facet) in pieces. front_query: the Embree query of a ray's segment
  // from o (inside the tile), with its slab and border distances; false when o is below the
  // slab (lost, no query).
  struct FrontSegment {
    double t_slab = 0, t_exit = 0;
    bool slab_first = false;  // the segment certainly leaves the slab before the tile border
  };
  bool front_query(const DownwardRays& rays, const Vec3& o, RTCRayHit& rh, FrontSegment& seg) const;
  // o of the ray from org: its copy inside the tile.
  Vec3 front_origin(const DownwardRays& rays, const Vec3& org) const;
  // The answer to a hit of the ray from org after `crossings` wrap-arounds: fast decoding from
  // Embree's (u, v) and Ng, else front_checked.
  std::size_t front_decode(const DownwardRays& rays, const Vec3& org, const RTCRayHit& rh,
                           std::uint64_t crossings, TraceCounters& c) const;
  // The rare cases, out of the hot loop: a hit near a cell's border or diagonal or grazing
  // (checked decoding, back faces traced again by first_hit); a first segment that missed
  // (the ray's further segments); a ray lost before its first query.
  std::size_t front_checked(const DownwardRays& rays, const Vec3& org, const RTCRayHit& rh,
                            std::uint64_t crossings, TraceCounters& c) const;
  std::size_t front_after_miss(const DownwardRays& rays, const Vec3& org, TraceCounters& c) const;
  static std::size_t front_lost(TraceCounters& c, std::uint64_t crossings);
  static std::vector<RTCRay>* ray_log_of_this_thread();
  template <bool kOcclusion>
  bool trace(const Vec3& org, const Vec3& dir, const SourcePlane* source,
             const SourceFacet* leaving, TraceCounters& c, TraceHit* out,
             RaySide side = RaySide::Front) const;
  // trace in steps (tracer.cpp, inline there: every query takes them): the ray's state between
  // segments, a window's entry, a segment's extent, a hit's report, the step through the border.
  struct RayState;
  inline double border_margin(const Vec3& dir) const;
  inline double footprint_exit(const Vec3& p, const Vec3& dir) const;
  bool enter_window(RayState& r, TraceCounters& c) const;
  inline bool segment_extent(RayState& r) const;
  inline bool take_hit(const RTCRayHit& rh, const RayState& r, bool filtered, TraceCounters& c,
                       TraceHit* out) const;
  inline bool cross_border(RayState& r, TraceCounters& c, TraceHit* out) const;

  const Microsurface& surface_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  double z_top_ = 0, z_bottom_ = 0;
  int pad_ = 1;            // heightfield: cells of periodic copy around the tile
  int grid_width_ = 0;     // heightfield: vertices per grid row in Embree
  int grid_height_ = 0;
  const float* grid_vertices_ = nullptr;  // heightfield: Embree's vertex buffer (x, y, z)
  void* vertex_pages_ = nullptr;  // heightfield: the vertex buffer's own mapping (huge pages)
  std::size_t vertex_bytes_ = 0;
  double mean_height_ = 0;  // heightfield: mean of the traced grid's heights (prefetch_front)
  bool window_ = false;    // non-periodic heightfield: traced without wrap, footprint below
  double foot_x0_ = 0, foot_x1_ = 0, foot_y0_ = 0, foot_y1_ = 0;
  std::vector<std::uint32_t> mesh_prim_to_facet_;  // periodic meshes: copies map back
  double build_seconds_ = 0;
  double scale_ = 1;  // scene size, for relative tolerances (read by the filter)
};

// --- The lean path's hot pieces (inline: the loops of front_facets and measure_g1) ----------

inline Vec3 Tracer::front_origin(const DownwardRays& rays, const Vec3& org) const {
  Vec3 o = org;
  const double sx = 2 * rays.hx, sy = 2 * rays.hy;
  if (o.x() < -rays.hx || o.x() > rays.hx) o.x() -= sx * std::floor((o.x() + rays.hx) / sx);
  if (o.y() < -rays.hy || o.y() > rays.hy) o.y() -= sy * std::floor((o.y() + rays.hy) / sy);
  return o;
}

inline bool Tracer::front_query(const DownwardRays& rays, const Vec3& o, RTCRayHit& rh,
                                FrontSegment& seg) const {
  const Vec3& dir = rays.dir;
  // From the window's height the slab distance is a constant of the direction (the same
  // quotient); dir.z < 0.
  seg.t_slab = o.z() == rays.z0 ? rays.t_slab0 : (rays.z_bottom - o.z()) / dir.z();
  if (seg.t_slab < 0) return false;  // below the slab already: lost
  // When the ray certainly leaves the slab before the tile border (t_exit >= t_slab, decided
  // without a division: reaches_before_border), the segment ends at t_slab and a miss is lost,
  // as with the quotients; else the quotients, as Tracer::trace.
  seg.slab_first = reaches_before_border(o, dir, rays.hx, rays.hy, seg.t_slab);
  seg.t_exit = std::numeric_limits<double>::infinity();
  double tfar = seg.t_slab;
  if (!seg.slab_first) {
    seg.t_exit = distance_to_tile_border(o, dir, rays.hx, rays.hy);
    tfar = std::min(seg.t_exit + rays.margin, seg.t_slab);
  }
  rh.ray.org_x = static_cast<float>(o.x());
  rh.ray.org_y = static_cast<float>(o.y());
  rh.ray.org_z = static_cast<float>(o.z());
  rh.ray.dir_x = rays.fdir[0];
  rh.ray.dir_y = rays.fdir[1];
  rh.ray.dir_z = rays.fdir[2];
  set_ray_extent(rh.ray, tfar);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return true;
}

inline std::size_t Tracer::front_decode(const DownwardRays& rays, const Vec3& org,
                                        const RTCRayHit& rh, std::uint64_t crossings,
                                        TraceCounters& c) const {
  // Fast decoding (DownwardRays::band, graze): away from the cell's borders and diagonal the
  // grid coordinates name the triangle met, and unless the ray grazes it Ng's sign along dir
  // is the exact normal's (a front face: Ng.dir < 0).
  const double gu = static_cast<double>(rh.hit.u) * rays.cells_x;
  const double gv = static_cast<double>(rh.hit.v) * rays.cells_y;
  const long ci = static_cast<long>(gu), cj = static_cast<long>(gv);
  const double fu = gu - static_cast<double>(ci), fv = gv - static_cast<double>(cj);
  const double diag = fu + fv - 1, b = rays.band;
  const double ngx = rh.hit.Ng_x, ngy = rh.hit.Ng_y, ngz = rh.hit.Ng_z;
  const double d = ngx * rays.dir.x() + ngy * rays.dir.y() + ngz * rays.dir.z();
  if (!(fu > b && fu < 1 - b && fv > b && fv < 1 - b && std::abs(diag) > b && d < 0 &&
        d * d > rays.graze * (ngx * ngx + ngy * ngy + ngz * ngz) && !rays.exact_decode))
    return front_checked(rays, org, rh, crossings, c);
  long i = ci - rays.pad, j = cj - rays.pad;  // in [-pad, n + pad - 1] with pad <= 1: one wrap
  if (i < 0) i += rays.nx;
  else if (i >= rays.nx) i -= rays.nx;
  if (j < 0) j += rays.ny;
  else if (j >= rays.ny) j -= rays.ny;
  const int half = diag > 0 ? 1 : 0;
  ++c.rays;
  c.border_crossings += crossings;
  return rays.region ? surface_.facet_index(i, j, half)
                     : 2 * (static_cast<std::size_t>(j) * rays.nx + i) + half;
}

template <std::size_t kBatch, class Origin, class Counters, class Use>
void Tracer::front_facets(const DownwardRays& rays, std::size_t n, Origin&& origin,
                          Counters&& counters, Use&& use) const {
  static_assert(kBatch > 0 && kBatch <= 256, "a small block");
  if (!rays.lean) {
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 org = origin(i);
      use(i, front_facet(rays, org, counters(i)));
    }
    return;
  }
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  std::vector<RTCRay>* log = ray_log_of_this_thread();
  Vec3 org[kBatch];
  RTCRayHit rh[kBatch];
  bool query[kBatch];
  for (std::size_t i0 = 0; i0 < n; i0 += kBatch) {
    const std::size_t m = std::min(kBatch, n - i0);
    for (std::size_t i = 0; i < m; ++i) {  // set-up
      org[i] = origin(i0 + i);
      FrontSegment seg;
      query[i] = front_query(rays, front_origin(rays, org[i]), rh[i], seg);
    }
    for (std::size_t i = 0; i < m; ++i) {  // the queries alone
      if (!query[i]) continue;
      if (log) log->push_back(rh[i].ray);
      rtcIntersect1(scene_, &ctx, &rh[i]);
    }
    for (std::size_t i = 0; i < m; ++i) {  // decoding
      TraceCounters& c = counters(i0 + i);
      std::size_t k;
      if (!query[i]) k = front_lost(c, 0);
      else if (rh[i].hit.geomID != RTC_INVALID_GEOMETRY_ID) k = front_decode(rays, org[i], rh[i], 0, c);
      else k = front_after_miss(rays, org[i], c);
      use(i0 + i, k);
    }
  }
}

}  // namespace microsim
