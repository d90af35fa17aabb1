// The single-scattering microfacet BSDF ([GeomBSDF24, eq. 21d], [Heitz14, eq. 18]; BTDF with the eta factors of
// [GeomBSDF24, eq. 9c] and [RefractionBlog24, eq. 6]), its pieces (reflection and refraction vectors and their inverse
// maps, [GeomBSDF24, eq. 13a/13b/15a/15b]; Jacobians, [GeomBSDF24, eq. 19b/20b]) and the materials of a random walk
// (mirror, conductor with complex index, dielectric).
//
// Header-only, depends on Eigen and the other model headers only.
//
// Conventions (as in ndf.hpp): macrosurface normal n = +z, every direction points away from the
// surface, radians. The medium above the surface (z > 0) has index 1, the material below index
// eta (dielectrics only; `eta` is the index of the material relative to the medium above, so
// eta = 1/1.5 is a less dense material below). Facet normals m point up (m.z > 0), out of the
// material. f(o, i) is the radiance BSDF of [GeomBSDF24, eq. 4a]: outgoing radiance toward o over incident
// irradiance from i (i = the light direction l of [GeomBSDF24], o = the view direction v).
//
// eta factor of the BTDF: the radiance BTDF carries eta_o^2 / eta_i^2 ([GeomBSDF24, eq. 9c]; [RefractionBlog24, eq. 4 and 6];
// [Walter07, eq. 21]): with m the refraction half vector,
//   f_t(o, i) = |o.m| |i.m| / (|o.n| |i.n|) * eta_o^2 (1 - F) G2 D(m) / (eta_i (i.m) + eta_o (o.m))^2.
// In [GeomBSDF24]'s notation this is (eta_v^2 / eta_l^2) (v.m)(l.m) / ((eta_v/eta_l) v + l)^2 ... ; the
// prefactor printed in [GeomBSDF24, eq. 14/21d] (eta_l^2 / eta_v^2) is the inverse and contradicts [GeomBSDF24]'s
// own eq. 9c, 10b and the reciprocity 4c (f(v,l) / f(l,v) = eta_v^2 / eta_l^2); the form above
// satisfies all three (tests/test_bsdf_models.cpp checks reciprocity and eq. 10b numerically).
//
// Masking-shadowing:
//   SmithHeightCorrelated: reflection [Heitz14, eq. 21], 1 / (1 + Lambda(o) + Lambda(i)). Transmission:
//     the same height-correlated Smith model for directions on opposite sides. A facet at height
//     quantile u = C1(h) is visible from above with probability u^Lambda(o) and from below with
//     (1 - u)^Lambda(i'), i' = i mirrored to the upper side (the surface seen from below is the
//     same Smith surface with heights -h), so G2 = int_0^1 u^Lo (1-u)^Li du = B(1 + Lo, 1 + Li)
//     (Euler's beta function). ([GeomBSDF24, eq. 18a]'s G2(v, m, -t) = 1/(1 + Lo + Li) would treat both
//     directions as seen from above and correlate them the wrong way.) This is exactly the
//     order-1 term of the Smith random walk (models/smith_random_walk.hpp).
//   VCavity: [Heitz14, Sec. 6], min(G1_vc(o, m), G1_vc(i, m)); for transmission with i reflected to the
//     upper side ([GeomBSDF24, eq. 18a]: G2(v, m, -t)).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "microsim/models/fresnel.hpp"
#include "microsim/models/ndf.hpp"

namespace microsim::models {

// ---------------------------------------------------------------------------------------------
// Materials
// ---------------------------------------------------------------------------------------------

enum class MaterialKind { Mirror, Conductor, Dielectric };

inline const char* to_string(MaterialKind k) {
  switch (k) {
    case MaterialKind::Mirror: return "mirror";
    case MaterialKind::Conductor: return "conductor";
    case MaterialKind::Dielectric: return "dielectric";
  }
  return "unknown";
}

struct Material {
  MaterialKind kind = MaterialKind::Mirror;
  double eta = 1.0;  // conductor: real part of the complex index; dielectric: index below / above
  double k = 0.0;    // conductor: extinction coefficient

