#include "microsim/trace/tracer.hpp"
#include "microsim/trace/tile_border.hpp"
#include "microsim/trace/facet_plane.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <new>

namespace microsim {
namespace {
// Embree context extended with the plane the ray leaves (read by the filter functions).
struct PlaneContext {
  RTCIntersectContext context;
  const SourcePlane* source;   // the plane left; null: none, or `leaving`'s not yet formed
  const SourceFacet* leaving;  // the facet left, its plane formed on demand (may be null)
  const Microsurface* surface;
  const float* grid_vertices;  // the tracer's (FacetPlanes)
  SourcePlane formed;          // leaving's plane, once formed
  double scale;
  bool back_side;              // the ray travels below the surface (RaySide::Back)
};

// For rays that leave a facet: rejects back-face hits and hits on the plane the ray leaves
// (self-intersection). The 1 - cos tolerance allows for Embree's float normals; the plane
// distance tolerance is relative to the scene scale.
void reject_source_plane(const RTCFilterFunctionNArguments* args) {
  auto* ctx = reinterpret_cast<PlaneContext*>(args->context);
  const double scale = ctx->scale;
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    Vec3 ng(RTCHitN_Ng_x(args->hit, args->N, i), RTCHitN_Ng_y(args->hit, args->N, i),
            RTCHitN_Ng_z(args->hit, args->N, i));
    const double len2 = ng.squaredNorm();  // |ng| = 0 exactly when len2 = 0
    if (len2 == 0) continue;
    Vec3 dir(RTCRayN_dir_x(args->ray, args->N, i), RTCRayN_dir_y(args->ray, args->N, i),
             RTCRayN_dir_z(args->ray, args->N, i));
    // A ray leaving the surface enters the solid through a front face first; a back face
    // first means its float origin rounded to just below a neighbouring facet (concave edge).
    // A ray travelling inside the solid (Back side) leaves it through a back face first.
    if (ctx->back_side ? ng.dot(dir) < 0 : ng.dot(dir) > 0) {
      args->valid[i] = 0;
      continue;
    }
    if (!ctx->source && !ctx->leaving) continue;
    // Not parallel to the plane left (|ng.n| / |ng| < 1 - 1e-6): kept. Nearly every candidate
    // is decided on squares (not_parallel_clearly), with the reported normal of the facet left
    // when its plane is not formed; the rest by the quotient with the plane's own normal.
    double a = std::abs(ng.dot(ctx->source ? ctx->source->normal : ctx->leaving->normal));
    if (not_parallel_clearly(a, len2, ctx->source ? 0.0 : kReportedNormalSlack)) continue;
    if (!ctx->source) {
      ctx->formed = FacetPlanes(*ctx->surface, ctx->grid_vertices).plane(ctx->leaving->facet);
      ctx->source = &ctx->formed;
      a = std::abs(ng.dot(ctx->source->normal));
    }
    if (not_parallel_exactly(a, len2)) continue;
    float t = RTCRayN_tfar(args->ray, args->N, i);
    Vec3 p(RTCRayN_org_x(args->ray, args->N, i) + t * RTCRayN_dir_x(args->ray, args->N, i),
           RTCRayN_org_y(args->ray, args->N, i) + t * RTCRayN_dir_y(args->ray, args->N, i),
           RTCRayN_org_z(args->ray, args->N, i) + t * RTCRayN_dir_z(args->ray, args->N, i));
    if (std::abs(ctx->source->normal.dot(p) - ctx->source->offset) < 1e-5 * scale)
      args->valid[i] = 0;
  }
}

thread_local std::vector<RTCRay>* ray_log = nullptr;

void throw_on_embree_error(RTCDevice device, const char* what) {
  RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE)
    throw RuntimeFailure(std::string("Embree error while ") + what + " (code " +
                         std::to_string(static_cast<int>(e)) + ")");
}

}  // namespace

// The heightfield as an Embree grid, its vertices in a mapping of their own (with the periodic
// copy of one cell around the tile, none for a measured window).
RTCGeometry Tracer::new_grid_geometry() {
  const Microsurface& surface = surface_;
  const Macrosurface& macro = surface.macro();
  RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_GRID);
  if (!macro.periodic) {  // a measured window: its own vertices only, no periodic copy
    window_ = true;
    pad_ = 0;
    foot_x0_ = surface.grid_point(0, 0).x();
    foot_y0_ = surface.grid_point(0, 0).y();
    foot_x1_ = surface.grid_point(surface.traced_cells_x(), 0).x();
    foot_y1_ = surface.grid_point(0, surface.traced_cells_y()).y();
  }
  grid_width_ = surface.traced_cells_x() + 1 + 2 * pad_;
  grid_height_ = surface.traced_cells_y() + 1 + 2 * pad_;
  // The vertex buffer in a mapping of its own, advised to use transparent huge pages: a ray
  // reads the three vertex rows of its grid leaf, a row apart (12 bytes per vertex), so on a
  // large tile each ray otherwise costs three TLB misses besides its cache misses (Embree's
  // `hugepages` option covers its own allocations, not a geometry's buffers). 16 bytes of
  // padding: Embree may read the last vertex with a 16-byte load.
  const std::size_t nverts = static_cast<std::size_t>(grid_width_) * grid_height_;
  vertex_bytes_ = 3 * sizeof(float) * nverts + 16;
  vertex_pages_ = mmap(nullptr, vertex_bytes_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS,
                       -1, 0);
  if (vertex_pages_ == MAP_FAILED) {
    vertex_pages_ = nullptr;
    rtcReleaseGeometry(geom);
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
    throw std::bad_alloc();
  }
