// What the estimators need of a traced surface, whatever its kind: first hits and occlusion,
// its facets (area, normal, a point drawn on one), the measured region and what a ray leaving
// that region means. The kinds of Macrosurface (a periodic tile, a measured window with its
// guard band, a finite object) each get their own Scene instead of flags read by the callers;
// the tracing itself stays Tracer's (its grid fast path is private to the periodic heightfield,
// which the whole-surface G1 estimator reaches through Tracer directly).
#pragma once
#include <cstddef>
#include <memory>

#include "microsim/trace/ray_window.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

// What a ray that leaves the measured region means.
enum class RegionExit {
  Wrap,      // a periodic tile: it re-enters through the opposite border (border_crossings)
  SideExit,  // a measured heightfield window: it ends at the side wall, escaped upward or lost
             // downward (side_exits); a low ray from above enters through a side wall
             // (side_entries). The guard band keeps the bias of this rule small.
  Escape,    // a finite object: it leaves for good; a window ray beside the object is a miss
             // (lost_below counts misses there, not losses)
};

class Scene {
 public:
  static constexpr std::size_t kNoFacet = ~static_cast<std::size_t>(0);
  virtual ~Scene() = default;

  // First hit along org + t dir, t > 0, with Tracer::first_hit's rules; occluded: anything met
  // before the ray leaves the scene upward. `source`: the plane the ray leaves (or null).
  virtual TraceHit intersect(const Vec3& org, const Vec3& dir, const SourcePlane* source,
                             TraceCounters& counters, RaySide side = RaySide::Front) const = 0;
  virtual bool occluded(const Vec3& org, const Vec3& dir, const SourcePlane* source,
                        TraceCounters& counters) const = 0;
  // The scene's facet whose front face a hit met; kNoFacet for a miss, a back face (a rounding
  // gap, counted by the tracer) or a facet outside the measured region.
  virtual std::size_t front_facet(const TraceHit& h) const = 0;

  // The facets: their count, area, unit normal, and the point of facet f at (u1, u2) in
  // [0, 1)^2, uniform over its area, with the plane an occlusion ray from it leaves.
  virtual std::size_t num_facets() const = 0;
  virtual double facet_area(std::size_t f) const = 0;
  virtual Vec3 facet_normal(std::size_t f) const = 0;
  virtual Vec3 facet_point(std::size_t f, double u1, double u2) const = 0;
  virtual SourcePlane facet_plane(std::size_t f) const = 0;

  // The measured region: the window of rays along -v that covers it, and the meaning of a ray
  // leaving it.
  virtual RayWindow ray_window(const Vec3& v) const = 0;
  virtual RegionExit region_exit() const = 0;
  virtual double macro_area() const = 0;

  // The tracer the random walks run on (measure/bsdf_walk.hpp).
  virtual const Tracer& tracer() const = 0;
};

// A scene whose rays a Tracer traces as they are (the Tracer is not owned: it must outlive the
// scene, or be a member of the derived scene).
class TracedScene : public Scene {
 public:
  explicit TracedScene(const Tracer& tracer) : traced_(tracer) {}
  TraceHit intersect(const Vec3& org, const Vec3& dir, const SourcePlane* source, TraceCounters& c,
                     RaySide side = RaySide::Front) const override {
    return traced_.first_hit(org, dir, source, c, side);
  }
  bool occluded(const Vec3& org, const Vec3& dir, const SourcePlane* source,
                TraceCounters& c) const override {
    return traced_.occluded(org, dir, source, c);
  }
  const Tracer& tracer() const override { return traced_; }

 private:
  const Tracer& traced_;
};

// A scene over a whole surface's Tracer: one class per kind of surface, each with its own rule
// at the region's border. Facets are the surface's own.
class TracerScene : public TracedScene {
 public:
  explicit TracerScene(const Tracer& tracer) : TracedScene(tracer), tracer_(tracer) {}
  std::size_t front_facet(const TraceHit& h) const override;
  std::size_t num_facets() const override { return tracer_.surface().num_facets(); }
  double facet_area(std::size_t f) const override { return tracer_.surface().facet(f).area(); }
  Vec3 facet_normal(std::size_t f) const override { return tracer_.surface().facet(f).normal(); }
  Vec3 facet_point(std::size_t f, double u1, double u2) const override;
  SourcePlane facet_plane(std::size_t f) const override {
    return SourcePlane::of(tracer_.surface().facet(f));
  }
  RayWindow ray_window(const Vec3& v) const override;
  double macro_area() const override { return tracer_.surface().macro().area; }

 private:
  const Tracer& tracer_;
};

// A periodic tile (heightfield or mesh): rays wrap around.
class PeriodicTileScene : public TracerScene {
 public:
  using TracerScene::TracerScene;
  RegionExit region_exit() const override { return RegionExit::Wrap; }
};
// A measured heightfield window with its guard band: rays end at the side walls.
class HeightfieldWindowScene : public TracerScene {
 public:
  using TracerScene::TracerScene;
  RegionExit region_exit() const override { return RegionExit::SideExit; }
};
// A finite object (a closed or open mesh): rays escape past it.
class FiniteObjectScene : public TracerScene {
 public:
  using TracerScene::TracerScene;
  RegionExit region_exit() const override { return RegionExit::Escape; }
};

// The scene of a tracer's surface, of the kind its Macrosurface says.
std::unique_ptr<Scene> make_scene(const Tracer& tracer);

}  // namespace microsim
