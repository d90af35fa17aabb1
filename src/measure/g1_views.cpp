#include "microsim/measure/g1_views.hpp"

#include <memory>

#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/undersurface.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

G1Views measure_g1_views(const Microsurface& s, const std::vector<Vec3>& views, G1Options options,
                         const std::function<void(double)>& progress) {
  bool below = false;
  for (const Vec3& v : views) below = below || v.z() < 0;
  if (below && s.kind() == Microsurface::Kind::Heightfield)
    throw ParameterError("{theta} must be in [0, 90) degrees for a heightfield (theta in (90, 180], the "
                         "undersurface, is measured on meshes only)");
  if (below && is_vcavity(s)) throw ParameterError("{theta} must be in [0, 90) degrees for a vcavity ensemble");
  G1Views out;
  out.table = g1_table();
  std::size_t done = 0;
  options.progress = [&](double f) {
    if (progress) progress(static_cast<double>(done) + f);
  };
  if (is_vcavity(s)) {
    out.vcavity = true;
    for (const G1Result& r : measure_g1(vcavity_grooves(s, "measure_g1", GrooveFrames::StoredNormalOverHypot), views, options)) {
      out.counters += r.counters;
      add_row(out.table, r, s);
      ++done;
    }
    return out;
  }
  Tracer tracer(s);
  out.build_seconds += tracer.build_seconds();
  const FacetTable table = build_facet_table(s, g1_normal_binning(options));
  std::unique_ptr<Microsurface> under_surface;
  std::unique_ptr<Tracer> under;
  if (below) {
    under_surface = std::make_unique<Microsurface>(undersurface(s));
    under = std::make_unique<Tracer>(*under_surface);
    out.build_seconds += under->build_seconds();
  }
  for (const Vec3& v : views) {
    const G1Result r = measure_g1(tracer, v, options, &table, under.get());
    out.counters += r.counters;
    Json& row = add_row(out.table, r, s);
    ++done;
    if (v.z() < 0) {  // the undersurface beside its two approximations [GeomBSDF24, "Inherent Assumptions"]
      const G1Result rev = measure_g1(tracer, -v, options, &table);
      const G1Result ref = measure_g1(tracer, mirror_z(v), options, &table);
      out.counters += rev.counters;
      out.counters += ref.counters;
      add_undersurface_approximations(row, r, rev, ref);
    }
  }
  return out;
}

}  // namespace microsim