#ifdef MADV_HUGEPAGE
  madvise(vertex_pages_, vertex_bytes_, MADV_HUGEPAGE);  // a hint: no huge pages is no error
#endif
  auto* v = static_cast<float*>(vertex_pages_);
  rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, v, 0,
                             3 * sizeof(float), nverts);
  grid_vertices_ = v;
  double height_sum = 0;
  for (int j = 0; j < grid_height_; ++j)
    for (int i = 0; i < grid_width_; ++i) {
      Vec3 p = surface.grid_point(i - pad_, j - pad_);
      float* q = v + 3 * (static_cast<std::size_t>(j) * grid_width_ + i);
      q[0] = static_cast<float>(p.x());
      q[1] = static_cast<float>(p.y());
      q[2] = static_cast<float>(p.z());
      height_sum += q[2];
    }
  mean_height_ = height_sum / (static_cast<double>(grid_width_) * grid_height_);
  auto* g = static_cast<RTCGrid*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_GRID, 0,
                                                          RTC_FORMAT_GRID, sizeof(RTCGrid), 1));
  g->startVertexID = 0;
  g->stride = grid_width_;
  g->width = static_cast<unsigned short>(grid_width_);
  g->height = static_cast<unsigned short>(grid_height_);
  return geom;
}

// The mesh as Embree triangles (with the copies of a periodic mesh's border triangles).
RTCGeometry Tracer::new_mesh_geometry() {
  const Macrosurface& macro = surface_.macro();
  RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
  const auto& verts = surface_.vertices();
  const auto& tris = surface_.triangles();
  // Periodic meshes: add copies, shifted by one tile, of the triangles near the borders so
  // that a ray crossing a border meets interior geometry (no hit lost to rounding there).
  std::vector<Eigen::Vector3f> vout(verts);
  std::vector<std::array<std::uint32_t, 3>> tout(tris);
  for (std::uint32_t k = 0; k < tris.size(); ++k) mesh_prim_to_facet_.push_back(k);
  if (macro.periodic) {
    const double mx = 0.05 * macro.size_x, my = 0.05 * macro.size_y;
    for (int sx = -1; sx <= 1; ++sx)
      for (int sy = -1; sy <= 1; ++sy) {
        if (sx == 0 && sy == 0) continue;
        Eigen::Vector3f shift(sx * macro.size_x, sy * macro.size_y, 0);
        for (std::uint32_t k = 0; k < tris.size(); ++k) {
          Eigen::AlignedBox3f tb;
          for (auto id : tris[k]) tb.extend(verts[id] + shift);
          if (tb.max().x() < -0.5 * macro.size_x - mx || tb.min().x() > 0.5 * macro.size_x + mx ||
              tb.max().y() < -0.5 * macro.size_y - my || tb.min().y() > 0.5 * macro.size_y + my)
            continue;
          std::array<std::uint32_t, 3> t{};
          for (int c = 0; c < 3; ++c) {
            t[c] = static_cast<std::uint32_t>(vout.size());
            vout.push_back(verts[tris[k][c]] + shift);
          }
          tout.push_back(t);
          mesh_prim_to_facet_.push_back(k);
        }
      }
  }
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vout.size() + 1));
  for (std::size_t k = 0; k < vout.size(); ++k)
    for (int c = 0; c < 3; ++c) v[3 * k + c] = vout[k][c];
  auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), tout.size()));
  for (std::size_t k = 0; k < tout.size(); ++k)
    for (int c = 0; c < 3; ++c) idx[3 * k + c] = tout[k][c];
  return geom;
}

