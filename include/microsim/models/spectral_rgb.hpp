// Colour of a sampled reflectance spectrum: CIE 1931 2-degree XYZ by the multi-lobe analytic fit
// of the colour-matching functions [Wyman13] (its multi-lobe piecewise-Gaussian fit), then linear sRGB
// (ITU-R BT.709 primaries, the XYZ-to-linear-sRGB matrix of [SRGB99]) under the equal-energy illuminant E, white
// balanced by scaling each linear sRGB channel so that a spectrum equal to 1 everywhere (a mirror)
// maps to (1, 1, 1) (a von Kries scaling in the sRGB primaries).
//
// The spectrum between the given wavelengths is linear, and constant beyond the first and the last
// out to the integration range 360 - 830 nm; the integral is a sum at 1 nm steps. The colour is
// linear in the sampled values: rgb = sum_l W[l] s_l with weights W fixed by the wavelengths.
#pragma once
#include <array>
#include <vector>

namespace microsim::models {

// [Wyman13], multi-lobe fit: the CIE 1931 2-degree colour-matching functions at `nm`.
std::array<double, 3> cie1931_xyz_fit(double nm);

class SpectrumToRgb {
 public:
  explicit SpectrumToRgb(std::vector<double> wavelengths_nm);
  int size() const { return static_cast<int>(nm_.size()); }
  // White-balanced linear sRGB of the sampled spectrum `s` (one value per wavelength).
  std::array<double, 3> rgb(const double* s) const;
  std::array<double, 3> rgb(const std::vector<double>& s) const { return rgb(s.data()); }
  // Luminance: Y relative to the white's (1 for a spectrum equal to 1).
  double luminance(const double* s) const;

 private:
  std::vector<double> nm_;
  std::vector<std::array<double, 3>> w_rgb_;  // per wavelength
  std::vector<double> w_y_;
};

}  // namespace microsim::models
