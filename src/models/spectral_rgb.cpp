#include "microsim/models/spectral_rgb.hpp"

#include <cmath>
#include <stdexcept>

namespace microsim::models {

namespace {

// [Wyman13], the multi-lobe fit: a Gaussian with different widths left and right of its peak.
double piecewise_gaussian(double x, double mu, double sigma_left, double sigma_right) {
  const double t = (x - mu) / (x < mu ? sigma_left : sigma_right);
  return std::exp(-0.5 * t * t);
}

// [SRGB99]: XYZ to linear sRGB (BT.709 primaries, D65 white).
constexpr double kXyzToSrgb[3][3] = {
    {3.2406, -1.5372, -0.4986}, {-0.9689, 1.8758, 0.0415}, {0.0557, -0.2040, 1.0570}};

constexpr double kFirstNm = 360.0, kLastNm = 830.0;

// Weight of sample l in the linear interpolation of the spectrum at nm (constant beyond the ends).
double hat(const std::vector<double>& nm, std::size_t l, double x) {
  const std::size_t n = nm.size();
  if (n == 1) return 1.0;
  if (x <= nm.front()) return l == 0 ? 1.0 : 0.0;
  if (x >= nm.back()) return l == n - 1 ? 1.0 : 0.0;
  if (l > 0 && x >= nm[l - 1] && x <= nm[l]) return (x - nm[l - 1]) / (nm[l] - nm[l - 1]);
  if (l + 1 < n && x >= nm[l] && x < nm[l + 1]) return (nm[l + 1] - x) / (nm[l + 1] - nm[l]);
  return 0.0;
}

}  // namespace

std::array<double, 3> cie1931_xyz_fit(double nm) {
  const double x = 1.056 * piecewise_gaussian(nm, 599.8, 37.9, 31.0) +
                   0.362 * piecewise_gaussian(nm, 442.0, 16.0, 26.7) -
                   0.065 * piecewise_gaussian(nm, 501.1, 20.4, 26.2);
  const double y = 0.821 * piecewise_gaussian(nm, 568.8, 46.9, 40.5) +
                   0.286 * piecewise_gaussian(nm, 530.9, 16.3, 31.1);
  const double z = 1.217 * piecewise_gaussian(nm, 437.0, 11.8, 36.0) +
                   0.681 * piecewise_gaussian(nm, 459.0, 26.0, 13.8);
  return {x, y, z};
}

SpectrumToRgb::SpectrumToRgb(std::vector<double> wavelengths_nm) : nm_(std::move(wavelengths_nm)) {
  if (nm_.empty()) throw std::invalid_argument("SpectrumToRgb needs at least one wavelength");
  const std::size_t n = nm_.size();
  std::vector<std::array<double, 3>> xyz(n, {0.0, 0.0, 0.0});
  std::array<double, 3> white{0.0, 0.0, 0.0};
  for (double x = kFirstNm; x <= kLastNm; x += 1.0) {
    const auto c = cie1931_xyz_fit(x);
    for (int i = 0; i < 3; ++i) white[i] += c[i];
    for (std::size_t l = 0; l < n; ++l) {
      const double h = hat(nm_, l, x);
      for (int i = 0; i < 3; ++i) xyz[l][i] += h * c[i];
    }
  }
  auto to_rgb = [](const std::array<double, 3>& v) {
    std::array<double, 3> r{};
    for (int i = 0; i < 3; ++i) r[i] = kXyzToSrgb[i][0] * v[0] + kXyzToSrgb[i][1] * v[1] + kXyzToSrgb[i][2] * v[2];
    return r;
  };
  const auto white_rgb = to_rgb(white);
  w_rgb_.resize(n);
  w_y_.resize(n);
  for (std::size_t l = 0; l < n; ++l) {
    const auto r = to_rgb(xyz[l]);
    for (int i = 0; i < 3; ++i) w_rgb_[l][i] = r[i] / white_rgb[i];
    w_y_[l] = xyz[l][1] / white[1];
  }
}

std::array<double, 3> SpectrumToRgb::rgb(const double* s) const {
  std::array<double, 3> out{0.0, 0.0, 0.0};
  for (std::size_t l = 0; l < nm_.size(); ++l)
    for (int i = 0; i < 3; ++i) out[i] += w_rgb_[l][i] * s[l];
  return out;
}

double SpectrumToRgb::luminance(const double* s) const {
  double y = 0.0;
  for (std::size_t l = 0; l < nm_.size(); ++l) y += w_y_[l] * s[l];
  return y;
}

}  // namespace microsim::models