Tracer::Tracer(const Microsurface& surface) : surface_(surface) {
  auto t0 = std::chrono::steady_clock::now();
  // Huge pages (transparent, by madvise) for the BVH and vertices: on large tiles every ray
  // touches leaves no earlier ray touched, and 4 KiB pages then cost a TLB miss per node.
  device_ = rtcNewDevice("hugepages=1");
  if (!device_) throw RuntimeFailure("cannot create an Embree device");
  scene_ = rtcNewScene(device_);
  // ROBUST: without it a few rays per million slip through shared edges (docs/theory/numerics.md).
  // Context filter: only rays that leave a facet pay for the filter; primary rays run bare.
  // COMPACT (heightfields): the grid's BVH in about half the memory (5 instead of 10 bytes
  // per facet at 4096^2), for a few percent of speed.
  const bool grid = surface.kind() == Microsurface::Kind::Heightfield;
  rtcSetSceneFlags(scene_, static_cast<RTCSceneFlags>(
                               RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION |
                               (grid ? RTC_SCENE_FLAG_COMPACT : 0)));
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);

  const Macrosurface& macro = surface.macro();
  Eigen::AlignedBox3d box = surface.bounds();
  RTCGeometry geom = grid ? new_grid_geometry() : new_mesh_geometry();
  static_assert(sizeof(double) == 8, "");
  scale_ = std::max({box.sizes().maxCoeff(), macro.size_x, macro.size_y});
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene_, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene_);
  throw_on_embree_error(device_, "building the scene");

  // The slab that holds all geometry; a little margin so that its faces are never tangent.
  const double eps = 1e-6 * scale_;
  z_top_ = box.max().z() + eps;
  z_bottom_ = box.min().z() - eps;
  build_seconds_ =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Tracer::~Tracer() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
  if (vertex_pages_) munmap(vertex_pages_, vertex_bytes_);
}

namespace {
// Unnormalised normal (cross product) of facet `half` of a cell with corner heights h00, h10,
// h01, h11: facet 0 = (v00, v10, v01), facet 1 = (v10, v11, v01); see Microsurface::facet.
inline Vec3 cell_cross_of(double h00, double h10, double h01, double h11, int half, double dx,
                          double dy) {
  if (half == 0) return Vec3(-(h10 - h00) * dy, -(h01 - h00) * dx, dx * dy);
  return Vec3(-(h11 - h01) * dy, -(h11 - h10) * dx, dx * dy);
}
inline long wrap_index(long i, long n) {
  while (i < 0) i += n;
  while (i >= n) i -= n;
  return i;
}
// cos^2 of the angle between c and ng, sign kept.
inline double alignment_of(const Vec3& c, const Vec3& ng) {
  const double d = c.dot(ng);
  return (d > 0 ? 1 : -1) * d * d / (c.squaredNorm() * ng.squaredNorm());
}
}  // namespace

bool Tracer::grid_facet_guess(float u, float v, const Vec3& ng, long& i, long& j, int& half,
                              Vec3& c) const {
  // Grid hits report u, v normalised over the whole grid: the cell and its half follow.
  const double gu = static_cast<double>(u) * (grid_width_ - 1);
  const double gv = static_cast<double>(v) * (grid_height_ - 1);
  // Truncation is the floor for u, v >= 0 (nearly always; without a call to floor()).
  const long ci = gu >= 0 ? static_cast<long>(gu) : static_cast<long>(std::floor(gu));
  const long cj = gv >= 0 ? static_cast<long>(gv) : static_cast<long>(std::floor(gv));
  half = (gu - ci) + (gv - cj) < 1.0 ? 0 : 1;
  i = ci - pad_;
  j = cj - pad_;
  if (window_) {
    i = std::min(std::max(i, 0L), static_cast<long>(surface_.traced_cells_x()) - 1);
    j = std::min(std::max(j, 0L), static_cast<long>(surface_.traced_cells_y()) - 1);
  }
  const double dx = surface_.dx(), dy = surface_.dy();
  // The cell's corner heights from Embree's own vertices when it is inside the grid (the same
  // floats as the heights, and in cache: the traversal just read them); else from the heights.
  const long gi = i + pad_, gj = j + pad_;
  if (gi >= 0 && gj >= 0 && gi + 1 < grid_width_ && gj + 1 < grid_height_) {
    const float* row0 = grid_vertices_ + 3 * (static_cast<std::size_t>(gj) * grid_width_ + gi);
    const float* row1 = row0 + 3 * static_cast<std::size_t>(grid_width_);
    c = cell_cross_of(row0[2], row0[5], row1[2], row1[5], half, dx, dy);
  } else {
    const long nx = surface_.nx(), ny = surface_.ny();
    const std::vector<float>& h = surface_.heights();
    const long i0 = wrap_index(i, nx), j0 = wrap_index(j, ny);
    const long i1 = wrap_index(i0 + 1, nx), j1 = wrap_index(j0 + 1, ny);
    c = cell_cross_of(h[j0 * nx + i0], h[j0 * nx + i1], h[j1 * nx + i0], h[j1 * nx + i1], half,
                      dx, dy);
  }
  // alignment_of(c, ng) > 1 - 2e-6, without its division.
  const double d = c.dot(ng);
  return d > 0 && d * d > (1 - 2e-6) * (c.squaredNorm() * ng.squaredNorm());
}

