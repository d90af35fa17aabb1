#include "microsim/io/pbsdf.hpp"

#include <tbb/parallel_for.h>

#include <cmath>
#include <cstring>
#include <limits>

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

}  // namespace microsim
