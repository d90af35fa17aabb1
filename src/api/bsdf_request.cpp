#include "microsim/api/bsdf_request.hpp"

#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>

#include "microsim/api/request_checks.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/io/pbsdf_grid.hpp"
#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/models/metals.hpp"

namespace microsim {

namespace {

// Sorted, without repeats (a table's axes must increase).
std::vector<double> sorted_unique(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }), v.end());
  return v;
}

// The request as it is measured: its incidence angles sorted, without repeats.
BsdfRequest normalized(const BsdfRequest& r) {
  BsdfRequest n = r;
  n.theta_i_deg = sorted_unique(r.theta_i_deg);
  n.phi_i_deg = sorted_unique(r.phi_i_deg);
  return n;
}

bool renderer_table(const std::string& format) { return format == "bsdf" || format == "binary" || format == "pbsdf"; }

// A polarized table (Mitsuba 3's measured_polarized): reflection of a conductor or mirror measured
// with Mueller matrices, one incidence azimuth (isotropic), and the five whole-nanometre
// wavelengths the plugin reads (a single index is written at kPbsdfWavelengthsNm).
void check_pbsdf_request(const BsdfRequest& o) {
  if (!o.polarized) throw ParameterError("{output} .pbsdf holds Mueller matrices: give {polarized}");
  if (o.material == "dielectric")
    throw ParameterError("{output} .pbsdf: {material} conductor or mirror only (a dielectric's table would miss its transmission)");
  if (o.phi_i_deg.size() != 1)
    throw ParameterError("{output} .pbsdf: Mitsuba's measured_polarized tables are isotropic; give one {phi_i}");
  const std::vector<double> nm = bsdf_wavelengths(o);
  if (nm.empty()) return;
  if (nm.size() != kPbsdfWavelengths)
    throw ParameterError("{wavelengths}: Mitsuba's measured_polarized reads exactly " + std::to_string(kPbsdfWavelengths) +
                         " wavelengths for {output} .pbsdf (got " + std::to_string(nm.size()) + ")");
  for (double x : nm)
    if (x != std::round(x) || x < 1 || x > 65535)
      throw ParameterError("{wavelengths}: a .pbsdf stores whole nanometres (got " + fixed_text(x, 3) + ")");
}

// The incidence angles: at least one, zeniths above the horizon, azimuths finite.
void check_incidences(const BsdfRequest& o) {
  if (o.theta_i_deg.empty() || o.phi_i_deg.empty()) throw ParameterError("{theta_i} and {phi_i} need at least one angle");
  for (double t : o.theta_i_deg)
    if (!(t >= 0 && t < 90))
      throw ParameterError("{theta_i} must be in [0, 90) degrees (got " + fixed_text(t, 2) + ")");
  for (double p : o.phi_i_deg)
    if (!std::isfinite(p) || std::abs(p) > 3600)
      throw ParameterError("{phi_i} must be finite angles in degrees, |phi| <= 3600");
}

// The counts, with the words of the command line's option checks.
void check_counts(const BsdfRequest& o) {
  require_integer_in(o.orders, 1, kMaxBsdfOrders, "orders");
  require_integer_in(o.rays, 1, kMaxRays, "rays");
  require_integer_in(o.replicates, 2, kMaxReplicates, "replicates");
  require_integer_in(o.resolution, 1, kMaxBsdfResolution, "resolution");
  require_integer_in(o.table_resolution, kMinTableResolution, kMaxTableResolution, "table_resolution");
  require_integer_in(o.table_azimuths, 1, kMaxTableAzimuths, "table_azimuths");
}

