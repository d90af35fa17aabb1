#include "microsim/measure/groove_models.hpp"

#include "microsim/models/vgroove_multiple.hpp"

#include <algorithm>
#include "microsim/surface/generators.hpp"

namespace microsim {

namespace {

bool is_vgroove_1d(const Microsurface& s) {
  return s.description.is_object() && s.description.value("kind", std::string()) == "vgroove" &&
         !s.description.value("two_d", false);
}

// In-plane reflected lobes of the closed forms, per slot and bin: sums of the beams' weights
// (fraction x reflectance) whose exit direction falls in the bin, and their squares per sample.
struct PlaneLobes {
  std::vector<double> sum, sum2;  // [slot * bins + b]
  std::uint64_t samples = 0;
};

void add_beams(PlaneLobes& p, const std::vector<models::GrooveBeam>& beams, const models::GrooveFrame* f,
               const InPlaneBins& plane, int K) {
  const int nb = plane.size();
  std::vector<std::pair<std::size_t, double>> here;
  for (const auto& b : beams) {
    const Vec3 d = f ? f->to_world(b.direction) : b.direction;
    if (!(d.z() > 0)) continue;
    const int bin = plane.bin_of(d);
    if (bin < 0) continue;
    const double w = b.fraction * b.reflectance;
    here.push_back({static_cast<std::size_t>(std::min(b.bounces, K) - 1) * nb + bin, w});
    here.push_back({static_cast<std::size_t>(K) * nb + bin, w});
  }
  // Squares per sample: beams of one groove landing in the same cell add before squaring.
  std::sort(here.begin(), here.end());
  for (std::size_t i = 0; i < here.size();) {
    double w = 0;
    std::size_t j = i;
    for (; j < here.size() && here[j].first == here[i].first; ++j) w += here[j].second;
    p.sum[here[i].first] += w;
    p.sum2[here[i].first] += w * w;
    i = j;
  }
  ++p.samples;
}

// The lobes of the model for this surface: a periodic V-groove's beams (exact), or Monte Carlo
// over grooves of the nominal D (slopes drawn from P22: (n.m) D(m) dm, [Heitz14, App. A]; stratified in
// the slope radius).
std::optional<PlaneLobes> groove_model_lobes(const Microsurface& s, const BsdfResult& r, const std::string& which) {
  const int K = r.options.orders, nb = r.plane.size();
  PlaneLobes p;
  p.sum.assign(static_cast<std::size_t>(K + 1) * nb, 0.0);
  p.sum2 = p.sum;
  if (which == "vgroove_multiple") {
    if (!is_vgroove_1d(s)) return std::nullopt;
    add_beams(p, models::vgroove_beams(rad(s.description.at("facet_angle_deg").get<double>()), r.wi,
                                       r.options.material),
              nullptr, r.plane, K);
    return p;
  }
  if (which == "vcavity_multiple_grooves") {
    // The ensemble's own grooves, one sample each: the exact expectation of the traced lobe (every
    // groove gets the same rays); the spread between grooves is the error of this average as an
    // estimate of the nominal model's lobe, like the albedo's reflected_stderr.
    if (!is_vcavity(s)) return std::nullopt;
    const std::size_t G = s.num_facets() / 4;
    for (std::size_t g = 0; g < G; ++g) {
      const models::GrooveFrame f(vcavity_groove_normal(s, g));
      add_beams(p, models::vgroove_beams(f.facet_angle, f.to_local(r.wi), r.options.material), &f, r.plane, K);
    }
    return p;
  }
  if (which != "vcavity_multiple" || !is_vcavity(s) || !s.nominal) return std::nullopt;
  const models::Ndf& ndf = *s.nominal;
  const std::uint64_t n = 1 << 18;
  for (std::uint64_t i = 0; i < n; ++i) {
    CounterRng rng(r.options.seed, 0x7CAF1000ull, i);
    const double u1 = (static_cast<double>(i) + rng.uniform()) / n, u2 = rng.uniform();
    const double rr = ndf.kind == models::Distribution::Beckmann ? std::sqrt(-std::log1p(-u1))
                                                                 : std::sqrt(u1 / (1 - u1));
    const Vec3 m = Vec3(-ndf.alpha_x * rr * std::cos(2 * kPi * u2), -ndf.alpha_y * rr * std::sin(2 * kPi * u2), 1.0)
                       .normalized();
    const models::GrooveFrame f(m);
    add_beams(p, models::vgroove_beams(f.facet_angle, f.to_local(r.wi), r.options.material), &f, r.plane, K);
  }
  return p;
}

}  // namespace

std::optional<std::vector<double>> groove_model_albedo(const Microsurface& s, const BsdfOptions& o,
                                                      const std::string& which,
                                                      std::vector<double>* stderr_out) {
  const Vec3 wi = direction_from_angles(o.theta_i, o.phi_i);
  const int K = o.orders;
  if (which == "vgroove_multiple") {
    if (!is_vgroove_1d(s)) return std::nullopt;
    // The ridges run along y: the world frame is the groove frame.
    return models::vgroove_albedo(rad(s.description.at("facet_angle_deg").get<double>()), wi, o.material, K);
  }
  if (!is_vcavity(s)) return std::nullopt;
  if (which == "vcavity_multiple") {
    if (!s.nominal) return std::nullopt;
    return models::vcavity_multiple_albedo(*s.nominal, wi, o.material, K);
  }
  if (which != "vcavity_multiple_grooves") return std::nullopt;
  const std::size_t G = s.num_facets() / 4;
  std::vector<double> sum(K + 1, 0.0), sum2(K + 1, 0.0);
  for (std::size_t g = 0; g < G; ++g) {
    const models::GrooveFrame f(vcavity_groove_normal(s, g));
    const std::vector<double> a = models::vgroove_albedo(f.facet_angle, f.to_local(wi), o.material, K);
    for (int k = 0; k <= K; ++k) {
      sum[k] += a[k];
      sum2[k] += a[k] * a[k];
    }
  }
  std::vector<double> mean(K + 1);
  if (stderr_out) stderr_out->assign(K + 1, 0.0);
  for (int k = 0; k <= K; ++k) {
    mean[k] = sum[k] / G;
    if (stderr_out && G > 1)
      (*stderr_out)[k] = std::sqrt(std::max(0.0, sum2[k] / G - mean[k] * mean[k]) / (G - 1));
  }
  return mean;
}

void add_groove_models(Json& j, const BsdfResult& r, const Microsurface& s) {
  const int K = r.options.orders;
  const bool dielectric = r.options.material.transmits();
  for (const std::string name : {"vgroove_multiple", "vcavity_multiple", "vcavity_multiple_grooves"}) {
    std::vector<double> se;
    const auto a = groove_model_albedo(s, r.options, name, &se);
    if (!a) {
      j["albedo_models"][name] = nullptr;
      continue;
    }
    Json refl = Json::object();
    for (int k = 0; k <= K; ++k) refl[order_key(k, K)] = (*a)[k];
    Json m = {{"reflected", refl}, {"transmitted", nullptr}};
    if (!se.empty()) {
      Json e = Json::object();
      for (int k = 0; k <= K; ++k) e[order_key(k, K)] = se[k];
      m["reflected_stderr"] = e;
    }
    if (dielectric)
      m["note"] = "dielectric: only light reflected at every bounce (refracted light is not "
                  "followed); lower bounds of the reflected orders";
    j["albedo_models"][name] = m;
    // Rows: the model beside the reflected albedo per order; z against the measurement's error
    // (and the groove average's, for the nominal V-cavity model).
    for (Json& row : j["rows"]) {
      if (row.value("side", std::string()) != "reflected") continue;
      const std::string key = row.value("order", std::string());
      int k = -1;
      for (int q = 0; q <= K; ++q)
        if (order_key(q, K) == key) k = q;
      if (k < 0) continue;
      row[name] = (*a)[k];
      if (dielectric) continue;
      double err = row.value("albedo_stderr", 0.0);
      if (name == "vcavity_multiple") {
        std::vector<double> ge;
        groove_model_albedo(s, r.options, "vcavity_multiple_grooves", &ge);
        err = std::hypot(err, ge[k]);
      }
      row["z_" + name] = err > 0 ? Json((row.value("albedo", 0.0) - (*a)[k]) / err) : Json(nullptr);
    }
  }
  // In-plane reflected lobes: f of the model per bin (total and per order), its Monte Carlo
  // error for the V-cavity average over D and the between-groove spread for the ensemble's own
  // grooves (the V-groove beams are exact deltas, binned).
  for (const std::string name : {"vgroove_multiple", "vcavity_multiple", "vcavity_multiple_grooves"}) {
    const auto lobes = groove_model_lobes(s, r, name);
    if (!lobes || !j.contains("in_plane")) continue;
    const int nb = r.plane.size();
    for (Json& row : j["in_plane"]) {
      if (row.value("side", std::string()) != "reflected") continue;
      const double psi = rad(row.value("theta_o_deg", 0.0));
      int b = static_cast<int>(std::floor((psi + 0.5 * kPi) / (kPi / nb)));
      b = std::clamp(b, 0, nb - 1);
      const double ci = r.plane.cos_integral(b);
      for (int k = 0; k <= K; ++k) {
        const Estimate e = tally_estimate(lobes->sum[k * nb + b], lobes->sum2[k * nb + b], lobes->samples, 1.0 / ci);
        const std::string key = k == K ? name : name + "_" + order_key(k, K);
        row[key] = e.mean;
        if (name != "vgroove_multiple") row[key + "_stderr"] = e.stderr_;
      }
    }
  }
}

void add_macro_normalization(Json& j, const BsdfResult& r, const Microsurface& s) {
  const Macrosurface& m = s.macro();
  Json n = {{"macro_area", m.area}};
  if (is_vcavity(s)) {
    n["kind"] = "vcavity ensemble: every groove traced on its own as an infinite periodic groove "
                "with the same number of rays; per unit macro area (the V-cavity model's)";
  } else if (m.periodic) {
    n["kind"] = "periodic tile: per unit macro area (= per unit visible area)";
  } else {
    // Rays over a window covering the projection; weight W_perp / (A cos theta_i) each.
    double w_up = 0.0;  // reflected albedo binned upward (the rest left below the base plane)
    const int K = r.options.orders;
    for (int px = 0; px < r.map.size(); ++px) w_up += r.measured.pix[r.measured.p_index(0, K, px)];
    const double total = r.measured.albedo[r.measured.a_index(0, K)];
    n["kind"] = "finite object: per unit of the flux falling on the macrosurface ([GeomBSDF24, eq. 4a] with "
                "the declared area A); a convex mirror object's total albedo is its visible area "
                "ratio. Divide by the visible area ratio for albedos per unit visible area.";
    n["reflected_below_base_plane"] = r.measured.paths ? (total - w_up) / r.measured.paths : 0.0;
  }
  j["normalization"] = n;
}

}  // namespace microsim
