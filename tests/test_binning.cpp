// The exits' binning without atan2 (measure/bsdf_measure.hpp): azimuth_near within its bound of
// std::atan2, HemisphereMap::pixel_of equal to pixel_of_exact and InPlaneBins::bin_of equal to
// bin_of_exact on random directions and on directions placed at pixel, sector and band borders
// (exactly on them and a few ulps to 1e-9 off), and, as the power of those checks, the same
// fast paths with their margins perturbed disagree with the exact ones on those inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"

using namespace microsim;

namespace {

// Offsets from a border: exactly on it, a few ulps, and up to 1e-9 off either side.
std::vector<double> border_offsets() {
  std::vector<double> o = {0.0};
  for (double e : {1e-16, 2.2e-16, 4.4e-16, 1e-15, 3e-15, 1e-14, 1e-13, 1e-12, 1e-11, 1e-10, 1e-9}) {
    o.push_back(e);
    o.push_back(-e);
  }
  return o;
}

Vec3 random_unit(std::mt19937_64& g) {
  std::normal_distribution<double> n;
  Vec3 v(n(g), n(g), n(g));
  return v.normalized();
}

}  // namespace

TEST(Binning, AzimuthNearIsWithinItsBoundOfAtan2) {
  std::mt19937_64 g(11);
  std::uniform_real_distribution<double> u(-1, 1);
  double worst = 0;
  auto check = [&](double y, double x) {
    const double a = azimuth_near(y, x), b = std::atan2(y, x);
    ASSERT_EQ(std::signbit(a), std::signbit(b)) << y << " " << x;  // the same branch
    worst = std::max(worst, std::abs(a - b));
  };
  for (int k = 0; k < 2000000; ++k) check(u(g), u(g));
  // Ratios at and near the table's sixteenths and their midpoints, the diagonals, the axes,
  // signed zeros and the branch cut (x < 0, y = +-0 or tiny), tiny and huge scales.
  for (int k = 0; k <= 32; ++k)
    for (double e : border_offsets())
      for (double sx : {1.0, -1.0})
        for (double sy : {1.0, -1.0})
          for (double scale : {1.0, 1e-100, 3e100}) {
            const double t = k / 32.0 + e;
            if (t < 0 || t > 1) continue;
            check(sy * t * scale, sx * scale);
            check(sy * scale, sx * t * scale);
          }
  for (double x : {1.0, -1.0, 0.0, -0.0})
    for (double y : {1.0, -1.0, 0.0, -0.0, 1e-300, -1e-300})
      if (x != 0 || y != 0) check(y, x);
  EXPECT_LT(worst, HemisphereMap::kAzimuthError / 50) << worst;
  EXPECT_GT(worst, 0.0);  // not std::atan2 itself: the margins below are needed
}