// Peak bytes of the tallies of a BSDF run (measure_bsdf_table), checked against peak RSS. One
// tally holds F = 16 * 2 (K + 1) (1 + R^2 + R) bytes: sums and second moments of the albedos,
// pixels and in-plane bins, both sides, K + 1 slots. While a run walks: its own tally, the unit
// tallies of a pass (U bytes each, first moments only per wavelength in a spectral run; as many
// as path_passes in bsdf_measure.cpp takes: at most min(16, 4 threads) and 64 MiB of them, at
// least one) and the replicate being summed; afterwards, with models, the Smith walk's
// replicates (a tally each, kept until its error is met), a pass and their sum. Kept to the
// end, per incidence: the nominal run's tallies (spectral: each wavelength's and the first's
// copy; the Smith walk's) and each turned run's reflected-total pixel sums (8 R^2 bytes per
// wavelength, none for .pbsdf), with their hemisphere maps (8 R^2). Not counted: a polarized
// run's Mueller sums and the replicates a split run keeps until the exchange.
double bsdf_tally_bytes(const BsdfRequest& o, double n_inc, double runs, double wavelengths, int threads) {
  const double npix = static_cast<double>(o.resolution) * o.resolution, slots = o.orders + 1.0;
  const double F = 16.0 * 2 * slots * (1 + npix + o.resolution);
  const double U = wavelengths > 0 ? 8.0 * 2 * slots * (1 + npix + o.resolution) * wavelengths : F;
  const auto pass = [&](double unit) {
    return std::min(std::min(16.0, 4.0 * threads), std::max(1.0, std::floor(64.0 * 1024 * 1024 / unit)));
  };
  const double walking = F + U * (pass(U) + 1);
  const double smith = o.models ? F * (o.replicates + pass(F) + 1) : 0.0;
  const double nominal = F * ((wavelengths > 0 ? wavelengths + 1 : 1) + (o.models ? 1 : 0)) + 8 * npix;
  const double turned = (o.format == "pbsdf" ? 0.0 : 8 * npix * std::max(1.0, wavelengths)) + 8 * npix;
  return std::max(walking, smith) + n_inc * (nominal + (runs - 1) * turned);
}

// The output format against the incidences, and the memory of its tables and of the tallies.
void check_tables(const BsdfRequest& o) {
  const std::string& ext = o.format;
  const std::vector<double>& phis = o.phi_i_deg;
  // Runs per incidence: an isotropic renderer table measures table_azimuths azimuths.
  const bool averaged = renderer_table(ext) && phis.size() == 1 && o.table_azimuths > 1;
  const double runs = averaged ? o.table_azimuths : 1.0;
  const std::size_t n_inc = o.theta_i_deg.size() * phis.size();
  if (n_inc > 100000) throw ParameterError("{theta_i} x {phi_i}: more than 100000 incidences");
  if (ext == "binary" && phis.size() > 1)
    throw ParameterError("{output} .binary: MERL tables are isotropic; give one {phi_i} (got " +
                         std::to_string(phis.size()) + " azimuths)");
  if (ext == "bsdf" && phis.size() > 1 && (std::abs(phis.front() + 180) > 1e-9 || std::abs(phis.back() - 180) > 1e-9))
    throw ParameterError("{phi_i}: an anisotropic .bsdf needs azimuths over the full circle from -180 to 180 "
                         "(e.g. {phi_i} -180:180:30), or one azimuth for an isotropic table");
  // -o .bsdf: the RGL tables hold vndf, luminance and two spectra values (floats) per vertex of
  // the table_resolution^2 grid of every incidence.
  // A spectral run: a spectra value per wavelength and three rgb values.
  const double wavelengths = static_cast<double>(bsdf_wavelengths(o).size());
  const double vertex_bytes = wavelengths > 0 ? 4.0 * (2 + wavelengths + 3) : 16.0;
  if (ext == "bsdf")
    require_memory(vertex_bytes * static_cast<double>(n_inc) * o.table_resolution * o.table_resolution,
                   "{table_resolution} " + std::to_string(o.table_resolution) + " with " + std::to_string(n_inc) +
                       " incidences");
  if (ext == "pbsdf") {
    const PbsdfGrid g = pbsdf_grid(o.table_resolution);
    require_memory(4.0 * 16 * kPbsdfWavelengths * g.theta_h * g.theta_d * g.phi_d,
                   "{table_resolution} " + std::to_string(o.table_resolution) + " for a .pbsdf");
  }
  const int threads = o.threads > 0 ? o.threads : tbb::this_task_arena::max_concurrency();
  const double need = bsdf_tally_bytes(o, static_cast<double>(n_inc), runs, wavelengths, threads);
  const double have = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE);
  if (need > 0.5 * have)
    throw ParameterError("{resolution} " + std::to_string(o.resolution) + " with {orders} " +
                         std::to_string(o.orders) + " and " + std::to_string(n_inc) + " incidences needs about " +
                         fixed_text(need / (1 << 30), 1) + " GiB of tallies, more than half of this machine's memory");
  if (averaged && o.rays < o.table_azimuths)
    throw ParameterError("{table_azimuths} " + std::to_string(o.table_azimuths) + " splits {rays} over as many "
                         "azimuths: give at least that many rays (got " + std::to_string(o.rays) + ")");
}

