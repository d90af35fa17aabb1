// Closed-form multiple scattering of a symmetric specular V-groove, per scattering order, and its
// average over a distribution of grooves: the V-cavity construction of [Heitz14, Sec. 6] (grooves whose
// facet normals m, m' = (-mx, -my, mz) are drawn with weight (n.m) D(m), every groove covering the
// same macro area) with every interreflection inside the groove kept, as in
// [Xie18]. Header-only.
//
// Groove frame: x across the groove, y along its ridge, z = n. The groove's walls have normals
// (+-sin tf, 0, cos tf) (tf = facet angle); its aperture is the segment between two ridges.
//
// Derivation (2D unfolding). A ray keeps its component along y at every bounce, so the bounce
// count and the exit direction follow from the cross-section (x, z) alone. Let psi = pi/2 - tf be
// the half opening angle, R the wall length, and measure polar angles beta about the groove's
// bottom from +z toward +x: the walls lie at beta = -psi, +psi. The projected travel direction is
// d = (sin t, -cos t) with t = atan2(-lx, lz) (l the light direction). Reflecting the groove
// about its walls again and again unfolds the bouncing path into a straight line through a fan of
// copies; copy j spans beta in [(2j-1) psi, (2j+1) psi], and crossing a wall line is one bounce.
// The copies' apertures form a convex polygon inscribed in the circle of radius R with vertices
// at beta_j = (2j+1) psi; the line enters through the aperture of copy 0 and leaves through the
// aperture of copy n after n bounces.
//   Parameterize the parallel rays by their signed offset s = p x d from the bottom; at the
// vertex beta it is -R sin(beta + t), so write a = sin(u), u = beta + t, and s = -R a. Offsets
// are linear along each aperture, so the ray of level a crosses the aperture (beta_{j-1},
// beta_j) iff a lies between sin(u_{j-1}) and sin(u_j). The entry aperture spans a in
// [sin(t - psi), sin(t + psi)], of width 2 cos(t) sin(psi) (the projected aperture over R);
// entry positions uniform along the aperture are uniform in a.
//   Rays with a > 0 pass the bottom on the +x side: their polar angle increases, they meet the
// wall at +psi first and cross the fan toward copies 1, 2, ... Past the entry aperture the
// polygon's levels sin(u_j) fall monotonically on the far side of u = pi/2, so the ray leaves
// through the first aperture n >= 1 with u_n >= pi - arcsin(a):
//     n(a) = max(1, ceil((pi - t - psi - arcsin a) / (2 psi))),
// and the share of the entry width with at most n bounces is the length of
//     { a in [max(0, sin(t - psi)), sin(t + psi)] : arcsin a >= pi - t - (2n + 1) psi }
// over 2 cos(t) sin(psi). Rays with a < 0 meet the wall at -psi first: the same with t -> -t.
// Bounce j (0-based) crosses the wall line at beta = (2j+1) psi, whose normal is at
// (2j+1) psi + pi/2, so its local incidence cosine in the plane is |sin(t + (2j+1) psi)|; in 3D
// it is scaled by |l_p| = sqrt(lx^2 + lz^2) (the along-groove part is orthogonal to the walls'
// normals). Folding copy n back onto copy 0 is a reflection about beta = n psi (n odd) or a
// rotation by -2 n psi (n even), so the exit travel angle is
//     beta_out = pi - t - 2 n psi  (n even),   2 n psi - pi + t  (n odd),
// i.e. the exit direction o = (|l_p| sin beta_out, -ly, |l_p| cos beta_out) (x mirrored for the
// a < 0 family). Check: tf -> 0 gives one bounce and the mirror direction; tf = 70 deg, t = 20
// deg gives orders 3 and 4 with shares 0.4679 and 0.5321.
//
// Fresnel: the weight of a beam is the product of the unpolarized reflectances of its bounces at
// their local cosines (the convention of the explicit tracer and of the Smith walk; the exact
// polarized product differs slightly). A dielectric groove's reflected beams are those that
// reflect at every bounce; light refracted into the solid is not followed (it may come out
// again through the walls), so for a dielectric these are lower bounds of the reflected orders
// and no transmitted part is given.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/models/ndf.hpp"

