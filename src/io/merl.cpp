#include "microsim/io/merl.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>
#include <cmath>
#include <cstdint>
#include <fstream>

#include "microsim/io/output.hpp"
#include "microsim/models/spectral_rgb.hpp"

namespace microsim {

double table_f(const BsdfTable& t, const Vec3& wi0, const Vec3& wo0, int lambda) {
  if (t.phi_i.size() != 1) throw ParameterError("MERL tables are isotropic: give one {phi_i}");
  if (wi0.z() <= 0 || wo0.z() <= 0) return 0.0;
  // Turn the pair about the normal so that wi has the measured azimuth.
  const double turn = t.phi_i[0] - std::atan2(wi0.y(), wi0.x());
  const double c = std::cos(turn), s = std::sin(turn);
  const Vec3 wo(c * wo0.x() - s * wo0.y(), s * wo0.x() + c * wo0.y(), wo0.z());
  const double theta = std::acos(std::clamp(wi0.z() / wi0.norm(), -1.0, 1.0));
  const auto& th = t.theta_i;
  const int K = t.results[0].options.orders;
  const int n = static_cast<int>(th.size());
  if (n == 1 || theta <= th.front()) return table_f(t, 0, 0, 0, K, wo, lambda);
  if (theta >= th.back()) return table_f(t, 0, n - 1, 0, K, wo, lambda);
  const int k = static_cast<int>(std::upper_bound(th.begin(), th.end(), theta) - th.begin()) - 1;
  const double w = (theta - th[k]) / (th[k + 1] - th[k]);
  return (1 - w) * table_f(t, 0, k, 0, K, wo, lambda) + w * table_f(t, 0, k + 1, 0, K, wo, lambda);
}

namespace {
// Calls cell(index, wi, wo) for every cell (in parallel), the pair as merl.hpp describes.
template <class Cell>
void for_each_merl_cell(const BsdfTable& t, Cell&& cell) {
  if (t.phi_i.size() != 1)
    throw ParameterError("{output} .binary: MERL tables are isotropic; this table has " +
                         std::to_string(t.phi_i.size()) + " incidence azimuths (give one {phi_i})");
  for (std::size_t k = 1; k < t.theta_i.size(); ++k)
    if (!(t.theta_i[k] > t.theta_i[k - 1])) throw ParameterError("{theta_i} must be increasing for a .binary");
  tbb::parallel_for(0, kMerlThetaH, [&](int ih) {
    const double u = (ih + 0.5) / kMerlThetaH, th = u * u * 0.5 * kPi;
    const double ch = std::cos(th), sh = std::sin(th);
    const Vec3 h(sh, 0.0, ch);
    for (int id = 0; id < kMerlThetaD; ++id) {
      const double td = (id + 0.5) / kMerlThetaD * 0.5 * kPi;
      for (int ip = 0; ip < kMerlPhiD; ++ip) {
        const double pd = (ip + 0.5) / kMerlPhiD * kPi;
        const Vec3 d = direction_from_angles(td, pd);
        // wi = R_y(theta_h) d: the difference vector seen from the half vector's frame.
        Vec3 wi(d.x() * ch + d.z() * sh, d.y(), -d.x() * sh + d.z() * ch);
        Vec3 wo = 2.0 * wi.dot(h) * h - wi;
        // Reciprocity [GeomBSDF24, eq. 4c]: read the pair with the light at the smaller zenith angle,
        // which the measured incidences cover best.
        if (wo.z() > wi.z()) std::swap(wi, wo);
        cell(static_cast<std::size_t>(ip) + kMerlPhiD * (id + static_cast<std::size_t>(kMerlThetaD) * ih), wi, wo);
      }
    }
  });
}
}  // namespace

std::vector<double> merl_cells(const BsdfTable& t) {
  std::vector<double> cells(kMerlCells, 0.0);
  for_each_merl_cell(t, [&](std::size_t c, const Vec3& wi, const Vec3& wo) { cells[c] = table_f(t, wi, wo); });
  return cells;
}

std::array<std::vector<double>, 3> merl_rgb_cells(const BsdfTable& t) {
  const int L = t.results.front().wavelengths();
  if (L == 0) {
    std::vector<double> f = merl_cells(t);
    return {f, f, std::move(f)};
  }
  const models::SpectrumToRgb colour(t.results.front().options.wavelengths_nm);
  std::array<std::vector<double>, 3> rgb;
  for (auto& c : rgb) c.assign(kMerlCells, 0.0);
  for_each_merl_cell(t, [&](std::size_t c, const Vec3& wi, const Vec3& wo) {
    double f[kMaxWavelengths];
    for (int l = 0; l < L; ++l) f[l] = table_f(t, wi, wo, l);
    const auto v = colour.rgb(f);
    for (int ch = 0; ch < 3; ++ch) rgb[ch][c] = v[ch];
  });
  return rgb;
}

void write_merl(const std::string& path, const BsdfTable& t) {
  const std::array<std::vector<double>, 3> rgb = merl_rgb_cells(t);
  write_stream_atomically(path, [&](std::ofstream& out) {
    const std::int32_t dims[3] = {kMerlThetaH, kMerlThetaD, kMerlPhiD};
    out.write(reinterpret_cast<const char*>(dims), sizeof(dims));
    std::vector<double> block(kMerlCells);
    for (int c = 0; c < 3; ++c) {
      const std::vector<double>& f = rgb[c];
      for (std::size_t k = 0; k < f.size(); ++k) block[k] = f[k] / kMerlScale[c];
      out.write(reinterpret_cast<const char*>(block.data()), static_cast<std::streamsize>(block.size() * sizeof(double)));
    }
  });
}

}  // namespace microsim
