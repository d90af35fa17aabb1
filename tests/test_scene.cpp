// The Scene interface (trace/scene.hpp) and the ensemble scene (trace/scene_ensemble.hpp): the
// kind of each surface, the hits and facets a scene reports, and an ensemble of V-grooves run
// through the ensemble estimators against the V-groove's exact masking.
#include <gtest/gtest.h>

#include <cmath>

#include "microsim/measure/ensemble_estimators.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/models/vgroove_multiple.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/trace/scene.hpp"
#include "microsim/trace/scene_ensemble.hpp"
#include "test_helpers.hpp"

using namespace microsim;
using namespace microsim::testing;

TEST(Scene, EachKindOfSurfaceGetsItsOwnRuleAtTheRegionBorder) {
  const Microsurface tile = beckmann_tile(32, 3);
  Microsurface window = beckmann_tile(64, 5);
  window.set_sample_region(4, 60, 4, 60, false);
  const Microsurface box = generate_box(BoxParams{});
  const Tracer t_tile(tile), t_window(window), t_box(box);
  EXPECT_EQ(make_scene(t_tile)->region_exit(), RegionExit::Wrap);
  EXPECT_EQ(make_scene(t_window)->region_exit(), RegionExit::SideExit);
  EXPECT_EQ(make_scene(t_box)->region_exit(), RegionExit::Escape);
  EXPECT_EQ(make_scene(t_window)->num_facets(), window.num_facets());
  EXPECT_DOUBLE_EQ(make_scene(t_box)->macro_area(), box.macro().area);
}

TEST(Scene, TracerSceneHitsAreTheTracersAndItsFacetsTheSurfaces) {
  const Microsurface s = beckmann_tile(32, 7);
  const Tracer tracer(s);
  const auto scene = make_scene(tracer);
  const Vec3 v = direction_from_angles(rad(50), rad(20));
  const RayWindow w = scene->ray_window(v);
  const RayWindow ref = make_ray_window(tracer, v);
  EXPECT_EQ(w.origin0, ref.origin0);
  TraceCounters a, b;
  int hits = 0;
  for (int k = 0; k < 200; ++k) {
    const Vec3 org = w.origin0 + (k % 20 + 0.5) / 20 * w.e1 + (k / 20 + 0.5) / 10 * w.e2;
    const TraceHit h = scene->intersect(org, -v, nullptr, a);
    const TraceHit g = tracer.first_hit(org, -v, nullptr, b);
    ASSERT_EQ(h.hit, g.hit);
    ASSERT_EQ(h.facet, g.facet);
    const std::size_t f = scene->front_facet(h);
    if (h.hit && !h.backface) {
      ASSERT_EQ(f, h.facet);
      ++hits;
    } else {
      ASSERT_EQ(f, Scene::kNoFacet);
    }
  }
  EXPECT_GT(hits, 150);
  EXPECT_EQ(a.rays, b.rays);
  // A facet's point lies on its plane, and its normal and area are the surface's.
  for (std::size_t f : {std::size_t(0), std::size_t(17), s.num_facets() - 1}) {
    const SourcePlane p = scene->facet_plane(f);
    EXPECT_NEAR(p.normal.dot(scene->facet_point(f, 0.3, 0.6)) - p.offset, 0.0, 1e-12);
    EXPECT_EQ(scene->facet_normal(f), s.facet(f).normal());
    EXPECT_DOUBLE_EQ(scene->facet_area(f), s.facet(f).area());
  }
  // A back face, or a hit past the measured region's facets, names no facet of the scene.
  TraceHit back;
  back.hit = true;
  back.backface = true;
  EXPECT_EQ(scene->front_facet(back), Scene::kNoFacet);
  TraceHit outside;
  outside.hit = true;
  outside.facet = s.num_facets();
  EXPECT_EQ(scene->front_facet(outside), Scene::kNoFacet);
}

TEST(Scene, VGrooveSidesHaveTheGroovesAreasNormalsAndPoints) {
  const float top = 0.4f;  // tan(theta) / 2 with tan(theta) = 0.8
  const VGrooveScene g(top);
  const double side = std::sqrt(0.25 + static_cast<double>(top) * top);  // slant x ridge length 1
  EXPECT_NEAR(g.facet_area(0), side, 1e-6);
  EXPECT_NEAR(g.facet_area(1), side, 1e-6);
  EXPECT_GT(g.facet_normal(1).x(), 0);  // side 1 (x > 0) descends toward +x
  EXPECT_LT(g.facet_normal(0).x(), 0);
  for (int s = 0; s < 2; ++s) {
    const Vec3 p = g.facet_point(s, 0.7, 0.2);
    EXPECT_NEAR(g.facet_plane(s).normal.dot(p) - g.facet_plane(s).offset, 0.0, 1e-6);
    EXPECT_EQ(p.x() > 0, s == 1);
  }
  // A ray straight down on side 1 meets side 1.
  TraceCounters c;
  const TraceHit h = g.intersect(Vec3(0.25, 0.1, g.tracer().z_top()), -Vec3::UnitZ(), nullptr, c);
  EXPECT_EQ(g.front_facet(h), 1u);
}