// check() on a normalized request.
void check_normalized(const BsdfRequest& o) {
  require_given(o.material, "material");
  if (o.theta_i_deg.empty()) throw ParameterError("{theta_i} is required");
  const std::string& ext = o.format;
  if (ext != "exr" && ext != "json" && ext != "bsdf" && ext != "binary" && ext != "pbsdf")
    throw UsageError("the output must be .exr, .json, .bsdf, .binary or .pbsdf (got ." + ext + ")");
  bsdf_material(o);
  if (ext == "pbsdf") check_pbsdf_request(o);
  check_incidences(o);
  check_counts(o);
  check_tables(o);
}


}  // namespace

void BsdfRequest::check() const { check_normalized(normalized(*this)); }

BsdfRequest normalized_bsdf_request(const BsdfRequest& r) { return normalized(r); }

std::optional<models::IndexTable> bsdf_index_table(const BsdfRequest& o) {
  const bool spectral = !o.metal.empty() || !o.ior_file.empty();
  if (!spectral) {
    if (!o.wavelengths_nm.empty()) throw ParameterError("{wavelengths} needs {metal} or {ior_file}");
    return std::nullopt;
  }
  if (o.material != "conductor") throw ParameterError("{metal} and {ior_file} apply to {material} conductor only");
  if (!o.metal.empty() && !o.ior_file.empty()) throw ParameterError("give {metal} or {ior_file}, not both");
  if (o.eta || o.k) throw ParameterError("{eta} and {k} do not go with {metal} or {ior_file} (the table gives the index)");
  if (!o.metal.empty()) return models::metal_table(o.metal);
  return models::read_index_file(o.ior_file);
}

std::vector<double> bsdf_wavelengths(const BsdfRequest& o) {
  const auto table = bsdf_index_table(o);
  if (!table) return {};
  std::vector<double> nm = o.wavelengths_nm.empty() ? models::default_wavelengths_nm() : o.wavelengths_nm;
  if (static_cast<int>(nm.size()) > kMaxWavelengths)
    throw ParameterError("{wavelengths}: at most " + std::to_string(kMaxWavelengths) + " wavelengths");
  models::check_wavelengths(nm, *table, "{wavelengths}");
  return nm;
}

std::vector<models::Material> spectral_conductors(const models::IndexTable& table, const std::vector<double>& nm) {
  std::vector<models::Material> out;
  for (double x : nm) {
    const models::OpticalConstant c = table.at(x);
    out.push_back(models::Material::conductor(c.n, c.k));
  }
  return out;
}

models::Material bsdf_material(const BsdfRequest& o) {
  const auto f4 = [](double x) { return fixed_text(x, 4); };
  if (const auto table = bsdf_index_table(o)) return spectral_conductors(*table, bsdf_wavelengths(o)).front();
  if (o.material == "mirror") {
    if (o.eta || o.k) throw ParameterError("{eta} and {k} apply to {material} conductor or dielectric, not mirror");
    return models::Material::mirror();
  }
  if (o.material == "conductor") {
    if (!o.eta || !o.k) throw ParameterError("{material} conductor needs {eta} E and {k} K (complex index eta + ik)");
    if (!(std::isfinite(*o.eta) && *o.eta > 0 && *o.eta <= 100))
      throw ParameterError("{eta} must be in (0, 100] (got " + f4(*o.eta) + ")");
    if (!(std::isfinite(*o.k) && *o.k >= 0 && *o.k <= 100))
      throw ParameterError("{k} must be in [0, 100] (got " + f4(*o.k) + ")");
    return models::Material::conductor(*o.eta, *o.k);
  }
  if (o.material == "dielectric") {
    if (!o.eta) throw ParameterError("{material} dielectric needs {eta} E (index below / index above)");
    if (o.k) throw ParameterError("{k} applies to {material} conductor only");
    if (!(std::isfinite(*o.eta) && *o.eta >= 0.01 && *o.eta <= 100))
      throw ParameterError("{eta} must be in [0.01, 100] (got " + f4(*o.eta) + ")");
    return models::Material::dielectric(*o.eta);
  }
  throw ParameterError("{material} must be mirror, conductor or dielectric (got '" + literal_text(o.material) + "')");
}

}  // namespace microsim