std::size_t Tracer::facet_of_hit(unsigned prim_id, float u, float v, const Vec3& ng,
                                 Vec3* normal) const {
  if (surface_.kind() == Microsurface::Kind::Mesh) {
    std::size_t k = mesh_prim_to_facet_[prim_id];
    if (normal) *normal = surface_.facet(k).normal();
    return k;
  }
  // At cell borders float rounding can name a neighbour; the facet's own normal must then
  // match Ng, else search the cells around for the facet that does.
  const long nx = surface_.nx(), ny = surface_.ny();
  const std::vector<float>& h = surface_.heights();
  const double dx = surface_.dx(), dy = surface_.dy();
  auto cell_cross = [&](long i, long j, int hf) {
    long i0 = wrap_index(i, nx), j0 = wrap_index(j, ny);
    long i1 = wrap_index(i0 + 1, nx), j1 = wrap_index(j0 + 1, ny);
    return cell_cross_of(h[j0 * nx + i0], h[j0 * nx + i1], h[j1 * nx + i0], h[j1 * nx + i1], hf,
                         dx, dy);
  };
  auto index = [&](long i, long j, int hf) {
    return surface_.facet_index(wrap_index(i, nx), wrap_index(j, ny), hf);
  };
  // A window has no periodic neighbours: cells outside it are never candidates.
  const long cx = surface_.traced_cells_x(), cy = surface_.traced_cells_y();
  auto exists = [&](long i, long j) { return !window_ || (i >= 0 && i < cx && j >= 0 && j < cy); };
  long i, j;
  int half;
  Vec3 c;
  if (grid_facet_guess(u, v, ng, i, j, half, c)) {
    if (normal) *normal = c.normalized();
    return index(i, j, half);
  }
  double best_align = -2;
  std::size_t best = 0;
  for (long dj = -1; dj <= 1; ++dj)
    for (long di = -1; di <= 1; ++di)
      for (int hf = 0; hf < 2; ++hf) {
        if (!exists(i + di, j + dj)) continue;
        Vec3 cc = cell_cross(i + di, j + dj, hf);
        double a = alignment_of(cc, ng);
        if (a > best_align) {
          best_align = a;
          best = index(i + di, j + dj, hf);
          c = cc;
        }
      }
  if (normal) *normal = c.normalized();
  return best;
}

// The state of one ray of Tracer::trace, carried from segment to segment.
struct Tracer::RayState {
  Vec3 o;                  // the segment's origin
  const Vec3& dir;
  double hx, hy;           // half the tile
  bool back;               // RaySide::Back
  bool side_entry = false;  // entered a window through a side wall inside the slab
  double margin = -1;      // past the tile border (border_margin), formed when first needed
  // The segment: distances to the slab face it heads for and to the tile border (or the
  // window's footprint), and the query's extent.
  double t_slab = 0, t_exit = 0, tfar = 0;
};

namespace {

// The filter and plane of Tracer::trace's queries: a ray leaving a plane or facet, or
// travelling inside the solid, has its wrong-side and self-intersection hits rejected.
inline void init_plane_context(PlaneContext& ctx, const SourcePlane* source, const SourceFacet* leaving,
                               const Microsurface& surface, const float* grid_vertices, double scale,
                               bool back) {
  rtcInitIntersectContext(&ctx.context);
  ctx.source = source;
  ctx.leaving = source ? nullptr : leaving;
  ctx.surface = &surface;
  ctx.grid_vertices = grid_vertices;
  ctx.scale = scale;
  ctx.back_side = back;
  if (source || leaving || back) ctx.context.filter = reject_source_plane;
}

// The float ray of a segment from o along dir, [0, tfar].
inline void set_segment_ray(RTCRay& ray, const Vec3& o, const Vec3& dir, double tfar) {
  ray.org_x = static_cast<float>(o.x());
  ray.org_y = static_cast<float>(o.y());
  ray.org_z = static_cast<float>(o.z());
  ray.dir_x = static_cast<float>(dir.x());
  ray.dir_y = static_cast<float>(dir.y());
  ray.dir_z = static_cast<float>(dir.z());
  set_ray_extent(ray, tfar);
}

// A ray that leaves the slab downward: a ray inside the solid is transmitted (exit_below),
// any other is lost. Upward it has escaped: nothing to count.
inline void leave_slab(const Vec3& dir, bool back, TraceCounters& c, TraceHit* out) {
  if (dir.z() < 0) {
    if (back && out) out->exit_below = true;
    else ++c.lost_below;
  }
}

}  // namespace

// Beyond the tile border a ray may travel this far inside the padded copy before it is cut
// (half a cell), so a hit exactly on the border is found inside the geometry.
inline double Tracer::border_margin(const Vec3& dir) const {
  const Macrosurface& macro = surface_.macro();
  double dxy = std::max(std::abs(dir.x()), std::abs(dir.y()));
  double cell = surface_.kind() == Microsurface::Kind::Heightfield
                    ? std::min(surface_.dx(), surface_.dy())
                    : 0.02 * std::min(macro.size_x, macro.size_y);
  return dxy > 0 ? 0.5 * cell / dxy : 0.0;
}