TEST(Binning, PixelOfEqualsAtan2PixelOnRandomAndBorderDirections) {
  std::mt19937_64 g(12);
  std::uniform_real_distribution<double> u(0, 1);
  for (int res : {1, 2, 5, 16, 64, 4096}) {
    const HemisphereMap map(res);
    long differ_unguarded = 0, near = 0;
    auto check = [&](const Vec3& d) {
      ASSERT_EQ(map.pixel_of(d), map.pixel_of_exact(d)) << res << " " << d.transpose();
      ++near;
      if (map.pixel_of(d, 0.0) != map.pixel_of_exact(d)) ++differ_unguarded;
    };
    for (int k = 0; k < 200000; ++k) {
      Vec3 d = random_unit(g);
      ASSERT_EQ(map.pixel_of(d), map.pixel_of_exact(d)) << res << " " << d.transpose();
      ASSERT_EQ(map.pixel_of(3.5 * d), map.pixel_of_exact(3.5 * d));  // not unit: as to_square
    }
    // Directions whose angular square coordinate is at a pixel border (and off it by the
    // offsets), in every sector and both hemispheres; the radial one random.
    const std::vector<double> off = border_offsets();
    for (int k = 0; k < 20000; ++k) {
      const double edge = -1 + 2.0 * static_cast<int>(u(g) * (res + 1)) / res;
      const double e = edge + off[static_cast<std::size_t>(u(g) * off.size()) % off.size()];
      const double r = (u(g) < 0.5 ? 1 : -1) * (0.02 + 0.98 * u(g));
      Vec3 d = u(g) < 0.5 ? map.from_square(r, std::clamp(e, -std::abs(r), std::abs(r)))
                          : map.from_square(std::clamp(e, -std::abs(r), std::abs(r)), r);
      if (u(g) < 0.5) d.z() = -d.z();
      check(d);
    }
    // Sector borders (diagonals |x| = |y|) with the radius at pixel borders, and the axes.
    for (int k = 0; k < 5000; ++k) {
      const double edge = -1 + 2.0 * static_cast<int>(u(g) * (res + 1)) / res;
      const double r = edge + off[static_cast<std::size_t>(u(g) * off.size()) % off.size()];
      if (std::abs(r) < 1e-3 || std::abs(r) > 1) continue;
      const double s = off[static_cast<std::size_t>(u(g) * off.size()) % off.size()];
      check(map.from_square(r, r * (1 + s)));
      check(map.from_square(r, -r * (1 + s)));
      const double phi = (static_cast<int>(u(g) * 8) + 1) * 0.25 * kPi + s;
      check(Vec3(std::cos(phi), std::sin(phi), 0.3 + u(g)));
      check(Vec3(std::cos(phi) * 1e-5, std::sin(phi) * 1e-5, 1));
    }
    for (const Vec3& d : {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(-1, -0.0, 0.2),
                          Vec3(-1, 0.0, 0.2), Vec3(1e-170, 1e-170, 1)})
      check(d);
    // Power: without its edge margin the atan2-free pixel differs on such directions (for
    // resolutions whose borders are not only the axes and diagonals).
    if (res >= 5) {
      EXPECT_GT(differ_unguarded, 0) << res << " of " << near;
    }
  }
}

TEST(Binning, InPlaneBinOfEqualsExactOnRandomAndBandBorderDirections) {
  std::mt19937_64 g(13);
  std::uniform_real_distribution<double> u(0, 1);
  for (int res : {1, 3, 16, 64, 4096})
    for (double phi_i : {0.0, 0.7, -2.1, kPi}) {
      const InPlaneBins bins(phi_i, res);
      for (int k = 0; k < 50000; ++k) {
        const Vec3 d = random_unit(g);
        ASSERT_EQ(bins.bin_of(d), bins.bin_of_exact(d));
        ASSERT_EQ(bins.bin_of(0.25 * d), bins.bin_of_exact(0.25 * d));  // not unit
      }
      // At the band's border |beta| = delta (and off it), any psi, both sides.
      long differ_shrunk = 0, in_band = 0;
      const std::vector<double> off = border_offsets();
      for (int k = 0; k < 20000; ++k) {
        const double psi = (u(g) - 0.5) * kPi;
        const double e = off[static_cast<std::size_t>(u(g) * off.size()) % off.size()];
        const double beta = (u(g) < 0.5 ? 1 : -1) * (bins.half_width() + e);
        const Vec3 d = bins.direction(psi, beta, u(g) < 0.5) * (u(g) < 0.5 ? 1.0 : 1.7);
        ASSERT_EQ(bins.bin_of(d), bins.bin_of_exact(d)) << d.transpose();
        if (bins.bin_of_exact(d) >= 0) ++in_band;
        if (bins.bin_of(d, -InPlaneBins::kBandMargin) != bins.bin_of_exact(d)) ++differ_shrunk;
      }
      EXPECT_GT(in_band, 0);
      // Power: with the margin reversed, directions just inside the band are thrown out.
      if (res > 1) {
        EXPECT_GT(differ_shrunk, 0) << res;
      }
    }
}
