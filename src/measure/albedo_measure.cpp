#include "microsim/measure/albedo_measure.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "microsim/measure/bsdf_record.hpp"
#include "microsim/models/metals.hpp"
#include "microsim/models/ndf.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const char* const kSideName[2] = {"reflected", "transmitted"};

// Mean over independent runs weighted by their paths; the errors combine in quadrature.
Estimate combine_runs(const std::vector<std::pair<Estimate, std::uint64_t>>& runs) {
  double n = 0, sum = 0, var = 0;
  for (const auto& [e, paths] : runs) {
    const double w = static_cast<double>(paths);
    n += w;
    sum += w * e.mean;
    var += w * w * e.stderr_ * e.stderr_;
  }
  Estimate out;
  if (n <= 0) return out;
  out.mean = sum / n;
  out.stderr_ = std::sqrt(var) / n;
  out.n = static_cast<std::uint64_t>(n);
  return out;
}

std::vector<std::string> order_names(int orders) {
  std::vector<std::string> out;
  for (int k = 0; k <= orders; ++k) out.push_back(order_key(k, orders));
  return out;
}

}  // namespace

double nominal_alpha(const Microsurface& s) {
  if (!s.nominal) return kNaN;
  return s.nominal->isotropic() ? s.nominal->alpha_x : std::sqrt(s.nominal->alpha_x * s.nominal->alpha_y);
}

// ---------------------------------------------------------------------------------------------
// Measurement

namespace {
// The runs of node t (the nominal azimuth and the turned ones).
std::vector<const BsdfResult*> node_runs(const BsdfTable& table, std::size_t t) {
  std::vector<const BsdfResult*> runs = {&table.at(0, static_cast<int>(t))};
  if (!table.turned.empty())
    for (const BsdfResult& r : table.turned[t]) runs.push_back(&r);
  return runs;
}

AlbedoNode albedo_node(const BsdfTable& table, std::size_t t, int orders) {
  AlbedoNode n;
  n.theta_i_deg = deg(table.theta_i[t]);
  n.mu = std::cos(table.theta_i[t]);
  const auto runs = node_runs(table, t);
  for (int sd = 0; sd < 2; ++sd)
    for (int k = 0; k <= orders; ++k) {
      std::vector<std::pair<Estimate, std::uint64_t>> parts;
      for (const BsdfResult* r : runs) parts.push_back({r->albedo(sd, k), r->measured.paths});
      n.side[sd].push_back(combine_runs(parts));
    }
  std::vector<std::pair<Estimate, std::uint64_t>> parts;
  for (const BsdfResult* r : runs) {
    const BsdfTally& m = r->measured;
    // R + T per path is the path's weight when it leaves: its own error (both2).
    parts.push_back({m.estimate(m.albedo[m.a_index(0, orders)] + m.albedo[m.a_index(1, orders)], m.both2), m.paths});
    n.paths += m.paths;
    n.lost += m.lost;
    n.unterminated += m.unterminated;
  }
  n.total = combine_runs(parts);
  return n;
}
}  // namespace