// Window: distance along the ray from p to where it leaves the footprint (+inf if it never does).
inline double Tracer::footprint_exit(const Vec3& p, const Vec3& dir) const {
  double t = std::numeric_limits<double>::infinity();
  if (dir.x() > 0) t = std::min(t, (foot_x1_ - p.x()) / dir.x());
  if (dir.x() < 0) t = std::min(t, (foot_x0_ - p.x()) / dir.x());
  if (dir.y() > 0) t = std::min(t, (foot_y1_ - p.y()) / dir.y());
  if (dir.y() < 0) t = std::min(t, (foot_y0_ - p.y()) / dir.y());
  return std::max(t, 0.0);
}

// A window's ray starts where it enters the footprint (rays from above the guard band start
// outside it when they are long enough); false for one that never enters (nothing to meet).
// A ray that enters through a side wall below the surface there meets the solid from behind
// first: a miss (the side-wall rule), not the convex-edge graze of take_hit.
bool Tracer::enter_window(RayState& r, TraceCounters& c) const {
  Vec3& o = r.o;
  const Vec3& dir = r.dir;
  double t_in = 0, t_out = std::numeric_limits<double>::infinity();
  const double lo[2] = {foot_x0_, foot_y0_}, hi[2] = {foot_x1_, foot_y1_};
  for (int a = 0; a < 2; ++a) {
    if (dir[a] == 0) {
      if (o[a] < lo[a] || o[a] > hi[a]) t_out = -1;
      continue;
    }
    double t0 = (lo[a] - o[a]) / dir[a], t1 = (hi[a] - o[a]) / dir[a];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  if (!(t_in <= t_out)) {
    ++c.side_exits;
    return false;
  }
  if (t_in > 0) {
    o += t_in * dir;
    for (int a = 0; a < 2; ++a) o[a] = std::min(std::max(o[a], lo[a]), hi[a]);
    if (o.z() < z_top_) {  // entered through a side wall, inside the slab
      ++c.side_entries;
      r.side_entry = true;
    }
  }
  return true;
}

// The segment from r.o: its slab and border distances and the query's extent; false when the
// ray is already outside the slab and moving away from it.
inline bool Tracer::segment_extent(RayState& r) const {
  const Vec3& o = r.o;
  const Vec3& dir = r.dir;
  const bool periodic = surface_.macro().periodic;
  r.t_slab = std::numeric_limits<double>::infinity();
  if (dir.z() > 0) r.t_slab = (z_top_ - o.z()) / dir.z();
  if (dir.z() < 0) r.t_slab = (z_bottom_ - o.z()) / dir.z();
  if (r.t_slab < 0) return false;
  // On a periodic tile a segment that certainly leaves the slab before the tile border (most:
  // the slab is a few cells thick) ends at t_slab whatever the border distance and margin
  // are (t_exit >= t_slab): neither is formed (tile_border.hpp, reaches_before_border).
  r.t_exit = std::numeric_limits<double>::infinity();
  r.tfar = r.t_slab;
  if (!(periodic && reaches_before_border(o, dir, r.hx, r.hy, r.t_slab))) {
    if (periodic) {
      r.t_exit = distance_to_tile_border(o, dir, r.hx, r.hy);
    } else if (window_) {
      r.t_exit = footprint_exit(o, dir);
    }
    if (!window_ && r.margin < 0) r.margin = border_margin(dir);
    r.tfar = std::min(r.t_exit + (window_ ? 0.0 : r.margin), r.t_slab);
  }
  return true;
}

// The hit Embree reported for the segment, into *out (the facet's copy inside the tile, its
// exact normal, the side met); false for a downward ray from above a heightfield that grazed a
// convex edge (a back face first): the caller traces the segment again with wrong-side hits
// rejected.
inline bool Tracer::take_hit(const RTCRayHit& rh, const RayState& r, bool filtered,
                             TraceCounters& c, TraceHit* out) const {
  const Macrosurface& macro = surface_.macro();
  const Vec3& dir = r.dir;
  Vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  out->hit = true;
  out->point = r.o + static_cast<double>(rh.ray.tfar) * dir;
  if (macro.periodic) {  // canonical copy: inside the tile, like the facet reported
    if (out->point.x() >= r.hx) out->point.x() -= macro.size_x;
    else if (out->point.x() < -r.hx) out->point.x() += macro.size_x;
    if (out->point.y() >= r.hy) out->point.y() -= macro.size_y;
    else if (out->point.y() < -r.hy) out->point.y() += macro.size_y;
  }
  out->facet = facet_of_hit(rh.hit.primID, rh.hit.u, rh.hit.v, ng, &out->normal);
  out->backface = out->normal.dot(dir) > 0;
  if (out->backface && !filtered && !r.back && dir.z() < 0 && !r.side_entry &&
      surface_.kind() == Microsurface::Kind::Heightfield) {
    // A downward ray from above a heightfield meets the graph from above first, so a back
    // face first means it grazed a convex edge (a V-groove's ridge) closer than float spacing:
    // it passes over it. (Finite objects seen from below legitimately see back faces first:
    // the undersurface.)
    *out = TraceHit();
    return false;
  }
  if (out->backface != r.back) ++c.backface_hits;
  return true;
}

// After a segment that met nothing: true when the ray goes on through the opposite tile border
// (r.o moved there), false when it ended (left the slab, a window's side wall, a finite object).
inline bool Tracer::cross_border(RayState& r, TraceCounters& c, TraceHit* out) const {
  const Macrosurface& macro = surface_.macro();
  if (r.t_slab <= r.t_exit) {
    // Leaves the slab inside this tile: upward it escapes; downward it was lost, or, for a
    // ray inside the solid, it leaves through the bottom (transmitted).
    leave_slab(r.dir, r.back, c, out);
    return false;
  }
  if (window_) {  // reached a side wall inside the slab: ends here (see first_hit)
    ++c.side_exits;
    return false;
  }
  if (!macro.periodic) return false;
  // Move to the border and re-enter through the opposite side (both at a corner).
  r.o += r.t_exit * r.dir;
  reenter_opposite_side(r.o, r.dir, macro);
  ++c.border_crossings;
  return true;
}

template <bool kOcclusion>
bool Tracer::trace(const Vec3& org, const Vec3& dir, const SourcePlane* source,
                   const SourceFacet* leaving, TraceCounters& c, TraceHit* out, RaySide side) const {
  ++c.rays;
  const Macrosurface& macro = surface_.macro();
  const bool back = side == RaySide::Back;
  PlaneContext ctx;
  init_plane_context(ctx, source, leaving, surface_, grid_vertices_, scale_, back);
  RayState r{org, dir, 0.5 * macro.size_x, 0.5 * macro.size_y, back};
  if (macro.periodic && surface_.kind() == Microsurface::Kind::Heightfield) {
    // An origin off the tile (a measured region's ray window reaches past it): its periodic copy.
    Vec3& o = r.o;
    if (o.x() < -r.hx || o.x() > r.hx) o.x() -= macro.size_x * std::floor((o.x() + r.hx) / macro.size_x);
    if (o.y() < -r.hy || o.y() > r.hy) o.y() -= macro.size_y * std::floor((o.y() + r.hy) / macro.size_y);
  }
  if (window_ && !enter_window(r, c)) return false;
  const int max_segments = 100000;
  for (int segment = 0; segment < max_segments; ++segment) {
    if (!segment_extent(r)) {
      leave_slab(dir, back, c, out);
      return false;
    }
    RTCRayHit rh;
    set_segment_ray(rh.ray, r.o, dir, r.tfar);
    if (ray_log) ray_log->push_back(rh.ray);
    if (kOcclusion) {
      rtcOccluded1(scene_, &ctx.context, &rh.ray);
      if (rh.ray.tfar < 0) return true;  // Embree marks occlusion with tfar = -inf
    } else {
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene_, &ctx.context, &rh);
      if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
        if (take_hit(rh, r, ctx.context.filter != nullptr, c, out)) return true;
        ctx.context.filter = reject_source_plane;  // the grazed edge: this segment again
        --segment;
        continue;
      }
    }
    if (!cross_border(r, c, out)) return false;
  }
  ++c.unresolved;
  return false;
}

