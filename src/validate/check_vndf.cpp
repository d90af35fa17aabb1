// Check of the VNDF (histogram against D_v, sampler identity).
#include "checks_common.hpp"
#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/measure/vcavity_measure.hpp"
#include "microsim/surface/generators.hpp"

namespace microsim::validation {

// ---------------------------------------------------------------------------------------------
// VNDF ([GeomBSDF24, eq. 3b], [Heitz14, eq. 13]): the histogram of first-hit normals against the nominal D_v
// (approximate model), and the nominal NDF's VNDF sampler against its own D_v (identity: the
// sampler must reproduce its model; chi-square row: measured chi2/dof, model 1, stderr
// sqrt(2/dof), the normal approximation of chi2/dof). The nominal D_v is a statistic of the
// generated surfaces: over an ensemble, the bin densities (bins holding at least
// kVndfMinBinMass of the nominal D_v) are compared with the between-surface error; the
// chi-square of one surface's histogram against it (which counts surface-to-surface variation
// as a deviation) is an info row.
constexpr double kVndfMinBinMass = 0.01;

namespace {
// A chi-square row's value (chi2/dof against the model 1) and its record fields.
Row with_chi2(Row m, const GofResult& g, const std::string& error, const std::string& group, const Json& ang) {
  set_chi2(m, g.chi2, g.dof);
  m.error = error;
  m.group = group;
  m.extra = ang;
  m.extra["chi2"] = g.chi2;
  m.extra["dof"] = g.dof;
  m.extra["p_value"] = g.p_value;
  return m;
}

// The chi-square row (chi2/dof, model 1) of one view's hit histogram against a model's bin
// probabilities, with the ray-count error.
Row chi2_row(const SurfaceSet& set, const std::string& model, Kind kind, const std::string& source,
             const std::string& where, const GofResult& g, const std::string& group, const Json& ang) {
  Row m = make_row(set, "", "vndf_chi2_per_dof", model, kind, source);
  m.condition += " " + where;
  return with_chi2(std::move(m), g, "rays", group, ang);
}

// One view direction of the check, as the rows name it and the records give it.
struct VndfView {
  double theta_deg, phi_deg;
  Vec3 v;
  std::string where;
  Json ang;
};

// Per direction and bin, the density of each surface (the ensemble rows).
using DensitiesByDirection = std::map<std::pair<double, double>, std::vector<std::vector<Estimate>>>;

// The nominal D_v against one surface's histogram (an info row: one surface), the surface's bin
// densities kept for the ensemble rows, and on the first surface the nominal NDF's VNDF sampler
// against its own D_v (it depends only on the nominal NDF: tested once per direction).
std::optional<SamplerTest> push_nominal_vndf_rows(const SurfaceSet& set, const SurfacePass& pass, const VndfResult& r,
                                                  const VndfView& view, const VndfOptions& vo,
                                                  const DirectionBinning& binning, DensitiesByDirection& densities,
                                                  CheckOutput& out) {
  const Microsurface& s = pass.surface;
  const std::vector<double> model =
      bin_integrals(r.binning, [&](const Vec3& m) { return s.nominal->D_visible(r.v, m); });
  const GofResult g = histogram_gof(r.bin_hits, r.hits, model, vo.family_alpha);
  Row m = chi2_row(set, "nominal", Kind::Info, "[Heitz14, eq. 13]: D_v of the nominal NDF, bin integrals", view.where,
                   g, set.name + "/vndf_nominal", view.ang);
  m.error = "rays (one surface: surface-to-surface variation not included)";
  out.rows.push_back(m);
  auto& dv = densities[{view.theta_deg, view.phi_deg}];
  dv.resize(static_cast<std::size_t>(binning.size()));
  for (int b = 0; b < binning.size(); ++b) dv[b].push_back(floored(r.dv(b), r.hits, 1.0 / binning.solid_angle(b)));
  if (pass.k != 0) return std::nullopt;
  std::optional<SamplerTest> sampler =
      test_vndf_sampler(*s.nominal, view.v, vo.rays, binning, set.options.seed ^ 0x5a5a5a5aULL);
  Row sr = make_row(set, "", "vndf_sampler_chi2_per_dof", "sampler_model", Kind::Identity,
                    "models/ndf.hpp VNDF sampler vs its own D_v [Heitz14, eq. 13]");
  sr.condition = set.name + " nominal sampler, theta " + angle(view.theta_deg) + " phi " + angle(view.phi_deg);
  out.rows.push_back(with_chi2(std::move(sr), sampler->gof, "samples", set.name + "/vndf_sampler", view.ang));
  return sampler;
}

// One surface at one view: the histogram of first-hit normals against the V-cavity model (a
// V-cavity ensemble) and the nominal D_v; the measurement row into the surface's record.
void check_vndf_view(const SurfaceSet& set, SurfacePass& pass, const VndfView& view, VndfOptions& vo,
                     const DirectionBinning& binning, DensitiesByDirection& densities, Progress& progress,
                     CheckOutput& out) {
  const Microsurface& s = pass.surface;
  const double unit = static_cast<double>(vo.rays);
  const VndfResult r = measure_with_progress(progress, unit, vo, [&](const VndfOptions& opt) {
    // A V-cavity ensemble: groove by groove [Heitz14, Sec. 6.1], as check_g1 measures it.
    if (!is_vcavity(s)) return measure_vndf(pass.tracer, view.v, opt, &pass.table);
    return measure_vndf(vcavity_grooves(s, "check vndf", GrooveFrames::StoredNormalNormalized), view.v, opt);
  });
  std::optional<SamplerTest> sampler;
  if (is_vcavity(s)) {
    // The V-cavity model's VNDF over the ensemble's own facets: exact for separate grooves
    // (the surface's own statistics, so the ray-count error is the right one).
    const GofResult g = histogram_gof(r.bin_hits, r.hits, vcavity_vndf_probabilities(s, r.v, r.binning),
                                      vo.family_alpha);
    Row m = chi2_row(set, "vcavity", Kind::Model,
                     "[Heitz14, eq. 13] with the V-cavity G1 [Heitz14, eq. 24] over the facets, bin sums", view.where,
                     g, set.name + "/vndf_vcavity", view.ang);
    m.extra["max_abs_z"] = g.max_abs_z;
    out.rows.push_back(m);
  }
  if (s.nominal) sampler = push_nominal_vndf_rows(set, pass, r, view, vo, binning, densities, out);
  progress.completed += unit;
  progress.update();
  Table vndf_rows = vndf_table(vo.family_alpha);
  Json& row = add_row(vndf_rows, r, s, vo, sampler);
  row["theta_deg"] = view.theta_deg;
  row["phi_deg"] = view.phi_deg;
  pass.rows().push_back(row);
}

// Over an ensemble: every bin holding at least kVndfMinBinMass of the nominal D_v, the
// surfaces' densities against it with the between-surface error.
void push_ensemble_vndf_bins(const SurfaceSet& set, const DirectionBinning& binning,
                             DensitiesByDirection& densities, CheckOutput& out) {
  for (double p : set.options.phi_deg)
    for (double t : set.options.theta_deg) {
      const Vec3 v = direction_from_angles(rad(t), rad(p));
      const std::vector<double> model =
          bin_integrals(binning, [&](const Vec3& m) { return set.surfaces[0].nominal->D_visible(v, m); });
      const std::string dir = "theta " + angle(t) + " phi " + angle(p);
      for (int b = 0; b < binning.size(); ++b) {
        if (model[b] < kVndfMinBinMass) continue;
        const NormalBinRange bin = normal_bin_range(binning, b);
        Row r = make_row(set, "", "vndf_bin", "nominal", Kind::Model,
                         "[Heitz14, eq. 13]: D_v of the nominal NDF, bin average");
        push_nominal(out, std::move(r), dir + ", " + bin.text(), densities[{t, p}][b],
                     model[b] / binning.solid_angle(b), set.name + "/vndf_nominal_bins/" + dir,
                     bin.with({{"theta_deg", t}, {"phi_deg", p}}));
      }
    }
}
}  // namespace

double vndf_work(const SurfaceSet& set) {
  const double n = static_cast<double>(share_of_rays(set.options, 4));
  const double dirs = static_cast<double>(set.options.theta_deg.size() * set.options.phi_deg.size());
  double w = 0;
  for (const auto& s : set.surfaces) w += 0.1 * static_cast<double>(s.num_facets()) + dirs * 2.0 * n;
  return w;
}

void check_vndf(const SurfaceSet& set, Progress& progress, CheckOutput& out) {
  const Options& o = set.options;
  VndfOptions vo = check_options<VndfOptions>(o, share_of_rays(o, 4));
  const DirectionBinning binning = vndf_binning(vo);
  DensitiesByDirection densities;
  const Json per_surface = for_each_surface(set, binning, progress, [&](SurfacePass& pass) {
    for_each_view(o, [&](double t, double p, const Vec3& v) {
      const VndfView view{t, p, v, (pass.label.empty() ? "" : pass.label + ", ") + "theta " + angle(t) + " phi " + angle(p),
                          {{"theta_deg", t}, {"phi_deg", p}}};
      check_vndf_view(set, pass, view, vo, binning, densities, progress, out);
    });
  });
  if (set.surfaces.size() > 1 && set.surfaces[0].nominal) push_ensemble_vndf_bins(set, binning, densities, out);
  out.measurements = per_surface;
}

}  // namespace microsim::validation