  static Material mirror() { return {MaterialKind::Mirror, 1.0, 0.0}; }
  static Material conductor(double eta, double k) {
    if (!(std::isfinite(eta) && eta > 0.0 && std::isfinite(k) && k >= 0.0))
      throw std::invalid_argument("conductor index must have eta > 0 and k >= 0");
    return {MaterialKind::Conductor, eta, k};
  }
  static Material dielectric(double eta) {
    if (!(std::isfinite(eta) && eta > 0.0))
      throw std::invalid_argument("dielectric index eta must be finite and > 0");
    return {MaterialKind::Dielectric, eta, 0.0};
  }

  bool transmits() const { return kind == MaterialKind::Dielectric; }
  // Index of the medium on the side `above` (z > 0) or below.
  double index(bool above) const { return (above || kind != MaterialKind::Dielectric) ? 1.0 : eta; }

  // Unpolarized reflectance of a facet for light arriving from the side `from_above` with
  // |cos| = cos_i to the facet normal. Mirror: 1. Conductor: complex index (opaque: only light
  // from above). Dielectric: relative index of the far side over the near side.
  double reflectance(double cos_i, bool from_above = true) const {
    switch (kind) {
      case MaterialKind::Mirror: return 1.0;
      case MaterialKind::Conductor: return fresnel_conductor(cos_i, eta, k).unpolarized();
      case MaterialKind::Dielectric:
        return fresnel_dielectric_unpolarized(cos_i, from_above ? eta : 1.0 / eta);
    }
    return 1.0;
  }
};

// ---------------------------------------------------------------------------------------------
// Reflection and refraction vectors, inverse maps, Jacobians
// ---------------------------------------------------------------------------------------------

// [GeomBSDF24, eq. 13a]: r = -v + 2 (v.m) m.
inline Vec3 reflect(const Vec3& v, const Vec3& m) { return -v + 2.0 * v.dot(m) * m; }

// [GeomBSDF24, eq. 15a] with eta_ratio = eta_v / eta_t (index on v's side over the far side):
// t = -e v + (e (v.m) - sgn(v.m) sqrt(1 - e^2 |v x m|^2)) m. Returns false under total internal
// reflection (negative radicand); *t is then left unchanged.
inline bool refract(const Vec3& v, const Vec3& m, double eta_ratio, Vec3* t) {
  const double vm = v.dot(m);
  const double sin2 = std::max(0.0, 1.0 - vm * vm);  // |v x m|^2 for unit v, m
  const double rad = 1.0 - eta_ratio * eta_ratio * sin2;
  if (rad < 0.0) return false;
  const double sgn = vm >= 0.0 ? 1.0 : -1.0;
  *t = -eta_ratio * v + (eta_ratio * vm - sgn * std::sqrt(rad)) * m;
  return true;
}

// [GeomBSDF24, eq. 13b]: m = (r + v) / |r + v| (requires v.m > 0).
inline Vec3 half_vector_reflection(const Vec3& v, const Vec3& r) { return (r + v).normalized(); }

// [GeomBSDF24, eq. 15b]: m = sgn(e + v.t) (e v + t) / |e v + t|, e = eta_v / eta_t; v.m > 0 by the sign.
inline Vec3 half_vector_refraction(const Vec3& v, const Vec3& t, double eta_ratio) {
  const Vec3 h = eta_ratio * v + t;
  const double sgn = (eta_ratio + v.dot(t)) >= 0.0 ? 1.0 : -1.0;
  return sgn * h.normalized();
}

// [GeomBSDF24, eq. 19b]: |J(m, r)| = dOmega(m) / dOmega(r) = 1 / (4 |r.m|).
inline double jacobian_reflection(const Vec3& r, const Vec3& m) { return 1.0 / (4.0 * std::abs(r.dot(m))); }

// [GeomBSDF24, eq. 20b] (first form): |J(m, t)| = |t.m| / |e v + t|^2, e = eta_v / eta_t.
inline double jacobian_refraction(const Vec3& v, const Vec3& t, const Vec3& m, double eta_ratio) {
  return std::abs(t.dot(m)) / (eta_ratio * v + t).squaredNorm();
}

// ---------------------------------------------------------------------------------------------
// Masking-shadowing for the BSDF
// ---------------------------------------------------------------------------------------------

// SmithMaskingOnly: the BRDF of the weak white furnace test [Heitz14, eq. 19]: G2 replaced by the
// Smith masking G1(o, m), no shadowing; for an opaque material the reflection is then defined
// for light from the whole sphere (|i.n| in the denominator), as in [Heitz14, App. C], and
// int f(o, i) |i.n| d omega_i = 1 for every o with F = 1. Dielectrics: G1 of o on its own side.
enum class Masking { SmithHeightCorrelated, VCavity, SmithMaskingOnly };

inline const char* to_string(Masking m) {
  switch (m) {
    case Masking::SmithHeightCorrelated: return "smith_height_correlated";
    case Masking::VCavity: return "vcavity";
    case Masking::SmithMaskingOnly: return "smith_masking_only";
  }
  return "unknown";
}

// Euler's beta function B(a, b) for a, b >= 1 (finite; 0 when either argument is infinite).
inline double beta_function(double a, double b) {
  if (std::isinf(a) || std::isinf(b)) return 0.0;
  return std::exp(std::lgamma(a) + std::lgamma(b) - std::lgamma(a + b));
}

// Height-correlated Smith G2 for a transmission pair (see the header comment): o above the
// facet's upper side, i' = the other direction mirrored to the upper side; chi+ of both
// included. 0 unless o.z > 0, i'.z > 0, o.m > 0, i'.m' > 0 (m' = m seen from below).
inline double G2_height_correlated_transmission(const Ndf& ndf, const Vec3& o, const Vec3& i_up) {
  if (!(o.z() > 0.0) || !(i_up.z() > 0.0)) return 0.0;
  return beta_function(1.0 + ndf.Lambda(o), 1.0 + ndf.Lambda(i_up));
}
// The same with lambda_o = ndf.Lambda(o) given.
inline double G2_height_correlated_transmission(const Ndf& ndf, const Vec3& o, const Vec3& i_up, double lambda_o) {
  if (!(o.z() > 0.0) || !(i_up.z() > 0.0)) return 0.0;
  return beta_function(1.0 + lambda_o, 1.0 + ndf.Lambda(i_up));
}

// ---------------------------------------------------------------------------------------------
// Single-scattering microfacet BSDF
// ---------------------------------------------------------------------------------------------

inline Vec3 mirror_z(const Vec3& d) { return Vec3(d.x(), d.y(), -d.z()); }

struct MicrofacetBsdf {
  Ndf ndf;
  Material material;
  Masking masking = Masking::SmithHeightCorrelated;

