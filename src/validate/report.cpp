// The validation record (JSON) and the printed table.
#include "checks_common.hpp"

namespace microsim::validation {

Json row_to_json(const Row& r) {
  Json j;
  j["quantity"] = r.quantity;
  j["model_name"] = r.model_name;
  j["condition"] = r.condition;
  j["entry"] = r.entry;
  j["kind"] = to_string(r.kind);
  j["measured"] = r.measured;
  j["stderr"] = r.stderr_ ? Json(*r.stderr_) : Json(nullptr);
  j["model"] = r.model ? Json(*r.model) : Json(nullptr);
  j["z"] = r.z && std::isfinite(*r.z) ? Json(*r.z) : Json(nullptr);
  if (r.z && !std::isfinite(*r.z)) j["z_infinite"] = true;
  j["rel_dev"] = r.rel_dev ? Json(*r.rel_dev) : Json(nullptr);
  j["verdict"] = r.verdict;
  if (r.kind == Kind::Deterministic) j["tolerance"] = r.tolerance;
  j["t_dof"] = r.dof ? Json(*r.dof) : Json(nullptr);
  j["z_threshold"] = r.threshold ? Json(*r.threshold) : Json(nullptr);
  j["error"] = r.error;
  j["reference"] = r.reference;
  j["group"] = r.group;
  for (auto it = r.extra.begin(); it != r.extra.end(); ++it) j[it.key()] = it.value();
  return j;
}

Json verdict_rules_json(double significance, double z_threshold, std::size_t comparisons) {
  return {
      {"identity", "exact identity measured by Monte Carlo: pass when |z| <= the row's z_threshold, else FAIL"},
      {"deterministic", "exact identity without sampling: pass when |measured - model| <= tolerance "
                        "(bound on double rounding of the facet sums), else FAIL"},
      {"model", "approximate model: agrees when |z| <= the row's z_threshold, else 'deviates "
                "(finding)'; a deviation is a result about the model, not an error. Nominal models "
                "(the generator's NDF) are model rows only over ensembles of surfaces (between-surface "
                "error), info rows for one surface"},
      {"info", "measured without a model or without an error bar: 'measured'"},
      {"z", "(measured - model) / stderr"},
      {"rel_dev", "(measured - model) / |model|"},
      {"z_threshold", "Sidak: per-row rate 1 - (1 - significance)^(1/comparisons) over the "
                      "'comparisons' z-tested rows of the run; the two-sided normal quantile at that "
                      "rate (z_threshold_value), or for rows with an error from K surfaces (t_dof = "
                      "K - 1) the two-sided Student t quantile with K - 1 degrees of freedom"},
      {"t_dof", "degrees of freedom of a row's error: K - 1 for the spread of K surfaces, null for "
              "ray-count errors (normal)"},
      {"significance", significance},
      {"comparisons", comparisons},
      {"z_threshold_value", z_threshold},
      {"stderr_floor", "errors of proportions from n samples are at least that of (n+1/2)/(n+1) "
                       "(about 0.7/n): a proportion of 0 or 1 is known only to ~1/n"},
      {"exit_code", "1 when any row is FAIL, else 0"}};
}

Json result_to_json(const Result& r) {
  Json j;
  std::size_t tested = 0;
  for (const Row& row : r.rows) tested += row.z.has_value();
  j["significance"] = r.significance;
  j["z_threshold"] = r.z_threshold;
  j["comparisons"] = tested;
  j["verdict_rules"] = verdict_rules_json(r.significance, r.z_threshold, tested);
  j["summary"] = {{"rows", r.rows.size()},
                  {"pass", r.count("pass")},
                  {"fail", r.count("FAIL")},
                  {"agrees", r.count("agrees")},
                  {"deviates", r.count("deviates (finding)")},
                  {"measured", r.count("measured")}};
  Json entries = Json::array();
  for (const EntryResult& e : r.entries)
    entries.push_back({{"name", e.name}, {"surfaces", e.surfaces}, {"parameters", e.parameters},
                       {"measurements", e.measurements}});
  j["entries"] = entries;
  Json rows = Json::array();
  for (const Row& row : r.rows) rows.push_back(row_to_json(row));
  j["rows"] = rows;
  j["seconds"] = r.seconds;
  return j;
}

std::string format_table(const Result& r) {
  struct Line {
    std::string quantity, condition, measured, model, z, thr, rel, verdict;
  };
  std::vector<Line> lines;
  lines.push_back({"quantity", "condition", "measured +- stderr", "model", "z", "|z|max", "rel_dev", "verdict"});
  // Group rows: a group is shown once, where its first row is, by its worst row.
  std::vector<std::vector<const Row*>> blocks;
  std::map<std::string, std::size_t> group_block;
  for (const Row& row : r.rows) {
    if (row.group.empty()) {
      blocks.push_back({&row});
      continue;
    }
    auto [it, fresh] = group_block.try_emplace(row.group, blocks.size());
    if (fresh) blocks.emplace_back();
    blocks[it->second].push_back(&row);
  }
  for (const auto& members : blocks) {
    // The worst row: a FAIL first, then the largest |z| (deterministic rows: |d| / tolerance).
    auto badness = [](const Row* x) {
      double b = -1;
      if (x->z) b = std::abs(*x->z);
      else if (x->kind == Kind::Deterministic && x->model)
        b = std::abs(x->measured - *x->model) / std::max(x->tolerance, 1e-300);
      return std::make_pair(x->verdict == "FAIL", b);
    };
    const Row* worst = members[0];
    std::size_t deviating = 0;
    for (const Row* m : members) {
      if (m->verdict == "FAIL" || m->verdict == "deviates (finding)") ++deviating;
      if (badness(m) > badness(worst)) worst = m;
    }
    Line l;
    l.quantity = worst->quantity + (worst->model_name.empty() ? "" : " vs " + worst->model_name);
    l.condition = worst->condition;
    if (members.size() > 1)
      l.condition += "  [worst of " + std::to_string(members.size()) + ", " +
                     std::to_string(deviating) + " outside]";
    l.measured = num(worst->measured) + (worst->stderr_ ? " +- " + num(*worst->stderr_, 2) : "");
    l.model = worst->model ? num(*worst->model) : "-";
    l.z = worst->z ? (std::isfinite(*worst->z) ? fixed(*worst->z, 2) : (*worst->z > 0 ? "inf" : "-inf"))
                   : "-";
    l.thr = worst->threshold ? fixed(*worst->threshold, 2) + (worst->dof ? " t" + std::to_string(*worst->dof) : "")
                             : "-";
    l.rel = worst->rel_dev ? fixed(100 * *worst->rel_dev, 3) + "%" : "-";
    if (worst->kind == Kind::Deterministic && worst->model)
      l.z = "|d|=" + num(std::abs(worst->measured - *worst->model), 2);
    l.verdict = worst->verdict;
    lines.push_back(l);
  }
  std::size_t w[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (const Line& l : lines) {
    const std::string* f[8] = {&l.quantity, &l.condition, &l.measured, &l.model, &l.z, &l.rel, &l.verdict, &l.thr};
    for (int c = 0; c < 8; ++c) w[c] = std::max(w[c], f[c]->size());
  }
  std::ostringstream os;
  for (const Line& l : lines) {
    os << std::left << std::setw(static_cast<int>(w[0])) << l.quantity << "  "
       << std::setw(static_cast<int>(w[1])) << l.condition << "  " << std::right
       << std::setw(static_cast<int>(w[2])) << l.measured << "  " << std::setw(static_cast<int>(w[3]))
       << l.model << "  " << std::setw(static_cast<int>(w[4])) << l.z << "  "
       << std::setw(static_cast<int>(w[7])) << l.thr << "  " << std::setw(static_cast<int>(w[5])) << l.rel << "  " << std::left << l.verdict << "\n";
  }
  return os.str();
}

}  // namespace microsim::validation
