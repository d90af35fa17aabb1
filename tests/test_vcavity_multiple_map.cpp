// Tests of the V-cavity multiple-scattering maps (measure/vcavity_multiple_map.hpp): the V-groove
// closed form [Xie18] binned on the equal-area hemisphere map and averaged over grooves
// ([Heitz14, Sec. 6]: weight (n.m) D(m)).
//
// Independent route: `measure bsdf` traces a V-cavity ensemble (generate_vcavity) groove by groove
// with the explicit tracer; the expectation of its maps is the groove-list map of the same
// ensemble's grooves, and the nominal model differs from that by the groove sampling only (the
// between-groove spread). Both comparisons are per order and pixel, Sidak-corrected Student t
// thresholds on the replicate errors, with a wrong variant that must fail.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/compensation_maps.hpp"
#include "microsim/measure/stats.hpp"
#include "microsim/measure/vcavity_multiple_map.hpp"
#include "microsim/models/vgroove_multiple.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/trace/tracer.hpp"

namespace {

using namespace microsim;
namespace mm = microsim::models;

Vec3 dir(double theta_deg, double phi_deg) {
  const double t = rad(theta_deg), p = rad(phi_deg);
  return Vec3(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
}

TEST(VCavityMultipleMap, MirrorTotalIsOneAndSlotsAddUp) {
  // White furnace: with F = 1 every ray leaves a groove upward, so the total albedo is 1.
  const HemisphereMap map(16);
  for (const mm::Ndf& ndf : {mm::Ndf::beckmann(0.5, 0.5), mm::Ndf::ggx(1.0, 1.0)})
    for (double th : {0.0, 60.0, 80.0}) {
      const GrooveLobeMaps g = vcavity_multiple_maps(ndf, mm::Material::mirror(), dir(th, 0), map, 4, 256, 256);
      EXPECT_NEAR(g.albedo[4], 1.0, 1e-12) << th;
      EXPECT_NEAR(g.albedo_from_order(1), 1.0, 1e-12);
      EXPECT_NEAR(map_albedo(map, g.f[4]), 1.0, 1e-12);
      const std::vector<double> all = g.f_from_order(1);
      for (int px = 0; px < map.size(); ++px) EXPECT_NEAR(all[px], g.f[4][px], 1e-12 * (1 + g.f[4][px]));
      EXPECT_NEAR(g.albedo_from_order(2), 1.0 - g.albedo[0], 1e-12);
    }
  // A conductor loses light at every bounce: its total is below 1.
  const GrooveLobeMaps c =
      vcavity_multiple_maps(mm::Ndf::beckmann(0.5, 0.5), mm::Material::conductor(0.47, 2.4), dir(60, 0), map, 4, 256, 256);
  EXPECT_LT(c.albedo[4], 0.8);
}

TEST(VCavityMultipleMap, AlbedoEqualsTheGrooveAverageOfTheClosedForm) {
  // The map's albedo per slot against vcavity_multiple_albedo (the midpoint rule on 1024 x 256
  // normals), within the quadratures' error; a 1% change of orders >= 2 is seen.
  const HemisphereMap map(16);
  const mm::Material mats[2] = {mm::Material::mirror(), mm::Material::conductor(0.47, 2.4)};
  for (const mm::Ndf& ndf : {mm::Ndf::beckmann(1.0, 1.0), mm::Ndf::ggx(0.7, 0.7)})
    for (const mm::Material& mat : mats)
      for (double th : {0.0, 80.0}) {
        const GrooveLobeMaps g = vcavity_multiple_maps(ndf, mat, dir(th, 30), map, 4);
        const std::vector<double> a = mm::vcavity_multiple_albedo(ndf, dir(th, 30), mat, 4);
        for (int k = 0; k <= 4; ++k) EXPECT_NEAR(g.albedo[k], a[k], 1e-5) << th << " slot " << k;
        const double ms = a[1] + a[2] + a[3];
        if (ms > 0.01) {
          EXPECT_GT(std::abs(g.albedo_from_order(2) - 1.01 * ms), 1e-5);
        }
      }
}

TEST(VCavityMultipleMap, QuadratureIsConvergedPerPixel) {
  // 1024^2 normals (the default) against 2048^2 (another stratified sample), orders >= 2: the
  // Hellinger distance of the two maps below 1e-3 (the study's noise floors are 0.013 and above), and
  // every pixel holding more than the mean within 1% of the finer map. (A regular grid of normals,
  // unjittered, was off by up to 5.5% of the mean: at normal incidence the beams leave at the grid's
  // azimuths.)
  const HemisphereMap map(16);
  for (const mm::Ndf& ndf : {mm::Ndf::beckmann(0.1, 0.1), mm::Ndf::beckmann(1.0, 1.0), mm::Ndf::ggx(0.3, 0.3)})
    for (double th : {0.0, 80.0}) {
      const auto f1 = vcavity_multiple_maps(ndf, mm::Material::mirror(), dir(th, 0), map, 4).f_from_order(2);
      const auto f2 = vcavity_multiple_maps(ndf, mm::Material::mirror(), dir(th, 0), map, 4, 2048, 2048).f_from_order(2);
      double mean = 0, worst = 0;
      for (int px = 0; px < map.size(); ++px) mean += f2[px] / map.size();
      if (mean < 1e-9) continue;  // no light in orders >= 2 (Beckmann 0.1 at normal incidence)
      for (int px = 0; px < map.size(); ++px)
        if (f2[px] > mean) worst = std::max(worst, std::abs(f1[px] - f2[px]) / f2[px]);
      const double h = hellinger_distance(map, f1, f2);
      std::printf("[ info ] alpha %.1f theta %.0f: H %.1e, worst relative pixel difference %.1e\n", ndf.alpha_x, th,
                  h, worst);
      EXPECT_LT(h, 1e-3);
      EXPECT_LT(worst, 1e-2);
    }
}

// Per order (slots 0 .. K-1) and pixel: the largest |t| of measured - model over the cells where
// either carries power, the error being the measurement's and, if given, the groove sampling's
// (the between-groove spread of the ensemble's own grooves).
struct MapComparison {
  double worst_t = 0.0;
  int cells = 0;
};
MapComparison compare_maps(const BsdfResult& r, const GrooveLobeMaps& g, const GrooveLobeMaps* groove_spread) {
  MapComparison c;
  const int K = r.options.orders;
  for (int k = 0; k < K; ++k)
    for (int px = 0; px < r.map.size(); ++px) {
      const Estimate e = r.f_pixel(0, k, px);
      const double model = g.f[k][px];
      if (e.mean == 0 && model == 0) continue;
      const double ci = r.map.pixel_cos_integral(px);
      // A cell that no path reached is known to the resolution of the path count, and one that no
      // groove reached to that of the groove count (a groove puts at most its whole power there).
      double se = std::max(e.stderr_, proportion_floor(r.measured.paths) / ci);
      if (groove_spread)
        se = std::hypot(se, std::max(groove_spread->f_stderr[k][px], proportion_floor(groove_spread->grooves) / ci));
      c.worst_t = std::max(c.worst_t, std::abs(e.mean - model) / se);
      ++c.cells;
    }
  return c;
}

TEST(VCavityMultipleMap, TracedEnsembleEqualsItsGroovesAndTheNominalModel) {
  VCavityParams vp;
  vp.alpha_x = vp.alpha_y = 0.7;
  vp.grooves = 1024;
  const Microsurface s = generate_vcavity(vp);
  std::vector<Vec3> normals;
  for (std::size_t k = 0; k < s.num_facets() / 4; ++k) normals.push_back(vcavity_groove_normal(s, k));
  const Tracer tracer(s);
  const mm::Material mats[2] = {mm::Material::mirror(), mm::Material::conductor(0.47, 2.4)};
  for (const mm::Material& mat : mats)
    for (double th : {0.0, 60.0}) {
      BsdfOptions o;
      o.theta_i = rad(th);
      o.rays = 400000;
      o.resolution = 8;
      o.material = mat;
      const BsdfResult r = measure_bsdf(tracer, o);
      const HemisphereMap& map = r.map;
      const GrooveLobeMaps own = groove_ensemble_maps(normals, mat, r.wi, map, o.orders);
      const GrooveLobeMaps nominal = vcavity_multiple_maps(mm::Ndf::beckmann(0.7, 0.7), mat, r.wi, map, o.orders);
      // Wrong variants: the grooves lit from 10 deg further round; the nominal model of GGX.
      const GrooveLobeMaps turned = groove_ensemble_maps(normals, mat, dir(th + 5, 10), map, o.orders);
      const GrooveLobeMaps ggx = vcavity_multiple_maps(mm::Ndf::ggx(0.7, 0.7), mat, r.wi, map, o.orders);
      const MapComparison a = compare_maps(r, own, nullptr), b = compare_maps(r, nominal, &own);
      const MapComparison wa = compare_maps(r, turned, nullptr), wb = compare_maps(r, ggx, &own);
      const double dof = o.replicates - 1;
      const double ta = sidak_t(0.001, a.cells, dof), tb = sidak_t(0.001, b.cells, dof);
      std::printf("[ info ] theta %.0f %s: own grooves max|t| %.2f (%d cells, threshold %.2f), nominal %.2f; "
                  "wrong: turned %.2f, ggx %.2f\n", th, mat.reflectance(1.0, true) < 1 ? "conductor" : "mirror",
                  a.worst_t, a.cells, ta, b.worst_t, wa.worst_t, wb.worst_t);
      EXPECT_LT(a.worst_t, ta);
      EXPECT_LT(b.worst_t, tb);
      EXPECT_GT(wa.worst_t, ta);
      EXPECT_GT(wb.worst_t, tb);
      // Albedo of orders >= 2: the traced ensemble against its grooves' closed form.
      double traced = 0;
      for (int k = 1; k < o.orders; ++k) traced += r.albedo(0, k).mean;
      const double se = r.albedo(0, o.orders).stderr_ + r.albedo(0, 0).stderr_;  // bounds the sum's error
      EXPECT_LT(std::abs(traced - own.albedo_from_order(2)), 4 * se + 1e-12);
    }
}

}  // namespace