namespace microsim::models {

// One beam of a V-groove: the share `fraction` of the light entering the aperture leaves after
// `bounces` reflections in `direction` (unit, groove frame) with the weight `reflectance`.
struct GrooveBeam {
  int bounces = 0;
  double fraction = 0.0;
  double reflectance = 1.0;
  Vec3 direction = Vec3::UnitZ();
};

// The beams (at most four: each first-wall family splits into two consecutive counts) of a
// symmetric V-groove of facet angle tf (radians, in (0, pi/2)) lit from l (groove frame, l.z > 0).
inline std::vector<GrooveBeam> vgroove_beams(double tf, const Vec3& l_in, const Material& mat) {
  std::vector<GrooveBeam> beams;
  const Vec3 l = l_in.normalized();
  const double lp = std::hypot(l.x(), l.z());
  if (!(l.z() > 0.0) || !(tf > 0.0 && tf < 0.5 * detail::kPi) || !(lp > 0.0)) return beams;
  const double psi = 0.5 * detail::kPi - tf;
  const double theta = std::atan2(-l.x(), l.z());
  const double width = std::sin(theta + psi) - std::sin(theta - psi);  // 2 cos(t) sin(psi)
  const int n_max = static_cast<int>(std::ceil(detail::kPi / (2.0 * psi))) + 2;
  for (int sign : {+1, -1}) {
    const double t = sign * theta;
    const double p = std::max(0.0, std::sin(t - psi)), q = std::sin(t + psi);
    if (!(q - p > 1e-13 * width)) continue;  // no rays in this family (up to rounding)
    // Width with at most n bounces.
    auto cumulative = [&](int n) {
      const double c = std::clamp(detail::kPi - t - (2 * n + 1) * psi, -0.5 * detail::kPi, 0.5 * detail::kPi);
      return std::max(0.0, q - std::max(p, std::sin(c)));
    };
    double below = 0.0, reflectance = 1.0;
    for (int n = 1; n <= n_max && below < q - p; ++n) {
      const double cos_local = lp * std::abs(std::sin(t + (2 * n - 1) * psi));
      reflectance *= mat.reflectance(std::min(1.0, cos_local), true);
      const double cum = cumulative(n);
      if (cum - below > 1e-13 * width) {
        const double b = (n % 2 == 0) ? detail::kPi - t - 2 * n * psi : 2 * n * psi - detail::kPi + t;
        GrooveBeam beam;
        beam.bounces = n;
        beam.fraction = (cum - below) / width;
        beam.reflectance = reflectance;
        beam.direction = Vec3(sign * lp * std::sin(b), -l.y(), lp * std::cos(b));
        beams.push_back(beam);
      }
      below = cum;
    }
  }
  return beams;
}

// Reflected albedo of one groove per slot: orders 1 .. K-1, K and above together (slot K-1),
// total (slot K), K >= 1.
inline std::vector<double> vgroove_albedo(double tf, const Vec3& l, const Material& mat, int K) {
  std::vector<double> a(static_cast<std::size_t>(K) + 1, 0.0);
  for (const GrooveBeam& b : vgroove_beams(tf, l, mat)) {
    const double w = b.fraction * b.reflectance;
    a[std::min(b.bounces, K) - 1] += w;
    a[K] += w;
  }
  return a;
}

// The groove of normal m (m.z > 0): facet angle theta_m, frame x along m's horizontal part.
struct GrooveFrame {
  double facet_angle = 0.0;
  Vec3 x = Vec3::UnitX(), y = Vec3::UnitY();
  explicit GrooveFrame(const Vec3& m) {
    const Vec3 mu = m.normalized();
    const double h = std::hypot(mu.x(), mu.y());
    facet_angle = std::atan2(h, mu.z());
    if (h > 0) x = Vec3(mu.x() / h, mu.y() / h, 0.0);
    y = Vec3::UnitZ().cross(x);
  }
  Vec3 to_local(const Vec3& w) const { return Vec3(w.dot(x), w.dot(y), w.z()); }
  Vec3 to_world(const Vec3& w) const { return w.x() * x + w.y() * y + w.z() * Vec3::UnitZ(); }
};

// Row i (polar angle index, 0 <= i < n_theta) of vcavity_quadrature: rows are independent, so a
// caller may sum them in parallel.
template <class F>
void vcavity_quadrature_row(const Ndf& ndf, int n_theta, int n_phi, int i, F&& f) {
  const double dt = 0.5 * detail::kPi / n_theta, dp = 2.0 * detail::kPi / n_phi;
  const double th = (i + 0.5) * dt, st = std::sin(th), ct = std::cos(th);
  for (int j = 0; j < n_phi; ++j) {
    const double ph = (j + 0.5) * dp;
    const Vec3 m(st * std::cos(ph), st * std::sin(ph), ct);
    const double w = ct * ndf.D(m) * st * dt * dp;
    if (w > 0) f(w, m);
  }
}

// Calls f(weight, m) over a midpoint quadrature of the hemisphere of groove normals with
// weight (n.m) D(m) dm (sums to ~1: [Heitz14, eq. 2]); grooves m and m' are the same groove, both
// are visited. Per-order albedos are continuous in m (kinks only), so the error is O(h^2).
template <class F>
void vcavity_quadrature(const Ndf& ndf, int n_theta, int n_phi, F&& f) {
  for (int i = 0; i < n_theta; ++i) vcavity_quadrature_row(ndf, n_theta, n_phi, i, f);
}

// The V-cavity multiple-scattering albedo per slot (as vgroove_albedo): the groove albedo
// averaged over normals drawn with (n.m) D(m) (every groove covers the same macro area, so the
// average is per unit macro area). Normalized by the quadrature's own total weight.
inline std::vector<double> vcavity_multiple_albedo(const Ndf& ndf, const Vec3& l, const Material& mat,
                                                   int K, int n_theta = 1024, int n_phi = 256) {
  std::vector<double> a(static_cast<std::size_t>(K) + 1, 0.0);
  double total = 0.0;
  vcavity_quadrature(ndf, n_theta, n_phi, [&](double w, const Vec3& m) {
    const GrooveFrame g(m);
    const std::vector<double> ag = vgroove_albedo(g.facet_angle, g.to_local(l), mat, K);
    for (int k = 0; k <= K; ++k) a[k] += w * ag[k];
    total += w;
  });
  if (total > 0)
    for (double& x : a) x /= total;
  return a;
}

}  // namespace microsim::models