AlbedoSurface measure_albedo(const Microsurface& s, const std::string& file, const AlbedoOptions& o,
                             const std::function<void(double)>& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  const MuQuadrature& q = o.quadrature;
  AlbedoSurface out;
  out.file = file;
  out.description = s.description;
  out.nominal = s.nominal;
  out.alpha = nominal_alpha(s);
  out.orders = o.orders;
  const bool anisotropic = s.nominal && !s.nominal->isotropic();
  out.azimuths = o.azimuths > 0 ? o.azimuths : (anisotropic ? kAnisotropicAlbedoAzimuths : 1);
  if (o.rays < static_cast<long long>(out.azimuths) * o.replicates)
    throw ParameterError("{rays} must be at least {replicates} per azimuth (" +
                         std::to_string(out.azimuths * o.replicates) + " for " + std::to_string(out.azimuths) +
                         " azimuths; got " + std::to_string(o.rays) + ")");
  BsdfTableOptions to;
  to.base.material = o.material;
  out.transmits = to.base.material.transmits();
  to.base.orders = o.orders;
  to.base.rays = static_cast<std::uint64_t>(o.rays);
  to.base.seed = o.seed;
  to.base.resolution = 1;  // the albedo needs no map: one pixel, one in-plane bin
  to.base.replicates = o.replicates;
  to.base.max_events = o.max_events;
  to.base.models = false;
  to.base.model_walks = 0;
  for (double mu : q.mu) to.theta_i.push_back(std::acos(std::min(1.0, mu)));
  to.phi_i = {rad(o.phi_i_deg)};
  to.table_azimuths = out.azimuths;
  if (progress) to.progress = progress;
  const BsdfTable table = measure_bsdf_table(Tracer(s), to);
  for (std::size_t t = 0; t < q.mu.size(); ++t) {
    out.nodes.push_back(albedo_node(table, t, o.orders));
    out.nodes.back().mu = q.mu[t];  // the node exactly (not cos(acos(mu)))
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

std::vector<std::string> albedo_series(int orders, bool transmits) {
  std::vector<std::string> out = {"albedo"};
  for (int sd = 0; sd < (transmits ? 2 : 1); ++sd)
    for (const std::string& k : order_names(orders)) out.push_back(std::string(kSideName[sd]) + "_" + k);
  return out;
}

std::vector<Estimate> albedo_series_values(const AlbedoSurface& s, const std::string& name) {
  std::vector<Estimate> out;
  const std::vector<std::string> keys = order_names(s.orders);
  for (const AlbedoNode& n : s.nodes) {
    if (name == "albedo") {
      out.push_back(n.total);
      continue;
    }
    bool found = false;
    for (int sd = 0; sd < 2 && !found; ++sd)
      for (int k = 0; k <= s.orders && !found; ++k)
        if (name == std::string(kSideName[sd]) + "_" + keys[k]) {
          out.push_back(n.side[sd][k]);
          found = true;
        }
    if (!found) throw ParameterError("unknown albedo series '" + literal_text(name) + "'");
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Tables and record

Table albedo_nodes_spec(int orders, bool transmits) {
  Table t;
  t.error = ErrorKind::Replicates;
  const ErrorKind R = ErrorKind::Replicates, N = ErrorKind::None;
  t.spec.columns = {
      {"surface", Merge::Key, N, "", "the surface file (the lookup table's row)"},
      {"alpha", Merge::Copy, N, "1",
       "the surface's nominal roughness: alpha, or sqrt(alpha_x alpha_y) when anisotropic (null without a nominal NDF)"},
      {"mu", Merge::Key, N, "1", "the quadrature node mu = cos theta_i (the lookup table's column)"},
      {"theta_i_deg", Merge::Copy, N, "deg", "incidence zenith angle, acos(mu)"},
      {"weight", Merge::Copy, N, "1", "quadrature weight W_j of the node: E_avg = sum_j W_j E(mu_j)"},
      {"albedo", Merge::Measured, R, "1",
       "E(mu): fraction of the incident power leaving the surface (reflected plus transmitted), all orders"}};
  for (int sd = 0; sd < (transmits ? 2 : 1); ++sd)
    for (int k = 0; k <= orders; ++k) {
      const std::string slot = k == orders       ? std::string("all orders")
                               : k == orders - 1 ? "orders " + std::to_string(orders) + " and above"
                                                 : "order " + std::to_string(k + 1);
      t.spec.columns.push_back({std::string(kSideName[sd]) + "_" + order_key(k, orders), Merge::Measured, R, "1",
                                std::string("fraction of the incident power ") + (sd == 0 ? "reflected" : "transmitted") +
                                    " after " + slot});
    }
  t.spec.columns.push_back({"albedo_average", Merge::Copy, N, "1",
                            "E_avg = 2 int_0^1 E(mu) mu dmu of the row's surface (the same in each of its rows)"});
  t.spec.columns.push_back({"albedo_average_stderr", Merge::Copy, N, "1",
                            "statistical error of albedo_average, sqrt(sum_j W_j^2 se_j^2)"});
  t.spec.columns.push_back({"albedo_average_quadrature_error", Merge::Copy, N, "1",
                            "estimated quadrature error of albedo_average, |Q - Q_low| (null without a lower-order rule)"});
  t.spec.row_fields = {
      {"paths", Merge::Copy, N, "", "random walks started at the node (over every azimuth)"},
      {"lost_fraction", Merge::Copy, N, "1",
       "fraction of the walks that ended without leaving (tracer loss, wrong-side hit)"},
      {"unterminated_fraction", Merge::Copy, N, "1", "fraction of the walks cut at max_events scattering events"},
      {"azimuths", Merge::Copy, N, "", "incidence azimuths averaged (rays split evenly)"}};
  return t;
}

Table albedo_average_spec() {
  Table t;
  t.error = ErrorKind::Replicates;
  const ErrorKind R = ErrorKind::Replicates, N = ErrorKind::None;
  t.spec.columns = {
      {"surface", Merge::Key, N, "", "the surface file"},
      {"alpha", Merge::Copy, N, "1", "the surface's nominal roughness (as in rows)"},
      {"series", Merge::Key, N, "",
       "which E is averaged: albedo (all orders, both sides), or <side>_<order slot> as in rows"},
      {"average", Merge::Measured, R, "1",
       "2 int_0^1 E(mu) mu dmu by the quadrature (sum_j W_j E(mu_j)); its stderr: sqrt(sum_j W_j^2 se_j^2)"},
      {"quadrature_error", Merge::Copy, N, "1",
       "|Q - Q_low|: the lower-order rule's difference, an overestimate of the quadrature error (null "
       "without a lower-order rule)"},
      {"quadrature_error_noise", Merge::Copy, N, "1",
       "the standard error of Q - Q_low from the nodes' errors: a quadrature_error near it is noise"},
      {"low_rule_average", Merge::Copy, N, "1", "Q_low, the lower-order rule's value"}};
  return t;
}

namespace {
Json number_or_null(double x) { return std::isfinite(x) ? Json(x) : Json(nullptr); }
}  // namespace

Table albedo_nodes_table(const std::vector<AlbedoSurface>& surfaces, const MuQuadrature& q) {
  const int K = surfaces.empty() ? 4 : surfaces[0].orders;
  const bool transmits = !surfaces.empty() && surfaces[0].transmits;
  Table t = albedo_nodes_spec(K, transmits);
  const std::vector<std::string> keys = order_names(K);
  for (const AlbedoSurface& s : surfaces) {
    const AlbedoAverage avg = average_albedo(q, albedo_series_values(s, "albedo"));
    for (std::size_t j = 0; j < s.nodes.size(); ++j) {
      const AlbedoNode& n = s.nodes[j];
      Json row;
      row["surface"] = s.file;
      row["alpha"] = number_or_null(s.alpha);
      row["mu"] = n.mu;
      row["theta_i_deg"] = n.theta_i_deg;
      row["weight"] = q.weight[j];
      row["albedo"] = n.total.mean;
      row["albedo_stderr"] = n.total.stderr_;
      for (int sd = 0; sd < (s.transmits ? 2 : 1); ++sd)
        for (int k = 0; k <= K; ++k) {
          const std::string name = std::string(kSideName[sd]) + "_" + keys[k];
          row[name] = n.side[sd][k].mean;
          row[name + "_stderr"] = n.side[sd][k].stderr_;
        }
      row["albedo_average"] = avg.value;
      row["albedo_average_stderr"] = avg.stderr_;
      row["albedo_average_quadrature_error"] = number_or_null(avg.quadrature_error);
      const double paths = static_cast<double>(n.paths);
      row["paths"] = n.paths;
      row["lost_fraction"] = paths > 0 ? static_cast<double>(n.lost) / paths : 0.0;
      row["unterminated_fraction"] = paths > 0 ? static_cast<double>(n.unterminated) / paths : 0.0;
      row["azimuths"] = s.azimuths;
      t.rows.push_back(row);
    }
  }
  return t;
}

Table albedo_average_table(const std::vector<AlbedoSurface>& surfaces, const MuQuadrature& q) {
  Table t = albedo_average_spec();
  for (const AlbedoSurface& s : surfaces)
    for (const std::string& series : albedo_series(s.orders, s.transmits)) {
      const AlbedoAverage a = average_albedo(q, albedo_series_values(s, series));
      Json row;
      row["surface"] = s.file;
      row["alpha"] = number_or_null(s.alpha);
      row["series"] = series;
      row["average"] = a.value;
      row["average_stderr"] = a.stderr_;
      row["quadrature_error"] = number_or_null(a.quadrature_error);
      row["quadrature_error_noise"] = number_or_null(a.quadrature_error_noise);
      row["low_rule_average"] = number_or_null(a.low_rule_value);
      t.rows.push_back(row);
    }
  return t;
}

namespace {
// The quadrature in mu: its nodes (also as theta_i), weights and the lower-order rule.
Json albedo_quadrature_json(const MuQuadrature& q) {
  Json quad = {{"rule", q.rule}, {"nodes", q.mu.size()}, {"mu", q.mu}, {"weight", q.weight},
               {"low_rule_weight", q.low_weight}, {"has_low_rule", q.has_low_rule},
               {"description", q.description()}};
  std::vector<double> theta;
  for (double mu : q.mu) theta.push_back(deg(std::acos(std::min(1.0, mu))));
  quad["theta_i_deg"] = theta;
  return quad;
}

// What the record's fields mean.
Json albedo_definitions_json() {
  return {
      {"albedo", "E(mu), the directional albedo at mu = cos theta_i: the fraction of the incident power that "
                 "leaves the surface, reflected plus (a dielectric) transmitted, all scattering orders; a "
                 "conductor's paths carry the product of their Fresnel factors, a dielectric chooses "
                 "reflection with probability F (unpolarized light). For a mirror E = 1 - (lost + "
                 "unterminated paths) / paths: the white furnace test. *_stderr: standard error of the mean "
                 "of `replicates` independent stratified replicates of the node's walks"},
      {"reflected_order_n", "the same for the paths that leave upward after exactly n events (order_Kplus: K "
                            "or more; total: all orders); transmitted_*: leaving downward (a dielectric)"},
      {"albedo_average", "E_avg = 2 int_0^1 E(mu) mu dmu = sum_j W_j E(mu_j) by the quadrature named in "
                         "quadrature (the albedo under uniform illumination); stderr sqrt(sum_j W_j^2 se_j^2): "
                         "the nodes are independent runs (own counter streams)"},
      {"quadrature_error", "|Q - Q_low|, Q_low a lower-order rule on every other node of the same measured "
                           "values: the lower rule's error, an overestimate of Q's; quadrature_error_noise is "
                           "its standard error from the nodes' errors"},
      {"azimuths", "incidence azimuths phi_i + 360 a / N degrees averaged at each node (N = 1 for an "
                   "isotropic surface unless given; rays split evenly, errors combined in quadrature)"},
      {"alpha", "the row's nominal roughness from the surface's metadata: alpha, or sqrt(alpha_x alpha_y) for "
                "an anisotropic NDF"}};
}

// One surface's summary: file, description, nominal NDF and roughness, path counts, time.
Json albedo_surface_json(const AlbedoSurface& s) {
  std::uint64_t paths = 0, lost = 0, unterminated = 0;
  for (const AlbedoNode& n : s.nodes) paths += n.paths, lost += n.lost, unterminated += n.unterminated;
  Json ndf = nullptr;
  if (s.nominal)
    ndf = {{"distribution", s.nominal->kind == models::Distribution::GGX ? "ggx" : "beckmann"},
           {"alpha_x", s.nominal->alpha_x},
           {"alpha_y", s.nominal->alpha_y}};
  return {{"file", s.file},
          {"surface", s.description},
          {"nominal_ndf", ndf},
          {"alpha", number_or_null(s.alpha)},
          {"azimuths", s.azimuths},
          {"paths", paths},
          {"lost_paths", lost},
          {"unterminated_paths", unterminated},
          {"seconds", s.seconds}};
}
}  // namespace

void put_albedo_results(Json& j, const MuQuadrature& q, const std::vector<AlbedoSurface>& surfaces) {
  j["quadrature"] = albedo_quadrature_json(q);
  j["definitions"] = albedo_definitions_json();
  Json per_surface = Json::array();
  for (const AlbedoSurface& s : surfaces) per_surface.push_back(albedo_surface_json(s));
  j["surfaces"] = per_surface;
  j["rows"] = albedo_nodes_table(surfaces, q).rows;
  j["averages"] = albedo_average_table(surfaces, q).rows;
}

ExrTable albedo_lut_exr(const MuQuadrature& q, const std::vector<AlbedoSurface>& surfaces, const std::string& material,
                        long long rays, int orders) {
  ExrTable t;
  t.width = static_cast<int>(q.mu.size());
  t.height = static_cast<int>(surfaces.size());
  const std::size_t px = static_cast<std::size_t>(t.width) * t.height;
  auto add = [&](const std::string& name) {
    t.channel_names.push_back(name);
    t.channels.emplace_back(px, 0.0f);
    return t.channels.size() - 1;
  };
  const std::size_t e = add("E"), se = add("E_stderr"), avg = add("E_avg"), avg_se = add("E_avg_stderr"),
                    avg_q = add("E_avg_quadrature_error");
  const int K = surfaces.empty() ? orders : surfaces[0].orders;
  const bool transmits = !surfaces.empty() && surfaces[0].transmits;
  std::vector<std::string> series = albedo_series(K, transmits);
  series.erase(series.begin());  // "albedo" is E itself
  std::vector<std::size_t> value_ch, error_ch;
  for (const std::string& name : series) {
    value_ch.push_back(add(name));
    error_ch.push_back(add(name + "_stderr"));
  }
  std::vector<double> alphas, averages, average_errors, quadrature_errors;
  for (std::size_t row = 0; row < surfaces.size(); ++row) {
    const AlbedoSurface& s = surfaces[row];
    const std::vector<Estimate> E = albedo_series_values(s, "albedo");
    const AlbedoAverage a = average_albedo(q, E);
    alphas.push_back(s.alpha);
    averages.push_back(a.value);
    average_errors.push_back(a.stderr_);
    quadrature_errors.push_back(a.quadrature_error);
    for (std::size_t col = 0; col < q.mu.size(); ++col) {
      const std::size_t i = row * q.mu.size() + col;
      t.channels[e][i] = static_cast<float>(E[col].mean);
      t.channels[se][i] = static_cast<float>(E[col].stderr_);
      t.channels[avg][i] = static_cast<float>(a.value);
      t.channels[avg_se][i] = static_cast<float>(a.stderr_);
      t.channels[avg_q][i] = static_cast<float>(a.quadrature_error);
    }
    for (std::size_t c = 0; c < series.size(); ++c) {
      const std::vector<Estimate> v = albedo_series_values(s, series[c]);
      for (std::size_t col = 0; col < q.mu.size(); ++col) {
        t.channels[value_ch[c]][row * q.mu.size() + col] = static_cast<float>(v[col].mean);
        t.channels[error_ch[c]][row * q.mu.size() + col] = static_cast<float>(v[col].stderr_);
      }
    }
  }
  std::vector<std::string> files;
  for (const AlbedoSurface& s : surfaces) files.push_back(s.file);
  Json alpha_json = Json::array();
  for (double a : alphas) alpha_json.push_back(number_or_null(a));
  Json qe = Json::array();
  for (double x : quadrature_errors) qe.push_back(number_or_null(x));
  t.attributes = {{"microsim_table", "albedo_lut"},
                  {"layout", "rows (y): surfaces in the order given, nominal alpha in attribute alpha; columns (x): "
                             "mu nodes, increasing, in attribute mu; E_avg* channels repeat the row's value in every "
                             "column"},
                  {"mu", q.mu},
                  {"alpha", alpha_json},
                  {"surfaces", files},
                  {"quadrature", q.description()},
                  {"quadrature_weight", q.weight},
                  {"material", material},
                  {"E_avg", averages},
                  {"E_avg_stderr", average_errors},
                  {"E_avg_quadrature_error", qe},
                  {"rays_per_node", static_cast<double>(rays)},
                  {"orders", orders}};
  return t;
}

}  // namespace microsim
