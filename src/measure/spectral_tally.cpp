#include "microsim/measure/spectral_tally.hpp"

#include <algorithm>

#include "microsim/tally_fields.hpp"

namespace microsim {

SpectralTally::SpectralTally(int L, int K, int npix, int nplane)
    : wavelengths(L), orders(K), pixels(npix), plane_bins(nplane) {
  const std::size_t s = 2 * static_cast<std::size_t>(K + 1) * L;
  albedo.assign(s, 0.0);
  pix.assign(s * npix, 0.0);
  plane.assign(s * nplane, 0.0);
}

void SpectralTally::add_exit(int s, int order, const double* w, int px, int b) {
  const int k = std::min(order, orders) - 1;
  const std::size_t L = wavelengths;
  for (int slot : {k, orders}) {
    const std::size_t sk = static_cast<std::size_t>(s) * slots() + slot;
    double* a = &albedo[sk * L];
    for (std::size_t l = 0; l < L; ++l) a[l] += w[l];
    if (px >= 0) {
      double* p = &pix[(sk * pixels + px) * L];
      for (std::size_t l = 0; l < L; ++l) p[l] += w[l];
    }
    if (b >= 0) {
      double* q = &plane[(sk * plane_bins + b) * L];
      for (std::size_t l = 0; l < L; ++l) q[l] += w[l];
    }
  }
}

SpectralTally& SpectralTally::operator+=(const SpectralTally& o) {
  if (albedo.empty()) return *this = o;
  if (o.albedo.empty()) return *this;
  add_fields(*this, o);
  return *this;
}

BsdfTally SpectralTally::wavelength(int l) const {
  BsdfTally t(orders, pixels, plane_bins);
  const std::size_t L = wavelengths;
  for (std::size_t i = 0; i < t.albedo.size(); ++i) t.albedo[i] = albedo[i * L + l];
  for (std::size_t i = 0; i < t.pix.size(); ++i) t.pix[i] = pix[i * L + l];
  for (std::size_t i = 0; i < t.plane.size(); ++i) t.plane[i] = plane[i * L + l];
  put_path_counts(t);
  return t;
}

void SpectralTally::put_path_counts(BsdfTally& t) const {
  t.paths = paths;
  t.lost = lost;
  t.unterminated = unterminated;
  t.events = events;
  t.counters = counters;
}

}  // namespace microsim