  // f(o, i), [GeomBSDF24, eq. 21d]. Both directions unit. Reflection when o and i are on the same side
  // (below: the surface seen from below is the same Smith surface mirrored, [GeomBSDF24,
  // "Inherent Assumptions"]; only dielectrics have a lower side), transmission (dielectrics) otherwise.
  double eval(const Vec3& o, const Vec3& i) const {
    if (o.z() == 0.0 || i.z() == 0.0) return 0.0;
    const bool o_above = o.z() > 0.0, i_above = i.z() > 0.0;
    if (masking == Masking::SmithMaskingOnly && !material.transmits()) {
      // [Heitz14, eq. 19] integrand: G1(o, m) D(m) F / (4 |o.n| |i.n|), i anywhere on the sphere.
      if (!o_above) return 0.0;
      const Vec3 m = half_vector_reflection(o, i);
      if (!(m.z() > 0.0) || !(o.dot(m) > 0.0)) return 0.0;
      return material.reflectance(o.dot(m), true) * ndf.G1(o) * ndf.D(m) /
             (4.0 * o.z() * std::abs(i.z()));
    }
    if (o_above == i_above) {
      if (!o_above && !material.transmits()) return 0.0;
      // Work in the frame where both are above.
      const Vec3 oo = o_above ? o : mirror_z(o), ii = i_above ? i : mirror_z(i);
      const Vec3 m = half_vector_reflection(oo, ii);  // [GeomBSDF24, eq. 13b]
      if (!(m.z() > 0.0)) return 0.0;
      const double om = oo.dot(m), im = ii.dot(m);
      if (!(om > 0.0) || !(im > 0.0)) return 0.0;
      // o.m = i.m (13b); their average keeps f(o, i) = f(i, o) to the last bit
      const double F = material.reflectance(0.5 * (om + im), i_above);
      double G2 = 0.0;
      if (masking == Masking::SmithHeightCorrelated) G2 = G2_height_correlated(ndf, oo, ii, m);  // [Heitz14, eq. 21]
      else if (masking == Masking::VCavity) G2 = vcavity_G2(oo, ii, m);
      else G2 = ndf.G1(oo);  // [Heitz14, eq. 19] (weak white furnace)
      // [GeomBSDF24, eq. 21d] / [Heitz14, eq. 18]
      return F * G2 * ndf.D(m) / (4.0 * oo.z() * ii.z());
    }
    if (!material.transmits()) return 0.0;
    const double eta_o = material.index(o_above), eta_i = material.index(i_above);
    // Refraction half vector ([GeomBSDF24, eq. 15b]; in [RefractionBlog24] h = -(eta_i i + eta_o o)), oriented up.
    Vec3 h = eta_o * o + eta_i * i;
    const double hn = h.norm();
    if (!(hn > 0.0)) return 0.0;
    Vec3 m = h / hn;
    if (m.z() < 0.0) m = -m;
    if (!(m.z() > 0.0)) return 0.0;
    const double om = o.dot(m), im = i.dot(m);
    // Each direction on the same side of the facet as of the macrosurface.
    if (!(om * o.z() > 0.0) || !(im * i.z() > 0.0)) return 0.0;
    // Upper-side representatives of the two directions.
    const Vec3 up = o_above ? o : i, down = o_above ? i : o;
    // Fresnel is the same from either side [GeomBSDF24, after eq. 8c]; from the upper side, so that the
    // value does not depend on which direction is the light (reciprocity to the last bit).
    const double F = material.reflectance(std::abs(up.dot(m)), true);
    if (F >= 1.0) return 0.0;
    double G2 = 0.0;
    if (masking == Masking::SmithHeightCorrelated)
      G2 = G2_height_correlated_transmission(ndf, up, mirror_z(down));
    else if (masking == Masking::VCavity)
      G2 = std::min(vcavity_G1(up, m), vcavity_G1(-down, m));  // [GeomBSDF24, eq. 18a]: G2(v, m, -t)
    else
      G2 = ndf.G1(o_above ? o : mirror_z(o));
    const double denom = eta_i * im + eta_o * om;
    // [RefractionBlog24, eq. 6] / [GeomBSDF24, eq. 9c] eta factor (see header)
    return std::abs(om) * std::abs(im) / (std::abs(o.z()) * std::abs(i.z())) * eta_o * eta_o *
           (1.0 - F) * G2 * ndf.D(m) / (denom * denom);
  }
};

// ---------------------------------------------------------------------------------------------
// Single-scattering albedos
// ---------------------------------------------------------------------------------------------

struct SingleScatteringAlbedo {
  double reflected = 0.0;
  double transmitted = 0.0;
};

// Node p of n of the albedo quadrature on one axis of the sampler's unit square: the midpoint s = (p + 1/2) / n
// mapped by the quintic smoothstep u = s^3 (10 - 15 s + 6 s^2), with the weight du/ds = 30 s^2 (1 - s)^2.
// The sampler's map steepens toward the square's edges (u -> 0 or 1: slopes -> infinity); the weight
// vanishes there to second order, so that the integrand in s is smooth up to the edges and the product
// midpoint rule converges much faster than on the plain square (Beckmann alpha 0.2..1, theta_i 0..80 deg,
// mirror: errors 1e-5..2e-4 at n = 1024 on the plain square, < 2e-5 at n = 128 and < 3e-6 at n = 256 with it).
struct AlbedoNode {
  double u, w;
};
inline AlbedoNode albedo_node(int p, int n) {
  const double s = (p + 0.5) / n;
  return {s * s * s * (10.0 + s * (-15.0 + 6.0 * s)), 30.0 * s * s * (1.0 - s) * (1.0 - s)};
}

// Albedo of the single-scattering BSDF for light arriving from i (i.z > 0):
// int f(o, i) |o.z| d omega_o over each hemisphere. By the Jacobians 19b/20b this equals the
// expectation over visible normals m ~ D_i [Heitz14, eq. 13] of F G2 / G1(i) (reflection, o = 13a)
// and (1 - F) G2 / G1(i) (transmission, o = 15a), each 0 when o leaves on the wrong side.
// Computed by the product midpoint rule on the unit square of the exact VNDF sampler's (u1, u2), each
// axis smoothed by albedo_node (n x n points; deterministic). The integrand has kinks (horizon, critical
// angle, the V-cavity's min), so the error decreases irregularly (measure/single_scattering_albedos.hpp
// estimates it from three resolutions; tests compare with a direct quadrature of eval).
// SmithMaskingOnly uses G1(i) (the weak white furnace integrated over outgoing directions).
inline SingleScatteringAlbedo single_scattering_albedo(const MicrofacetBsdf& bsdf, const Vec3& i, int n = 1024) {
  SingleScatteringAlbedo a;
  if (!(i.z() > 0.0)) return a;
  const Ndf& ndf = bsdf.ndf;
  const double g1 = ndf.G1(i);
  if (!(g1 > 0.0)) return a;
  double sr = 0.0, st = 0.0;
  for (int p = 0; p < n; ++p)
    for (int q = 0; q < n; ++q) {
      const AlbedoNode a1 = albedo_node(p, n), a2 = albedo_node(q, n);
      const double w = a1.w * a2.w;
      const Vec3 m = ndf.sample_visible_normal(i, a1.u, a2.u);
      const double im = i.dot(m);
      if (!(im > 0.0)) continue;
      const double F = bsdf.material.reflectance(im, true);
      const Vec3 r = reflect(i, m);
      if (r.z() > 0.0) {
        const double G2 = bsdf.masking == Masking::SmithHeightCorrelated ? G2_height_correlated(ndf, r, i, m)
                          : bsdf.masking == Masking::VCavity                ? vcavity_G2(r, i, m)
                                                                            : g1;
        sr += w * (F * G2 / g1);
      }
      if (bsdf.material.transmits() && F < 1.0) {
        Vec3 t;
        if (refract(i, m, 1.0 / bsdf.material.eta, &t) && t.z() < 0.0) {
          const double G2 =
              bsdf.masking == Masking::SmithHeightCorrelated ? G2_height_correlated_transmission(ndf, i, mirror_z(t))
              : bsdf.masking == Masking::VCavity             ? std::min(vcavity_G1(i, m), vcavity_G1(-t, m))
                                                             : g1;
          st += w * ((1.0 - F) * G2 / g1);
        }
      }
    }
  a.reflected = sr / (static_cast<double>(n) * n);
  a.transmitted = st / (static_cast<double>(n) * n);
  return a;
}

// The single-scattering albedos of both G2 models of the BSDF (height-correlated Smith and V-cavity) from one
// pass of the quadrature of single_scattering_albedo: the visible normals, the Fresnel factors and the
// reflected / refracted directions are shared, only G2 differs. Each result is bit-identical to
// single_scattering_albedo with that masking at the same n: the same samples, the same terms, summed in the
// same order (row p, then column q). The Beckmann sampler's marginals are inverted once per row and column
// (the grid is a tensor product), which removes the 2 n^2 Newton inversions.
//
// for_rows(begin, end, body) must call body(p) once for every row p in [begin, end), in any order and on any
// threads: the rows' terms are written to separate slots and summed afterwards in the fixed order, so the
// result does not depend on how the rows are run.
struct SingleScatteringAlbedos {
  SingleScatteringAlbedo smith, vcavity;
};

struct SequentialRows {
  template <class Body>
  void operator()(int begin, int end, const Body& body) const {
    for (int p = begin; p < end; ++p) body(p);
  }
};

template <class ForRows = SequentialRows>
SingleScatteringAlbedos single_scattering_albedos(const Ndf& ndf, const Material& material, const Vec3& i, int n = 1024,
                                                  const ForRows& for_rows = ForRows()) {
  SingleScatteringAlbedos a;
  if (!(i.z() > 0.0) || n <= 0) return a;
  const double g1 = ndf.G1(i), lambda_i = ndf.Lambda(i);  // Lambda(i): once, not per sample
  if (!(g1 > 0.0)) return a;
  const auto u_of = [n](int p) { return albedo_node(p, n).u; };
  const auto w_of = [n](int p) { return albedo_node(p, n).w; };
  // Beckmann: the slope quantiles of every row (xt) and column (yt), as sample_visible_normal computes them.
  const bool beckmann = ndf.kind == Distribution::Beckmann;
  const Vec3 vs = ndf.stretched_view(i);
  const Ndf::BeckmannViewFrame frame = Ndf::beckmann_view_frame(vs);
  constexpr double one_minus = 1.0 - 0x1p-53;
  std::vector<double> xt, yt;
  if (beckmann) {
    xt.resize(n);
    yt.resize(n);
    for_rows(0, n, [&](int p) {
      const double u = std::max(std::clamp(u_of(p), 0.0, one_minus), 1e-300);
      xt[p] = detail::beckmann_visible_slope_quantile(frame.mu, u);
      yt[p] = detail::beckmann_visible_slope_quantile(detail::kInf, u);
    });
  }
  // Terms of one sample: Smith reflected, Smith transmitted, V-cavity reflected, V-cavity transmitted.
  constexpr int kTerms = 4;
  const auto sample_terms = [&](int p, int q, double* t) {
    t[0] = t[1] = t[2] = t[3] = 0.0;
    const Vec3 m = beckmann ? ndf.beckmann_normal_from_slopes(frame, xt[p], yt[q])
                            : ndf.sample_visible_normal(i, u_of(p), u_of(q));
    const double im = i.dot(m);
    if (!(im > 0.0)) return;
    const double F = material.reflectance(im, true);
    const Vec3 r = reflect(i, m);
    const double w = w_of(p) * w_of(q);
    if (r.z() > 0.0) {
      t[0] = w * (F * G2_height_correlated(ndf, r, i, m, lambda_i) / g1);
      t[2] = w * (F * vcavity_G2(r, i, m) / g1);
    }
    if (material.transmits() && F < 1.0) {
      Vec3 tr;
      if (refract(i, m, 1.0 / material.eta, &tr) && tr.z() < 0.0) {
        t[1] = w * ((1.0 - F) * G2_height_correlated_transmission(ndf, i, mirror_z(tr), lambda_i) / g1);
        t[3] = w * ((1.0 - F) * std::min(vcavity_G1(i, m), vcavity_G1(-tr, m)) / g1);
      }
    }
  };
  // Rows in blocks: the block's terms in parallel, then summed in the fixed order. A block holds about 2^12
  // samples (128 KiB of terms, reused; a block of 2^18, 8 MiB, was a fresh mapping at every call, and its page
  // faults tripled the time of n = 512), and at least 16 rows, so that the threads share every block.
  const int block = std::min(n, std::max(16, (1 << 12) / n));
  std::vector<double> terms(static_cast<std::size_t>(block) * n * kTerms);
  double sum[kTerms] = {0.0, 0.0, 0.0, 0.0};
  for (int p0 = 0; p0 < n; p0 += block) {
    const int p1 = std::min(n, p0 + block);
    for_rows(p0, p1, [&](int p) {
      double* row = terms.data() + static_cast<std::size_t>(p - p0) * n * kTerms;
      for (int q = 0; q < n; ++q) sample_terms(p, q, row + static_cast<std::size_t>(q) * kTerms);
    });
    for (std::size_t k = 0; k < static_cast<std::size_t>(p1 - p0) * n; ++k)
      for (int c = 0; c < kTerms; ++c) sum[c] += terms[k * kTerms + c];
  }
  const double nn = static_cast<double>(n) * n;
  a.smith = {sum[0] / nn, sum[1] / nn};
  a.vcavity = {sum[2] / nn, sum[3] / nn};
  return a;
}

}  // namespace microsim::models
