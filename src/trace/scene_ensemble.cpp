#include "microsim/trace/scene_ensemble.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "microsim/models/vgroove_multiple.hpp"
#include "microsim/surface/generators.hpp"

namespace microsim {

VGrooveScene::VGrooveScene(float top)
    : TracedScene(tracer_),  // bound here, used only once tracer_ is built below
      top_(top),
      surface_(Microsurface::heightfield(2, 2, 1.0, 1.0, {0.0f, top, 0.0f, top})),
      tracer_(surface_),
      plane_{SourcePlane::of(surface_.facet(0)), SourcePlane::of(surface_.facet(2))} {}

double VGrooveScene::facet_area(std::size_t side) const {
  double a = 0;  // the triangles of the cells of column `side`
  for (std::size_t f = 0; f < surface_.num_facets(); ++f)
    if ((f / 2) % 2 == side) a += surface_.facet(f).area();
  return a;
}

void SceneEnsemble::add_part(SceneFrame frame, double weight,
                             std::function<std::unique_ptr<Scene>()> build,
                             const std::vector<Vec3>& normals, const std::vector<double>& areas) {
  Part p{frame, weight, std::move(build), normal_.size(), normals.size()};
  normal_.insert(normal_.end(), normals.begin(), normals.end());
  area_.insert(area_.end(), areas.begin(), areas.end());
  parts_.push_back(std::move(p));
}

bool SceneEnsemble::equal_weights() const {
  return std::all_of(parts_.begin(), parts_.end(),
                     [&](const Part& p) { return p.weight == parts_.front().weight; });
}

std::size_t SceneEnsemble::part_at(double u) const {
  const std::size_t K = parts_.size();
  if (equal_weights())  // the common case, without a search
    return std::min<std::size_t>(K - 1, static_cast<std::size_t>(u * static_cast<double>(K)));
  double total = 0;
  for (const Part& p : parts_) total += p.weight;
  double acc = 0;
  for (std::size_t k = 0; k < K; ++k) {
    acc += parts_[k].weight;
    if (u * total < acc) return k;
  }
  return K - 1;
}

namespace {

// Groove k's frame and ridge height by one of the roundings of GrooveFrames.
struct GrooveGeometry {
  SceneFrame frame;
  float top = 0;
};
GrooveGeometry groove_geometry(const Microsurface& s, std::size_t k, const Vec3& m, GrooveFrames rule) {
  GrooveGeometry g;
  const double mh = std::hypot(m.x(), m.y());
  if (rule == GrooveFrames::OfModel) {
    const models::GrooveFrame model(vcavity_groove_normal(s, k));
    g.frame = {model.x, model.y};
    g.top = static_cast<float>(0.5 * std::tan(model.facet_angle));
    return g;
  }
  if (mh > 0)
    g.frame.x = rule == GrooveFrames::StoredNormalOverHypot ? Vec3(m.x() / mh, m.y() / mh, 0)
                                                             : Vec3(m.x(), m.y(), 0).normalized();
  g.frame.y = Vec3::UnitZ().cross(g.frame.x);
  g.top = static_cast<float>(0.5 * mh / m.z());
  return g;
}

}  // namespace

SceneEnsemble vcavity_grooves(const Microsurface& s, const char* what, GrooveFrames frames) {
  if (!is_vcavity(s) || s.num_facets() % 4 != 0)
    throw UsageError(std::string(what) + ": not a vcavity surface (generate vcavity)");
  SceneEnsemble e(s.macro().area);
  const std::size_t K = s.num_facets() / 4;
  for (std::size_t k = 0; k < K; ++k) {
    std::vector<Vec3> normals(2);
    std::vector<double> areas(2);
    for (int side = 0; side < 2; ++side) {
      const std::size_t f = 4 * k + (side == 1 ? 0 : 2);
      const Triangle a = s.facet(f), b = s.facet(f + 1);
      normals[side] = a.normal();
      areas[side] = a.area() + b.area();
    }
    const GrooveGeometry g = groove_geometry(s, k, normals[1], frames);
    const float top = g.top;
    e.add_part(g.frame, 1.0, [top] { return std::make_unique<VGrooveScene>(top); }, normals, areas);
  }
  return e;
}

}  // namespace microsim
