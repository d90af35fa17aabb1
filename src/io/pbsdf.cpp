#include "microsim/io/pbsdf.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>

#include "microsim/io/rgl_reader.hpp"

namespace microsim {

using models::Mueller;

Mueller PolarizedTable::block(std::size_t p, std::size_t d, std::size_t h, std::size_t l) const {
  const std::size_t o = offset(p, d, h, l);
  Mueller m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = M[o + 4 * r + c];
  return m;
}

std::vector<TensorField> PolarizedTable::fields() const {
  using U = std::uint64_t;
  return {TensorField::f32("theta_h", {1, theta_h.size()}, theta_h),
          TensorField::f32("theta_d", {1, theta_d.size()}, theta_d),
          TensorField::f32("phi_d", {1, phi_d.size()}, phi_d),
          TensorField::u16("wvls", {wavelengths.size()}, wavelengths),
          TensorField::f32("M", {static_cast<U>(phi_d.size()), theta_d.size(), theta_h.size(), wavelengths.size(), 4, 4}, M)};
}

namespace {
void check_grid(const std::vector<float>& g, double lo, double hi, const char* name) {
  if (g.empty()) throw UsageError(std::string("pbsdf: the ") + name + " grid is empty");
  for (std::size_t k = 0; k < g.size(); ++k) {
    if (!(g[k] >= lo - 1e-6 && g[k] <= hi + 1e-6))
      throw UsageError(std::string("pbsdf: ") + name + " values must lie in [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "] radians");
    if (k > 0 && !(g[k] > g[k - 1])) throw UsageError(std::string("pbsdf: ") + name + " values must increase");
  }
}
void check_table(const PolarizedTable& t) {
  check_grid(t.theta_h, 0.0, 0.5 * kPi, "theta_h");
  check_grid(t.theta_d, 0.0, 0.5 * kPi, "theta_d");
  check_grid(t.phi_d, -kPi, kPi, "phi_d");
  // Mitsuba's measured_polarized copies exactly five wavelengths from the file.
  if (t.wavelengths.size() != 5) throw UsageError("pbsdf: Mitsuba's measured_polarized reads exactly five wavelengths");
  for (std::size_t k = 1; k < t.wavelengths.size(); ++k)
    if (!(t.wavelengths[k] > t.wavelengths[k - 1])) throw UsageError("pbsdf: wavelengths must increase");
  if (t.M.size() != t.size()) throw UsageError("pbsdf: M does not have the size of the grids");
}
}  // namespace

void write_pbsdf(const std::string& path, const PolarizedTable& table) {
  check_table(table);
  write_tensor_file(path, table.fields());
}

PolarizedTable read_pbsdf(const std::string& path) {
  const auto f = read_tensor_file(path);
  auto field = [&](const char* name, std::size_t ndim, int dtype) -> const TensorField& {
    auto it = f.find(name);
    if (it == f.end() || it->second.shape.size() != ndim || it->second.dtype != dtype)
      throw UsageError(path + ": pbsdf field '" + name + "' missing or of the wrong type or shape");
    return it->second;
  };
  auto floats = [](const TensorField& t) {
    std::vector<float> v(t.data.size() / 4);
    std::memcpy(v.data(), t.data.data(), v.size() * 4);
    return v;
  };
  const TensorField& th = field("theta_h", 2, 10);
  const TensorField& td = field("theta_d", 2, 10);
  const TensorField& pd = field("phi_d", 2, 10);
  const TensorField& wl = field("wvls", 1, 3);
  const TensorField& m = field("M", 6, 10);
  if (th.shape[0] != 1 || td.shape[0] != 1 || pd.shape[0] != 1 || m.shape[0] != pd.shape[1] ||
      m.shape[1] != td.shape[1] || m.shape[2] != th.shape[1] || m.shape[3] != wl.shape[0] || m.shape[4] != 4 ||
      m.shape[5] != 4)
    throw UsageError(path + ": pbsdf fields of inconsistent shapes");
  PolarizedTable t;
  t.theta_h = floats(th);
  t.theta_d = floats(td);
  t.phi_d = floats(pd);
  t.wavelengths.resize(wl.data.size() / 2);
  std::memcpy(t.wavelengths.data(), wl.data.data(), t.wavelengths.size() * 2);
  t.M = floats(m);
  return t;
}

RusinkiewiczPair directions_of_rusinkiewicz(double theta_h, double theta_d, double phi_d) {
  RusinkiewiczPair r;
  r.h = Vec3(std::sin(theta_h), 0.0, std::cos(theta_h));
  const Vec3 t(std::cos(theta_h), 0.0, -std::sin(theta_h)), b(0.0, 1.0, 0.0);
  r.p = std::cos(phi_d) * t + std::sin(phi_d) * b;
  r.light = std::cos(theta_d) * r.h + std::sin(theta_d) * r.p;
  r.view = std::cos(theta_d) * r.h - std::sin(theta_d) * r.p;
  return r;
}

void rusinkiewicz_of_directions(const Vec3& light, const Vec3& view, double* theta_h, double* theta_d, double* phi_d) {
  const Vec3 h = (light + view).normalized();
  const Vec3 b = Vec3::UnitZ().cross(h).normalized();
  const Vec3 t = b.cross(h).normalized();
  *theta_d = std::acos(std::clamp(h.dot(light), -1.0, 1.0));
  *theta_h = std::acos(std::clamp(h.z(), -1.0, 1.0));
  const Vec3 p = (light - light.dot(h) * h).normalized();
  *phi_d = std::atan2(std::clamp(b.dot(p), -1.0, 1.0), std::clamp(t.dot(p), -1.0, 1.0));
}

Mueller to_pbsdf_frames(const Mueller& M, const RusinkiewiczPair& d) {
  const Vec3 x = pbsdf_reference_axis(d);
  return models::change_frames(M, -d.light, models::stokes_frame(d.light), x, d.view, models::stokes_frame(d.view), x);
}

PolarizedTable fill_pbsdf(std::vector<float> theta_h, std::vector<float> theta_d, std::vector<float> phi_d,
                          std::vector<std::uint16_t> wavelengths, const PolarizedBrdf& f) {
  PolarizedTable t;
  t.theta_h = std::move(theta_h);
  t.theta_d = std::move(theta_d);
  t.phi_d = std::move(phi_d);
  t.wavelengths = std::move(wavelengths);
  t.M.assign(t.size(), std::numeric_limits<float>::quiet_NaN());
  check_table(t);
  constexpr double kGrazing = 1e-6;  // z of a grazing direction, to the rounding of the float32 grid angles
  tbb::parallel_for(std::size_t(0), t.phi_d.size(), [&](std::size_t p) {
    for (std::size_t d = 0; d < t.theta_d.size(); ++d)
      for (std::size_t h = 0; h < t.theta_h.size(); ++h) {
        const RusinkiewiczPair r = directions_of_rusinkiewicz(t.theta_h[h], t.theta_d[d], t.phi_d[p]);
        if (r.light.z() < -kGrazing || r.view.z() < -kGrazing) continue;
        for (std::size_t l = 0; l < t.wavelengths.size(); ++l) {
          const Mueller m = to_pbsdf_frames(f(r.light, r.view, t.wavelengths[l]), r);
          const std::size_t o = t.offset(p, d, h, l);
          for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) t.M[o + 4 * i + j] = static_cast<float>(m(i, j));
        }
      }
  });
  return t;
}