DownwardRays::DownwardRays(const Tracer& tracer, const Vec3& v) {
  if (!(v.z() > 0)) throw UsageError("DownwardRays: v must point above the macrosurface");
  dir = -v;  // as given (a unit vector): the very direction first_hit(org, -v, ...) traces
  for (int a = 0; a < 3; ++a) fdir[a] = static_cast<float>(dir[a]);
  const Microsurface& s = tracer.surface();
  lean = s.kind() == Microsurface::Kind::Heightfield && s.macro().periodic && !tracer.window_;
  // As Tracer::trace: how far past the tile border a ray may travel in the padded copy.
  const double dxy = std::max(std::abs(dir.x()), std::abs(dir.y()));
  margin = dxy > 0 ? 0.5 * std::min(s.dx(), s.dy()) / dxy : 0.0;
  run_x = dir.x() / -dir.z();
  run_y = dir.y() / -dir.z();
  if (!lean) return;
  z0 = tracer.z_top_;
  z_bottom = tracer.z_bottom_;
  t_slab0 = (z_bottom - z0) / dir.z();  // as front_query divides it
  nx = s.nx();
  ny = s.ny();
  pad = tracer.pad_;
  hx = 0.5 * s.macro().size_x;
  hy = 0.5 * s.macro().size_y;
  region = s.macro().region;
  cells_x = tracer.grid_width_ - 1;
  cells_y = tracer.grid_height_ - 1;
  // Embree reports a grid hit as u = fl(fl(s + a) r), s the quad's column, a in [0, 1] its
  // barycentric coordinate in the triangle (a 1 - a' in the second one), r = rcp(cells_x)
  // refined by one Newton step (relative error < 2^-22), and a = U rcp(U + V + W) with U, V,
  // W of one sign; likewise v. So u cells_x = s + a within cells_x (2^-24 + 2^-22 + 2^-24)
  // + 2^-22 cells, and a within 2^-22 of [0, 1], a + b within 2^-21 of [0, 1] (first
  // triangle) or [1, 2] (second). Four times that: outside the band the cell and half
  // named are the triangle Embree met.
  band = std::ldexp(std::max(cells_x, cells_y) + 2, -20);
  // Embree's Ng is the cross product of float edges relative to the float origin: vertices
  // up to L away (the longest segment plus a cell) are rounded to 2^-24 L, and its float x, y
  // to 2^-24 of the tile, against edges at least a cell long: Ng is within 2^-22 ((L + tile) /
  // cell + 1) of the facet's exact normal; four times that is the grazing limit.
  const Macrosurface& m = s.macro();
  const double cell = std::min(s.dx(), s.dy()), tile = std::max(m.size_x, m.size_y);
  const double longest = std::min(t_slab0, dxy > 0 ? 2 * (m.size_x + m.size_y) / dxy + margin
                                                   : std::numeric_limits<double>::infinity()) +
                         2 * (s.dx() + s.dy());
  const double delta = std::ldexp((longest + tile) / cell + 1, -20);
  graze = delta * delta;
}

