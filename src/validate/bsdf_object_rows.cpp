#include "microsim/validate/bsdf_object_rows.hpp"

#include <algorithm>
#include <cmath>

#include "microsim/measure/groove_models.hpp"
#include "microsim/measure/stats.hpp"
#include "microsim/surface/generators.hpp"

namespace microsim::validation {

namespace {

// The visible area ratio of a finite object seen from l, when geometry gives it exactly.
std::optional<double> visible_area_ratio(const Microsurface& s, const Vec3& l, std::string* how) {
  const std::string kind = s.description.value("kind", std::string());
  const double ct = l.z(), st = std::sqrt(std::max(0.0, 1.0 - ct * ct));
  const double cp = std::abs(l.x()) / std::max(st, 1e-300), sp = std::abs(l.y()) / std::max(st, 1e-300);
  if (kind == "box" || kind == "tiled-boxes") {
    const double W = s.description.at("width").get<double>(), D = s.description.at("depth").get<double>();
    const double H = s.description.at("height").get<double>();
    const int N = s.description.value("tiles", 1);
    *how = "1 + (H/N) tan(theta) (|cos phi|/W + |sin phi|/D) [GeomBSDF24, Fig. 5-6]";
    return 1.0 + (H / N) * (st / ct) * (cp / W + sp / D);
  }
  if (kind == "ellipsoid" || (kind == "parallelepiped" && s.description.value("tiles", 1) == 1)) {
    *how = "convex object: sum_f A_f max(0, l.m_f) / (A cos theta) from the facets";
    return front_projected_area(s, l) / (s.macro().area * ct);
  }
  return std::nullopt;
}

Row complete(Row r, const std::string& quantity, const std::string& model_name, Kind kind,
             const std::string& reference, const std::string& where, double measured, double se,
             double model, const std::string& group, const Json& extra) {
  r.quantity = quantity;
  r.model_name = model_name;
  r.kind = kind;
  r.reference = reference;
  r.condition += " " + where;
  r.measured = measured;
  r.stderr_ = se;
  r.model = model;
  r.error = "rays";
  r.group = group;
  r.extra = extra;
  return r;
}

}  // namespace

bool mirror_total_is_one(const Microsurface& s) { return s.macro().periodic || is_vcavity(s); }

void append_bsdf_object_rows(const BsdfResult& r, const Microsurface& s, const Row& proto,
                             const std::string& where, const std::string& group,
                             const Json& extra, std::vector<Row>& rows) {
  const int K = r.options.orders;
  const bool opaque = !r.options.material.transmits();
  if (!mirror_total_is_one(s) && r.options.material.kind == models::MaterialKind::Mirror) {
    std::string how;
    if (const auto ratio = visible_area_ratio(s, r.wi, &how)) {
      const Estimate a = r.albedo(0, K);
      Row row = complete(proto, "albedo_total", "visible_area_ratio", Kind::Identity, how, where,
                         a.mean, a.stderr_, *ratio, group + "/albedo_visible_area_ratio", extra);
      row.extra["lost"] = r.measured.lost;
      rows.push_back(std::move(row));
    }
  }
  if (!opaque) return;  // the closed forms do not follow refracted light
  struct Model {
    const char* name;
    Kind kind;
    const char* reference;
  };
  const Model models[] = {
      {"vgroove_multiple", Kind::Identity, "models/vgroove_multiple.hpp: 2D unfolding of the groove"},
      {"vcavity_multiple_grooves", Kind::Identity,
       "models/vgroove_multiple.hpp over the ensemble's own grooves"},
      {"vcavity_multiple", Kind::Model,
       "V-cavity multiple scattering of the nominal D ([Heitz14, Sec. 6]; Xie and Hanrahan 2018)"}};
  std::vector<double> groove_se;
  for (const Model& m : models) {
    const auto a = groove_model_albedo(s, r.options, m.name,
                                       std::string(m.name) == "vcavity_multiple_grooves" ? &groove_se : nullptr);
    if (!a) continue;
    for (int k = 0; k <= K; ++k) {
      const Estimate e = r.albedo(0, k);
      double se = e.stderr_;
      if (std::string(m.name) == "vcavity_multiple" && !groove_se.empty()) se = std::hypot(se, groove_se[k]);
      if (!(se > 0) && std::abs(e.mean - (*a)[k]) < 1e-9) continue;  // nothing to test (empty order)
      // A fraction of n paths (weights <= 1 on tiles and grooves) resolves no better than
      // ~0.7/n: an order no path reached has that error, not zero (stats.hpp proportion_floor).
      se = std::max(se, proportion_floor(r.measured.paths));
      Row row = complete(proto, "albedo_" + order_key(k, K), m.name, m.kind, m.reference, where,
                         e.mean, se, (*a)[k], group + "/albedo_" + m.name, extra);
      row.extra["order"] = order_key(k, K);
      if (std::string(m.name) == "vcavity_multiple") row.error = "rays and grooves";
      rows.push_back(std::move(row));
    }
  }
}

}  // namespace microsim::validation
