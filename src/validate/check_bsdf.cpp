// Check of the mirror BSDF albedos (energy, single scattering, random walk, grooves).
#include "checks_common.hpp"

namespace microsim::validation {

// ---------------------------------------------------------------------------------------------
// BSDF albedos with a mirror material: total albedo = 1 (energy conservation, exact: every
// path leaves, lost and unterminated paths counted), the order-1 albedo against the
// single-scattering albedo of the nominal NDF (Smith height-correlated,
// models/microfacet_bsdf.hpp) and the per-order albedos against the Smith random walk
// (models/smith_random_walk.hpp): nominal models, so compared over an ensemble with the
// between-surface error (the walk's own error added), info rows for one surface.
const std::vector<double>& bsdf_theta() {
  static const std::vector<double> t = {30, 70};
  return t;
}

double bsdf_work(const SurfaceSet& set) {
  const double n = static_cast<double>(share_of_rays(set.options, 4));
  // Per surface and angle the measured paths (x2 for the tracing cost); the model walks once.
  return static_cast<double>(bsdf_theta().size()) *
         (2.0 * static_cast<double>(set.surfaces.size()) + (set.surfaces[0].nominal ? 1.0 : 0.0)) * n;
}

namespace {
constexpr int kMirrorOrders = 4;  // orders 1, 2, 3, 4+

// Per angle: per order (0..K, K = total) the albedo of each surface, the walk's albedo, and the
// incident direction.
struct MirrorAlbedos {
  std::vector<std::vector<std::vector<Estimate>>> albedo;
  std::vector<std::vector<Estimate>> walk;
  std::vector<Vec3> wi;
  MirrorAlbedos()
      : albedo(bsdf_theta().size(), std::vector<std::vector<Estimate>>(kMirrorOrders + 1)),
        walk(bsdf_theta().size()),
        wi(bsdf_theta().size()) {}
};

BsdfOptions mirror_bsdf_options(const Options& o, double theta_deg, bool with_walk) {
  BsdfOptions bo;
  bo.material = models::Material::mirror();
  bo.theta_i = rad(theta_deg);
  bo.orders = kMirrorOrders;
  bo.rays = share_of_rays(o, 4);
  bo.seed = o.seed;
  bo.split = o.split;
  bo.resolution = 16;
  bo.model_walks = with_walk ? bo.rays : 0;
  return bo;
}

// Surface k's mirror BSDF at angle ia: its object and energy rows into out, its albedos (and
// the walk's) into acc; returns its measurement row.
Json measure_mirror_albedo(const SurfaceSet& set, std::size_t k, std::size_t ia, const Tracer& tracer,
                           Progress& progress, CheckOutput& out, MirrorAlbedos& acc) {
  constexpr int K = kMirrorOrders;
  const Microsurface& s = set.surfaces[k];
  const std::string label = surface_label(set, k);
  const double t = bsdf_theta()[ia];
  // The walk depends only on the nominal NDF: run once, with the first surface.
  BsdfOptions bo = mirror_bsdf_options(set.options, t, s.nominal && k == 0);
  const double unit = (bo.model_walks > 0 ? 3.0 : 2.0) * static_cast<double>(bo.rays);
  bo.progress = [&](double f) { progress.update(f * unit); };
  const BsdfResult r = measure_bsdf(tracer, bo);
  progress.completed += unit;
  progress.update();
  const std::string where = (label.empty() ? "" : label + ", ") + "mirror, theta_i " + angle(t);
  const Json ang = {{"theta_i_deg", t}};
  // Finite objects against their visible area ratio; V-grooves and V-cavity ensembles
  // against the closed forms (validate/bsdf_object_rows.hpp).
  append_bsdf_object_rows(r, s, make_row(set, "", "", "", Kind::Identity, ""), where,
                          set.name, ang, out.rows);
  // Energy conservation: every path of a mirror carries weight 1 and leaves (or is lost).
  const Estimate up = r.albedo(0, K), down = r.albedo(1, K);
  Row e = albedo_total_row(r.measured.paths, r.measured.lost, r.measured.unterminated, up.mean,
                           down.mean);
  e.entry = set.name;
  e.condition = set.name + " " + where;
  e.group = set.name + "/albedo_total";
  e.extra["theta_i_deg"] = t;
  if (mirror_total_is_one(s)) out.rows.push_back(e);
  Json row = {{"theta_i_deg", t}, {"paths", r.measured.paths}, {"lost", r.measured.lost},
              {"unterminated", r.measured.unterminated}, {"albedo", Json::array()},
              {"albedo_stderr", Json::array()}};
  for (int j = 0; j <= K; ++j) {
    const Estimate a = floored(r.albedo(0, j), r.measured.paths);
    row["albedo"].push_back(a.mean);
    row["albedo_stderr"].push_back(a.stderr_);
    acc.albedo[ia][j].push_back(a);
    if (bo.model_walks > 0) acc.walk[ia].push_back(r.model_albedo(0, j));
  }
  acc.wi[ia] = r.wi;
  return row;
}

// The nominal models at angle ia against the surfaces' albedos: the order-1 albedo against the
// Smith single-scattering albedo, every order against the random walk. Returns the models'
// values for the measurement rows.
Json push_nominal_albedo_rows(const SurfaceSet& set, std::size_t ia, const MirrorAlbedos& acc,
                              CheckOutput& out) {
  constexpr int K = kMirrorOrders;
  const double t = bsdf_theta()[ia];
  const std::string where = "mirror, theta_i " + angle(t);
  const Json ang = {{"theta_i_deg", t}};
  models::MicrofacetBsdf ss;
  ss.ndf = *set.surfaces[0].nominal;
  ss.material = models::Material::mirror();
  ss.masking = models::Masking::SmithHeightCorrelated;
  const double single = models::single_scattering_albedo(ss, acc.wi[ia]).reflected;
  Row m = make_row(set, "", "albedo_order_1", "single_scattering_smith", Kind::Model,
                   "models/microfacet_bsdf.hpp single_scattering_albedo ([Heitz14, eq. 21] G2)");
  push_nominal(out, std::move(m), where, acc.albedo[ia][0], single,
               set.name + "/albedo_single_scattering", ang);
  Json mj = {{"single_scattering_model", single}, {"smith_walk_albedo", Json::array()},
             {"smith_walk_albedo_stderr", Json::array()}};
  for (int j = 0; j <= K; ++j) {
    const Estimate w = acc.walk[ia][j];
    // The walk's Monte Carlo error enters as a floor of every surface's error (it is
    // common to all K comparisons, so it is added to the mean's error below).
    Row rw = make_row(set, "", "albedo_" + order_key(j, K), "smith_random_walk", Kind::Model,
                      "models/smith_random_walk.hpp (Heitz et al. 2016), nominal NDF");
    Json ex = ang;
    ex["order"] = order_key(j, K);
    push_nominal(out, std::move(rw), where, acc.albedo[ia][j], w.mean,
                 set.name + "/albedo_smith_walk", ex);
    if (out.rows.back().stderr_) out.rows.back().stderr_ = std::hypot(*out.rows.back().stderr_, w.stderr_);
    mj["smith_walk_albedo"].push_back(w.mean);
    mj["smith_walk_albedo_stderr"].push_back(w.stderr_);
  }
  return mj;
}
}  // namespace

void check_bsdf_albedo(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  Json per_surface = Json::array();
  MirrorAlbedos acc;
  for (std::size_t k = 0; k < set.surfaces.size(); ++k) {
    Tracer tracer(set.surfaces[k]);
    Json rows = Json::array();
    for (std::size_t ia = 0; ia < bsdf_theta().size(); ++ia)
      rows.push_back(measure_mirror_albedo(set, k, ia, tracer, progress, out, acc));
    per_surface.push_back({{"label", set.labels[k]}, {"rows", rows}});
  }
  if (set.surfaces[0].nominal) {
    for (std::size_t ia = 0; ia < bsdf_theta().size(); ++ia) {
      const Json mj = push_nominal_albedo_rows(set, ia, acc, out);
      // The models beside every surface's row of this angle (as in a single-surface run).
      for (auto& ps : per_surface) ps["rows"][ia].update(mj);
    }
  }
  out.measurements = per_surface;
}

}  // namespace microsim::validation