std::size_t Tracer::prefetch_front(const DownwardRays& rays, const Vec3& org) const {
  if (!rays.lean) return DownwardRays::kNone;
  // Where the ray crosses the mean height, in grid vertex coordinates of the padded grid.
  const double drop = org.z() - mean_height_;
  const Macrosurface& macro = surface_.macro();
  double x = org.x() + drop * rays.run_x + 0.5 * macro.size_x;
  double y = org.y() + drop * rays.run_y + 0.5 * macro.size_y;
  x -= macro.size_x * std::floor(x / macro.size_x);
  y -= macro.size_y * std::floor(y / macro.size_y);
  // Embree's grid leaves are 3 x 3 vertex blocks starting at even indices: the leaf's rows.
  const long nx = surface_.nx(), ny = surface_.ny();
  const long ci = std::min(static_cast<long>(x / surface_.dx()), nx - 1);
  const long cj = std::min(static_cast<long>(y / surface_.dy()), ny - 1);
  const long gi = (ci + pad_) & ~1L, gj = (cj + pad_) & ~1L;
  if (gi + 2 < grid_width_ && gj + 2 < grid_height_) {
    const float* p = grid_vertices_ + 3 * (static_cast<std::size_t>(gj) * grid_width_ + gi);
    const std::size_t row = 3 * static_cast<std::size_t>(grid_width_);
    for (int r = 0; r < 3; ++r, p += row) {
      __builtin_prefetch(p);
      __builtin_prefetch(p + 8);  // the block's 9 floats may straddle a cache line
    }
  }
  return macro.region ? surface_.facet_index(ci, cj, 0)
                      : 2 * (static_cast<std::size_t>(cj) * nx + ci);
}

void Tracer::prefetch_cells(long i0, long i1, long j) const {
  if (!grid_vertices_) return;
  // Embree's grid leaves are 3 x 3 vertex blocks starting at even indices: the leaves' rows.
  const long gi0 = (i0 + pad_) & ~1L, gi1 = std::min<long>(i1 + pad_ + 2, grid_width_ - 1);
  const long gj = (j + pad_) & ~1L;
  if (gi0 > gi1 || gj + 2 >= grid_height_) return;
  const std::size_t row = 3 * static_cast<std::size_t>(grid_width_);
  const float* p = grid_vertices_ + 3 * (static_cast<std::size_t>(gj) * grid_width_);
  for (int r = 0; r < 3; ++r, p += row)
    for (long g = 3 * gi0; g <= 3 * gi1 + 2; g += 16) __builtin_prefetch(p + g);  // 64-byte lines
  // (the last line of each row when the step above skipped it)
  for (int r = 0; r < 3; ++r) __builtin_prefetch(grid_vertices_ + 3 * ((gj + r) * static_cast<std::size_t>(grid_width_) + gi1) + 2);
}

// Tracer::trace<false> for a Front ray without source plane on a periodic heightfield, step for
// step (the same float queries, so the same Embree answers), reduced to the facet met. The
// common case (one segment, a hit decoded from Embree's grid coordinates) is the inline
// front_query and front_decode (tracer.hpp); the rest is in the cold functions below.
std::size_t Tracer::front_facet(const DownwardRays& rays, const Vec3& org, TraceCounters& c) const {
  if (!rays.lean) {
    const TraceHit h = first_hit(org, rays.dir, nullptr, c);
    return h.hit && !h.backface ? h.facet : DownwardRays::kNone;
  }
  RTCRayHit rh;
  FrontSegment seg;
  if (!front_query(rays, front_origin(rays, org), rh, seg)) return front_lost(c, 0);
  if (ray_log) ray_log->push_back(rh.ray);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcIntersect1(scene_, &ctx, &rh);
  if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) return front_decode(rays, org, rh, 0, c);
  return front_after_miss(rays, org, c);
}