std::vector<float> evenly_spaced(double lo, double hi, int n) {
  std::vector<float> v(static_cast<std::size_t>(std::max(n, 0)));
  for (int k = 0; k < n; ++k) v[k] = static_cast<float>(n == 1 ? lo : lo + (hi - lo) * k / (n - 1));
  return v;
}

// ---------------------------------------------------------------------------------------------
// A table from a polarized measurement

namespace {
// The run's Mueller BSDF (all orders) at the direction wo: bilinear between the pixel centres of
// its bin map, in the map's square coordinates (edge pixels held to the border), as interpolate_f.
Mueller interpolate_mueller(const BsdfResult& r, const Vec3& wo, int l) {
  const PolarizationTally& t = *r.polarization;
  const int R = t.bin_resolution;
  auto pixel = [&](int i, int j) { return t.pixel_f(l, j * R + i); };
  if (R == 1) return pixel(0, 0);
  thread_local std::optional<HemisphereMap> map;  // built once per thread and resolution
  if (!map || map->resolution() != R) map.emplace(R);
  const Vec2 sq = map->to_square(wo);
  const double x = std::clamp((sq.x() + 1.0) * 0.5 * R - 0.5, 0.0, R - 1.0);
  const double y = std::clamp((sq.y() + 1.0) * 0.5 * R - 0.5, 0.0, R - 1.0);
  const int i = std::min(static_cast<int>(x), R - 2), j = std::min(static_cast<int>(y), R - 2);
  const double fx = x - i, fy = y - j;
  return (1 - fy) * ((1 - fx) * pixel(i, j) + fx * pixel(i + 1, j)) + fy * ((1 - fx) * pixel(i, j + 1) + fx * pixel(i + 1, j + 1));
}
// Incidence t's matrix toward wo (in the frame of the nominal azimuth): the walk-weighted mean over
// the table's azimuths, each run reading wo turned by its azimuth offset (table_f's rule).
Mueller incidence_mueller(const BsdfTable& table, int t, const Vec3& wo, int l) {
  const BsdfResult& r0 = table.at(0, t);
  if (table.turned.empty()) return interpolate_mueller(r0, wo, l);
  double walks = static_cast<double>(r0.polarization->paths);
  Mueller sum = walks * interpolate_mueller(r0, wo, l);
  const auto& runs = table.turned[static_cast<std::size_t>(t)];
  for (std::size_t a = 0; a < runs.size(); ++a) {
    const double w = static_cast<double>(runs[a].polarization->paths);
    sum += w * interpolate_mueller(runs[a], turn_about_normal(wo, table.turns[a + 1]), l);
    walks += w;
  }
  return sum / walks;
}
void check_measured_table(const BsdfTable& t) {
  if (t.phi_i.size() != 1)
    throw ParameterError("{output} .pbsdf: Mitsuba's measured_polarized tables are isotropic; give one {phi_i}");
  for (std::size_t k = 1; k < t.theta_i.size(); ++k)
    if (!(t.theta_i[k] > t.theta_i[k - 1])) throw ParameterError("{theta_i} must be increasing for a .pbsdf");
  auto polarized = [](const BsdfResult& r) { return r.polarization && r.polarization->bin_pixels > 0; };
  for (const BsdfResult& r : t.results)
    if (!polarized(r)) throw ParameterError("{output} .pbsdf holds Mueller matrices: give {polarized}");
  for (const auto& runs : t.turned)
    for (const BsdfResult& r : runs)
      if (!polarized(r)) throw ParameterError("{output} .pbsdf holds Mueller matrices: give {polarized}");
}
}  // namespace

