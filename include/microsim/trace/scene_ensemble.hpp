// An ensemble scene: parts of ONE surface, each traced on its own as a scene in its own frame
// (the grooves of a V-cavity, [Heitz14, Sec. 6.1]). The parts' tallies add up to the surface's
// tallies and the errors come from the rays (replicates or binomial counts), as for any single
// scene. Not to be confused with K independent surfaces (or tiles) of one generator measured
// separately and merged record by record (measure/shards.hpp, api/merge): there each surface
// is a sample and the error is the spread between surfaces, with Student t on K - 1 degrees of
// freedom.
#pragma once
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "microsim/surface/microsurface.hpp"
#include "microsim/trace/scene.hpp"

namespace microsim {

// A rotation about the macro normal: a part's own frame (x, y horizontal, z shared).
struct SceneFrame {
  Vec3 x = Vec3::UnitX(), y = Vec3::UnitY();
  Vec3 to_local(const Vec3& w) const { return Vec3(w.dot(x), w.dot(y), w.z()); }
  Vec3 to_world(const Vec3& w) const { return w.x() * x + w.y() * y + w.z() * Vec3::UnitZ(); }
};

// One infinite periodic V-groove in its own frame: one period x in [-1/2, 1/2] per unit tile,
// the ridge along y, the surface z = top (1 - 2|x|). Two facets: side 0 (x < 0) and side 1
// (x > 0). Traced as a periodic 2 x 2 heightfield (Tracer).
class VGrooveScene : public TracedScene {
 public:
  explicit VGrooveScene(float top);
  std::size_t front_facet(const TraceHit& h) const override {
    return h.hit && !h.backface ? (h.facet / 2) % 2 : kNoFacet;  // the cell's column is the side
  }
  std::size_t num_facets() const override { return 2; }
  double facet_area(std::size_t side) const override;
  Vec3 facet_normal(std::size_t side) const override { return plane_[side].normal; }
  Vec3 facet_point(std::size_t side, double u, double w) const override {
    const double x = (side == 1 ? 0.5 : -0.5) * u;
    return Vec3(x, w - 0.5, top_ * (1 - 2 * std::abs(x)));
  }
  SourcePlane facet_plane(std::size_t side) const override { return plane_[side]; }
  RayWindow ray_window(const Vec3& v) const override {
    return {Vec3(-0.5, -0.5, tracer_.z_top()), Vec3::UnitX(), Vec3::UnitY(), std::abs(v.z())};
  }
  RegionExit region_exit() const override { return RegionExit::Wrap; }
  double macro_area() const override { return 1.0; }

 private:
  float top_;
  Microsurface surface_;
  Tracer tracer_;  // of surface_ (so the scene is neither copied nor moved)
  SourcePlane plane_[2];
};

class SceneEnsemble {
 public:
  // Part k: its frame, its share of the macro area, how to build its scene (one at a time: a
  // part's Embree scene lives while it is traced) and its facets in the world frame (normals
  // and areas, in the order of its scene's facets).
  struct Part {
    SceneFrame frame;
    double weight = 1;
    std::function<std::unique_ptr<Scene>()> build;
    std::size_t first_facet = 0, facets = 0;
  };
  explicit SceneEnsemble(double macro_area) : macro_area_(macro_area) {}
  void add_part(SceneFrame frame, double weight, std::function<std::unique_ptr<Scene>()> build,
                const std::vector<Vec3>& normals, const std::vector<double>& areas);

  std::size_t parts() const { return parts_.size(); }
  const Part& part(std::size_t k) const { return parts_[k]; }
  std::unique_ptr<Scene> build(std::size_t k) const { return parts_[k].build(); }
  // The facets of every part, part after part: facet f of part k is first_facet + f.
  std::size_t num_facets() const { return normal_.size(); }
  const Vec3& facet_normal(std::size_t j) const { return normal_[j]; }
  double facet_area(std::size_t j) const { return area_[j]; }
  double macro_area() const { return macro_area_; }
  // Every part covers the same share of the macro area.
  bool equal_weights() const;
  // The part that u in [0, 1) picks with probability weight / total weight.
  std::size_t part_at(double u) const;

 private:
  double macro_area_;
  std::vector<Part> parts_;
  std::vector<Vec3> normal_;
  std::vector<double> area_;
};

// The grooves of a vcavity surface (surface/generators.hpp, is_vcavity; UsageError naming
// `what` otherwise): groove k is a VGrooveScene of unit area whose side 1 is the stored
// facets 4k, 4k+1 (normal m_k) and side 0 the facets 4k+2, 4k+3 (m'_k). The frame of groove k
// has x along the horizontal part of m_k and the ridge height top = tan(theta_k) / 2. It is
// rounded in one of three ways, the same frame to the last bits, each kept so that its
// estimator's records stay bit for bit: from the stored m_k divided by the hypotenuse of its
// horizontal part (G1), from the stored m_k's normalized horizontal part (G2, the VNDF), or
// from the V-groove model's GrooveFrame of vcavity_groove_normal (the random walk, whose exits
// are compared with that model).
enum class GrooveFrames { StoredNormalOverHypot, StoredNormalNormalized, OfModel };
SceneEnsemble vcavity_grooves(const Microsurface& s, const char* what,
                              GrooveFrames frames);

}  // namespace microsim