std::size_t Tracer::front_lost(TraceCounters& c, std::uint64_t crossings) {
  ++c.rays;
  c.border_crossings += crossings;
  ++c.lost_below;
  return DownwardRays::kNone;
}

std::vector<RTCRay>* Tracer::ray_log_of_this_thread() { return ray_log; }

// The checked decoding: the facet whose exact normal is aligned with Ng (the neighbours
// searched when the grid coordinates named the wrong one), the back face from that normal.
[[gnu::cold]] [[gnu::noinline]] std::size_t Tracer::front_checked(
    const DownwardRays& rays, const Vec3& org, const RTCRayHit& rh, std::uint64_t crossings,
    TraceCounters& c) const {
  const Vec3& dir = rays.dir;
  const Vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  const long nx = rays.nx, ny = rays.ny;
  long i, j;
  int half;
  Vec3 cr;
  std::size_t facet;
  bool backface;
  if (grid_facet_guess(rh.hit.u, rh.hit.v, ng, i, j, half, cr)) {
    // Back face: m.dir > 0 for the unit normal m = cr / |cr|. Unless the unnormalised dot is
    // within rounding of zero its sign is that of the normalised one (no square root).
    const double dc = cr.dot(dir);
    const double scale = std::abs(cr.x() * dir.x()) + std::abs(cr.y() * dir.y()) +
                         std::abs(cr.z() * dir.z());
    backface = std::abs(dc) > 1e-12 * scale ? dc > 0 : cr.normalized().dot(dir) > 0;
    const long wi = wrap_index(i, nx), wj = wrap_index(j, ny);
    facet = rays.region ? surface_.facet_index(wi, wj, half)
                        : 2 * (static_cast<std::size_t>(wj) * nx + wi) + half;
  } else {
    Vec3 m;
    facet = facet_of_hit(rh.hit.primID, rh.hit.u, rh.hit.v, ng, &m);
    backface = m.dot(dir) > 0;
  }
  if (backface) {
    // Grazed a convex edge closer than float spacing: first_hit traces the segment again with
    // wrong-side hits rejected. Rare; it is taken from the start with its own counts.
    const TraceHit h = first_hit(org, dir, nullptr, c);
    return h.hit && !h.backface ? h.facet : DownwardRays::kNone;
  }
  ++c.rays;
  c.border_crossings += crossings;
  return facet;
}

// The ray from org missed in its first segment: that segment's distances again (the same
// arithmetic, no query), then its further segments, as Tracer::trace.
[[gnu::cold]] [[gnu::noinline]] std::size_t Tracer::front_after_miss(const DownwardRays& rays,
                                                                   const Vec3& org,
                                                                   TraceCounters& c) const {
  const Macrosurface& macro = surface_.macro();
  Vec3 o = front_origin(rays, org);
  RTCRayHit rh;
  FrontSegment seg;
  front_query(rays, o, rh, seg);  // answered already: a miss
  std::uint64_t crossings = 0;
  const int max_segments = 100000;
  for (int segment = 0;;) {
    if (seg.slab_first || seg.t_slab <= seg.t_exit) break;  // left the slab inside the tile: lost
    // Move to the border and re-enter through the opposite side (both at a corner).
    o += seg.t_exit * rays.dir;
    reenter_opposite_side(o, rays.dir, macro);
    ++crossings;
    if (++segment == max_segments) {
      ++c.rays;
      c.border_crossings += crossings;
      ++c.unresolved;
      return DownwardRays::kNone;
    }
    if (!front_query(rays, o, rh, seg)) break;  // below the slab: lost
    if (ray_log) ray_log->push_back(rh.ray);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(scene_, &ctx, &rh);
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) return front_decode(rays, org, rh, crossings, c);
  }
  return front_lost(c, crossings);
}

void Tracer::log_rays_on_this_thread(std::vector<RTCRay>* log) { ray_log = log; }

TraceHit Tracer::first_hit(const Vec3& org, const Vec3& dir, const SourcePlane* source,
                           TraceCounters& counters, RaySide side) const {
  TraceHit h;
  trace<false>(org, dir, source, nullptr, counters, &h, side);
  return h;
}

TraceHit Tracer::first_hit(const Vec3& org, const Vec3& dir, const SourceFacet& source,
                           TraceCounters& counters, RaySide side) const {
  TraceHit h;
  trace<false>(org, dir, nullptr, &source, counters, &h, side);
  return h;
}

bool Tracer::occluded(const Vec3& org, const Vec3& dir, const SourcePlane* source,
                      TraceCounters& counters) const {
  return trace<true>(org, dir, source, nullptr, counters, nullptr);
}

}  // namespace microsim