Mueller measured_mueller(const BsdfTable& t, const Vec3& light, const Vec3& view, int l) {
  // Below the horizon: zero; grazing directions (z down to -1e-6, fill_pbsdf's rounding of the
  // float32 grid) are read at theta = 90 degrees.
  constexpr double kGrazing = 1e-6;
  if (light.z() < -kGrazing || view.z() < -kGrazing) return Mueller::Zero();
  // Turn the pair about the normal so that the light has the measured azimuth; stokes_frame turns
  // with the directions, so the matrix in microsim's frames is that of the turned pair.
  const double turn = t.phi_i[0] - std::atan2(light.y(), light.x());
  const Vec3 wo = turn_about_normal(view, turn);
  const double theta = std::acos(std::clamp(light.z() / light.norm(), -1.0, 1.0));
  const auto& th = t.theta_i;
  const int n = static_cast<int>(th.size());
  if (n == 1 || theta <= th.front()) return incidence_mueller(t, 0, wo, l);
  if (theta >= th.back()) return incidence_mueller(t, n - 1, wo, l);
  const int k = static_cast<int>(std::upper_bound(th.begin(), th.end(), theta) - th.begin()) - 1;
  const double w = (theta - th[k]) / (th[k + 1] - th[k]);
  return (1 - w) * incidence_mueller(t, k, wo, l) + w * incidence_mueller(t, k + 1, wo, l);
}

PolarizedTable measured_pbsdf(const BsdfTable& t, int table_resolution) {
  check_measured_table(t);
  const BsdfResult& r0 = t.results.front();
  std::vector<std::uint16_t> nm;
  const bool spectral = r0.polarization->wavelengths > 1 || !r0.options.wavelengths_nm.empty();
  if (spectral) {
    if (r0.options.wavelengths_nm.size() != kPbsdfWavelengths)
      throw ParameterError("{wavelengths}: Mitsuba's measured_polarized reads exactly " + std::to_string(kPbsdfWavelengths) +
                           " wavelengths for {output} .pbsdf (got " + std::to_string(r0.options.wavelengths_nm.size()) + ")");
    for (double x : r0.options.wavelengths_nm) {
      if (x != std::round(x) || x < 1 || x > 65535)
        throw ParameterError("{wavelengths}: a .pbsdf stores whole nanometres");
      nm.push_back(static_cast<std::uint16_t>(x));
    }
  } else {
    nm = pbsdf_single_index_wavelengths();
  }
  // The wavelength index of each written wavelength: the run's own, or its single index.
  std::vector<int> index_of(nm.size(), 0);
  if (spectral)
    for (std::size_t l = 0; l < nm.size(); ++l) index_of[l] = static_cast<int>(l);
  const PbsdfGrid g = pbsdf_grid(table_resolution);
  const std::vector<std::uint16_t> written = nm;
  return fill_pbsdf(evenly_spaced(0, 0.5 * kPi, g.theta_h), evenly_spaced(0, 0.5 * kPi, g.theta_d),
                    evenly_spaced(-kPi, kPi, g.phi_d), nm, [&](const Vec3& light, const Vec3& view, double w) {
                      const auto at = std::find(written.begin(), written.end(), static_cast<std::uint16_t>(w));
                      return measured_mueller(t, light, view, index_of[static_cast<std::size_t>(at - written.begin())]);
                    });
}

}  // namespace microsim
