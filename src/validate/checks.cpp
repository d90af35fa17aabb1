// The registry of checks and the run over surface sets.
#include "checks_common.hpp"

namespace microsim::validation {

const std::vector<Check>& checks() {
  static const std::vector<Check> registry = {
      {"d_identities", "[GeomBSDF24, eq. 1b and 1c] from the facets (exact, to rounding)",
       [](const SurfaceSet&) { return true; },
       [](const SurfaceSet& s) {
         double w = 0;
         for (const auto& m : s.surfaces) w += 0.1 * static_cast<double>(m.num_facets());
         return w;
       },
       check_d_identities},
      {"d_nominal", "D per theta ring and the fitted alpha against the generator's nominal NDF",
       [](const SurfaceSet& s) { return s.surfaces[0].nominal.has_value(); },
       [](const SurfaceSet& s) {
         double w = 0;
         for (const auto& m : s.surfaces) w += 0.2 * static_cast<double>(m.num_facets());
         return w;
       },
       check_d_nominal},
      {"g1", "G1: both estimators, visible area ratio, Smith from the facets and nominal, per-bin "
             "G1(v,m) against Smith and the V-cavity model",
       [](const SurfaceSet&) { return true; }, g1_work, check_g1},
      {"g2", "G2: symmetry and hotspot identities; the four Smith forms (facets and nominal) and "
             "the V-cavity model for the averaged G2",
       [](const SurfaceSet&) { return true; }, g2_work, check_g2},
      {"vndf", "VNDF histogram against the nominal D_v (chi-square), and the nominal NDF's VNDF "
               "sampler against its own D_v (identity)",
       [](const SurfaceSet& s) { return s.surfaces[0].nominal.has_value(); }, vndf_work, check_vndf},
      {"bsdf_albedo", "mirror BSDF albedos: total = 1 (energy conservation; finite objects: the "
                      "visible area ratio), order 1 against the single-scattering model, per order "
                      "against the Smith random walk and the V-groove / V-cavity closed forms",
       [](const SurfaceSet&) { return true; }, bsdf_work, check_bsdf_albedo},
  };
  return registry;
}

Result run(const std::vector<SurfaceSet>& sets, double significance,
           const std::function<void(double)>& report) {
  if (!(significance > 0 && significance < 1))
    throw ParameterError("{significance} must be in (0, 1) (got " + num(significance) + ")");
  auto t0 = std::chrono::steady_clock::now();
  // Resolve the checks of every set first: an unknown name fails before any work.
  std::vector<std::vector<const Check*>> todo(sets.size());
  Progress progress;
  progress.report = report;
  for (std::size_t i = 0; i < sets.size(); ++i) {
    const SurfaceSet& set = sets[i];
    if (set.surfaces.empty()) throw UsageError("validation entry " + set.name + " has no surface");
    if (set.labels.size() != set.surfaces.size())
      throw RuntimeFailure("validation entry " + set.name + ": one label per surface expected");
    const Options& o = set.options;
    if (o.theta_deg.empty() || o.phi_deg.empty())
      throw ParameterError("validation entry " + literal_text(set.name) + ": no view direction ({theta}, {phi})");
    for (double t : o.theta_deg)
      if (!(t >= 0 && t < 90)) throw ParameterError("{theta} must be in [0, 90) degrees (got " + num(t) + ")");
    if (o.rays == 0) throw ParameterError("{rays} must be positive");
    for (const std::string& name : set.options.checks) {
      auto it = std::find_if(checks().begin(), checks().end(), [&](const Check& c) { return c.name == name; });
      if (it == checks().end()) {
        std::string known;
        for (const Check& c : checks()) known += (known.empty() ? "" : ", ") + c.name;
        throw UsageError("unknown check '" + name + "' (known: " + known + ")");
      }
    }
    for (const Check& c : checks()) {
      const bool wanted = set.options.checks.empty() ||
                          std::find(set.options.checks.begin(), set.options.checks.end(), c.name) !=
                              set.options.checks.end();
      if (wanted && c.applies(set)) {
        todo[i].push_back(&c);
        progress.total += c.work(set);
      }
    }
  }
  Result result;
  result.significance = significance;
  for (std::size_t i = 0; i < sets.size(); ++i) {
    const SurfaceSet& set = sets[i];
    EntryResult e;
    e.name = set.name;
    for (std::size_t k = 0; k < set.surfaces.size(); ++k)
      e.surfaces.push_back({{"label", set.labels[k]}, {"description", set.surfaces[k].description},
                            {"facets", set.surfaces[k].num_facets()},
                            {"periodic", set.surfaces[k].macro().periodic}});
    const Options& o = set.options;
    e.parameters = {{"theta_deg", o.theta_deg}, {"phi_deg", o.phi_deg}, {"rays", o.rays},
                    {"seed", o.seed}, {"ndf_theta_bins", o.ndf_theta_bins},
                    {"ndf_phi_bins", o.ndf_phi_bins}, {"min_ring_mass", o.min_ring_mass},
                    {"min_bin_count", o.min_bin_count}, {"checks", Json::array()}};
    for (const Check* c : todo[i]) {
      e.parameters["checks"].push_back(c->name);
      CheckOutput out;
      c->run(set, progress, out);
      result.rows.insert(result.rows.end(), out.rows.begin(), out.rows.end());
      e.measurements[c->name] = out.measurements;
      if (auto row = discretization_row(set, c->name)) result.rows.push_back(*row);
    }
    result.entries.push_back(std::move(e));
  }
  result.z_threshold = assign_verdicts(result.rows, significance);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace microsim::validation