TEST(SceneEnsemble, PartsArePickedByWeight) {
  SceneEnsemble e(3.0);
  for (double w : {1.0, 1.0, 1.0})
    e.add_part({}, w, [] { return std::make_unique<VGrooveScene>(0.1f); }, {Vec3::UnitZ()}, {1.0});
  EXPECT_TRUE(e.equal_weights());
  EXPECT_EQ(e.part_at(0.0), 0u);
  EXPECT_EQ(e.part_at(0.5), 1u);
  EXPECT_EQ(e.part_at(0.999), 2u);
  SceneEnsemble u(4.0);
  for (double w : {1.0, 3.0})
    u.add_part({}, w, [] { return std::make_unique<VGrooveScene>(0.1f); }, {Vec3::UnitZ()}, {1.0});
  EXPECT_FALSE(u.equal_weights());
  EXPECT_EQ(u.part_at(0.2), 0u);  // the first quarter
  EXPECT_EQ(u.part_at(0.3), 1u);
  EXPECT_EQ(u.part(1).first_facet, 1u);
  // The estimators spread rays evenly: unequal parts are refused.
  G1Options o;
  o.rays = 1000;
  EXPECT_THROW(measure_g1(u, {Vec3::UnitZ()}, o), UsageError);
}

TEST(SceneEnsemble, VcavityGroovesAreTheStoredStrips) {
  VCavityParams p;
  p.grooves = 16;
  const Microsurface s = generate_vcavity(p);
  const SceneEnsemble e = vcavity_grooves(s, "test", GrooveFrames::StoredNormalOverHypot);
  ASSERT_EQ(e.parts(), 16u);
  ASSERT_EQ(e.num_facets(), 32u);
  for (std::size_t k = 0; k < 16; ++k) {
    EXPECT_EQ(e.facet_normal(2 * k + 1), s.facet(4 * k).normal());
    EXPECT_EQ(e.facet_normal(2 * k), s.facet(4 * k + 2).normal());
    // The part's frame takes m_k to its own x-z plane, on side 1 (x > 0).
    const Vec3 ml = e.part(k).frame.to_local(e.facet_normal(2 * k + 1));
    EXPECT_NEAR(ml.y(), 0.0, 1e-12);
    EXPECT_GE(ml.x(), 0.0);
  }
  EXPECT_THROW(vcavity_grooves(beckmann_tile(16, 1), "test", GrooveFrames::OfModel), UsageError);
}

// One V-groove as an ensemble of one part: the ensemble G1 estimators' G1 of the side facing v
// is the V-groove's exact masking, the V-cavity G1 of its normal [Heitz14, eq. 24]; the other
// side faces away and draws no samples.
TEST(SceneEnsemble, OneGrooveMeasuresTheVGroovesExactMasking) {
  const double theta = rad(40), tan_t = std::tan(theta);
  const Vec3 m1(std::sin(theta), 0, std::cos(theta)), m0(-std::sin(theta), 0, std::cos(theta));
  SceneEnsemble e(1.0);
  const double area = 0.5 / std::cos(theta);
  e.add_part({}, 1.0, [tan_t] { return std::make_unique<VGrooveScene>(static_cast<float>(0.5 * tan_t)); },
             {m0, m1}, {area, area});
  G1Options o;
  o.rays = 200000;
  o.normal_phi_bins = 2;  // m0 and m1 in different bins
  const Vec3 v = direction_from_angles(rad(70), 0);  // toward +x: the wall beyond the valley masks side 1
  const G1Result r = measure_g1(e, {v}, o).at(0);
  const double g1 = models::vcavity_G1(v, m1);
  ASSERT_LT(g1, 0.9);  // a case where masking matters
  const int b0 = r.binning.bin_of(m0), b1 = r.binning.bin_of(m1);
  ASSERT_NE(b0, b1);
  EXPECT_EQ(r.bins[b0].samples, 0u);
  EXPECT_EQ(r.bins[b0].raycast_hits, 0u);
  const Estimate sampled = r.bin_g1_area_sampling(b1), cast = r.bin_g1_raycast(b1);
  EXPECT_NEAR(sampled.mean, g1, 4 * sampled.stderr_ + 1e-4);
  EXPECT_NEAR(cast.mean, g1, 4 * cast.stderr_ + 1e-4);
  EXPECT_GT(sampled.stderr_, 0.0);
}
