#include "ensemble.hpp"

#include <cmath>

#include "microsim/measure/stats.hpp"

namespace microsim::cli {

std::pair<double, double> ensemble_stat(const std::vector<const Json*>& rows, const std::string& key) {
  double sum = 0, sum2 = 0;
  int k = 0;
  for (const Json* r : rows) {
    auto it = r->find(key);
    if (it == r->end() || !it->is_number()) continue;
    double x = it->get<double>();
    sum += x;
    sum2 += x * x;
    ++k;
  }
  if (k == 0) return {0.0, 0.0};
  double mean = sum / k;
  double var = k > 1 ? std::max(0.0, (sum2 - k * mean * mean) / (k - 1)) : 0.0;
  return {mean, std::sqrt(var / k)};
}

Json ensemble_p_value(const Json& z, std::size_t surfaces) {
  if (!z.is_number() || surfaces < 2) return nullptr;
  return student_t_two_sided_p(z.get<double>(), static_cast<double>(surfaces - 1));
}

namespace {
void apply(Json& out, const std::vector<const Json*>& rows, const FieldSpec& spec) {
  for (const auto& [key, how] : spec) {
    switch (how) {
      case Field::Copy:
      case Field::Key:
        out[key] = (*rows[0]).contains(key) ? (*rows[0])[key] : Json(nullptr);
        break;
      case Field::Count:
        out[key] = rows.size();
        out["t_dof"] = rows.size() - 1;
        break;
      case Field::Measured:
      case Field::MeanStderr:
      case Field::Mean: {
        bool any = false;
        for (const Json* r : rows) any = any || (r->contains(key) && (*r)[key].is_number());
        if (!any) {  // no surface has a value (e.g. an empty bin): null, not a made-up 0
          out[key] = nullptr;
          if (how != Field::Mean) out[key + "_stderr"] = nullptr;
          if (how == Field::Measured) out[key + "_stderr_rays"] = nullptr;
          break;
        }
        auto [mean, se] = ensemble_stat(rows, key);
        out[key] = mean;
        if (how == Field::Mean) break;
        out[key + "_stderr"] = se;
        if (how == Field::MeanStderr) break;
        double rays2 = 0;
        for (const Json* r : rows) {
          auto it = r->find(key + "_stderr");
          if (it != r->end() && it->is_number()) rays2 += std::pow(it->get<double>(), 2);
        }
        out[key + "_stderr_rays"] = std::sqrt(rays2) / rows.size();
        break;
      }
      case Field::Normal: {
        Vec3 m = Vec3::Zero();
        for (const Json* r : rows) {
          const Json& a = (*r)[key];
          m += Vec3(a[0].get<double>(), a[1].get<double>(), a[2].get<double>());
        }
        if (m.norm() > 0) m.normalize();
        out[key] = {m.x(), m.y(), m.z()};
        break;
      }
    }
  }
}
}  // namespace

Json ensemble_row(const std::vector<const Json*>& rows, const FieldSpec& row_fields,
                  const FieldSpec& bin_fields) {
  Json e;
  apply(e, rows, row_fields);
  if (bin_fields.empty()) return e;
  Json bins = Json::array();
  for (const auto& b0 : (*rows[0])["bins"]) {
    std::vector<const Json*> same;
    for (const Json* r : rows)
      for (const auto& b : (*r)["bins"]) {
        bool match = true;
        for (const auto& [key, how] : bin_fields)
          if (how == Field::Key && b[key] != b0[key]) match = false;
        if (match) same.push_back(&b);
      }
    Json eb;
    apply(eb, same, bin_fields);
    eb["surfaces"] = same.size();
    bins.push_back(eb);
  }
  e["bins"] = bins;
  return e;
}

}  // namespace microsim::cli

#include "cli_common.hpp"

namespace microsim::cli {

std::vector<Json> measure_over_surfaces(
    const GlobalOptions& g, const std::vector<std::string>& files,
    const std::function<Json(const Microsurface&, std::size_t)>& measure) {
  std::vector<Microsurface> first;
  first.push_back(input_surface(g, files.at(0)));
  for (std::size_t k = 1; k < files.size(); ++k) input_surface(g, files[k]);
  std::vector<Json> rows;
  for (std::size_t k = 0; k < files.size(); ++k) {
    Microsurface s = k == 0 ? std::move(first[0]) : input_surface(g, files[k]);
    rows.push_back(measure(s, k));
  }
  return rows;
}

void put_rows(Json& j, const std::vector<std::string>& files, const std::vector<Json>& per_surface,
              const std::function<Json(const std::vector<const Json*>&)>& combine) {
  if (files.size() == 1) {
    j["rows"] = per_surface[0];
    return;
  }
  Json rows = Json::array();
  for (std::size_t d = 0; d < per_surface[0].size(); ++d) {
    std::vector<const Json*> same;
    for (const auto& ps : per_surface) same.push_back(&ps[d]);
    rows.push_back(combine(same));
  }
  j["rows"] = rows;
  Json ps = Json::array();
  for (std::size_t k = 0; k < files.size(); ++k)
    ps.push_back({{"file", files[k]}, {"rows", per_surface[k]}});
  j["per_surface"] = ps;
}

}  // namespace microsim::cli
