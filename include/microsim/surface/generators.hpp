// Generators of structured microsurfaces: the exact references of the estimators and the
// surfaces on which microfacet theory shows its limits ([GeomBSDF24, "Distribution of Normals",
// "Inherent Assumptions", Fig. 2, 3, 5, 6]; [Heitz14, Sec. 6]; [TSBlog24, "GGX as an ellipsoid"]).
//
// Axes: x to the right, y into the page, z = the macrosurface normal n. Finite objects stand on
// the plane z = 0, centered on the origin; their macrosurface is their base (periodic = false).
// Periodic tiles are centered on the origin. Every generator validates its parameters first and
// throws UsageError with one line naming the option and its accepted range.
#pragma once
#include <cstdint>
#include <string>

#include "microsim/surface/microsurface.hpp"

namespace microsim {

// flat: a periodic plane z = 0 (every estimator's exact reference: D a delta at n, G1 = 1,
// visible area ratio 1, Fresnel reflection and refraction only).
struct FlatParams {
  int resolution = 16;  // grid cells per side (the plane is exact at any resolution)
  double size = 1.0;
};
Microsurface generate_flat(const FlatParams& p);

// box: the box of [GeomBSDF24, Fig. 2]. Top and four walls (outward normals); the flipped bottom face is
// the macrosurface: n = +z, A = W D, finite. Seen across a face at theta, its visible area ratio
// is 1 + (H/W) tan(theta) [GeomBSDF24, "Inherent Assumptions", Fig. 5].
// tiled-boxes: the same macrosurface covered by N x N copies of the box scaled by 1/N
// [GeomBSDF24, Fig. 6]: the same D, but the visible area ratio 1 + (H/(N W)) tan(theta) tends to 1. Copies
// are separate closed-but-for-the-base components; touching walls coincide.
struct BoxParams {
  double width = 1.0;   // W, along x
  double depth = 1.0;   // D, along y
  double height = 1.0;  // H, along z
  int tiles = 1;        // N (tiled-boxes)
};
Microsurface generate_box(const BoxParams& p);
Microsurface generate_tiled_boxes(const BoxParams& p);

// parallelepiped: boxes under a linear map p -> L p [GeomBSDF24, Fig. 3]. L keeps the base plane:
// its third row must be (0, 0, l33) with l33 > 0, so the macrosurface stays z = 0 with normal
// +z; A is the mapped base's area. Shears (l13, l23 != 0) tilt the walls; one of each pair then
// faces downward (n.m < 0). tiles > 1 maps N x N tiled boxes (sheared walls of neighbours
// coincide, the upward-facing ones are occluded from above: G1(n, m) < 1).
struct ParallelepipedParams {
  double width = 1.0, depth = 1.0, height = 1.0;
  double matrix[9] = {1, 0, 0.5, 0, 1, 0, 0, 0, 1};  // row-major L (default: shear x += z/2)
  int tiles = 1;
};
Microsurface generate_parallelepiped(const ParallelepipedParams& p);

// square-wave: periodic ridges (duty F of the period P raised by H, vertical walls) running
// along y; the tile is one period, P x P. --2d: raised square blocks F P x F P in each P x P
// cell. Built as a periodic mesh (vertical walls).
struct SquareWaveParams {
  double period = 1.0;
  double duty = 0.5;  // in (0, 1)
  double height = 0.5;
  bool two_d = false;
};
Microsurface generate_square_wave(const SquareWaveParams& p);

// vgroove: periodic V-grooves running along y with facet normals (+-sin tm, 0, cos tm), the
// surface on which [Heitz14, eq. 24] is exact; a heightfield with one period per tile (2 x 2 cells,
// each facet planar). --2d: square pyramids (faces (+-sin tm, 0, cos tm), (0, +-sin tm, cos tm)),
// a periodic mesh.
struct VGrooveParams {
  double facet_angle_deg = 45.0;  // theta_m in (0, 90)
  double period = 1.0;
  bool two_d = false;
};
Microsurface generate_vgroove(const VGrooveParams& p);

// ellipsoid: the upper half of (ax x)^2 + (ay y)^2 + z^2 = 1 (semi-axes 1/ax, 1/ay, 1), a
// finite object on its base ellipse (n = +z, A = the base polygon's area ~ pi / (ax ay)).
// Its normal distribution is GGX(ax, ay) and its front-facing projected areas give GGX's
// Lambda ([TSBlog24, "GGX"], ellipsoid p^T A^T A p = C^2 with A = diag(ax, ay, 1)). Tessellated as the
// image p = A^-1 u of a latitude-longitude mesh of the unit hemisphere u (facet normals are
// then A n_u, exactly the map of normals of [TSBlog24]).
struct EllipsoidParams {
  double alpha_x = 0.5, alpha_y = 0.5;
  // Each band between two rings holds exactly GGX's mass of normals; an isotropic band's facets
  // share one theta_m, so D over a fixed theta bin is off GGX by O(1/rings) (the two bands its
  // edges cut; 8.5% over 5 degree bins at 256 rings, docs/theory/ndf.md). 10 degree x 45 degree
  // bins at 192 x 768 pass a chi^2 with 3e6 vertical rays (tests/test_generators.cpp).
  int rings = 256;      // latitude steps of the hemisphere (0..90 deg)
  int segments = 1024;  // longitude steps
};
Microsurface generate_ellipsoid(const EllipsoidParams& p);

// vcavity: the V-cavity model made explicit [Heitz14, Sec. 6.1]: K separate V-grooves whose normal
// pairs (m, m' = (-mx, -my, mz)) are drawn from D (Beckmann or GGX) weighted by projected area
// (n.m) D(m), i.e. each groove covers the same macro area. The surface is stored as K separate
// strips (one period of each groove, unit period and length, laid out on a grid, description
// kind "vcavity"): their facets give the ensemble's D exactly (measure ndf, info), and
// measure g1 traces each groove on its own as an infinite periodic V-groove
// (measure_g1 on its vcavity_grooves, measure/ensemble_estimators.hpp).
struct VCavityParams {
  std::string ndf = "beckmann";  // beckmann | ggx
  double alpha_x = 0.5, alpha_y = 0.5;
  int grooves = 4096;
  std::uint64_t seed = 1;
};
Microsurface generate_vcavity(const VCavityParams& p);
// The normal m_k of groove k of a vcavity surface (facet 4k of the stored strips).
Vec3 vcavity_groove_normal(const Microsurface& s, std::size_t k);
bool is_vcavity(const Microsurface& s);

// gaussian-ggx: see surface/gaussian.hpp (generate_gaussian_ggx).

}  // namespace microsim
