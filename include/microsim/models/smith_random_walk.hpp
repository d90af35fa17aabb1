// The Smith random-walk multiple-scattering model [Heitz16]: a stochastic walk on the Smith microsurface
// (normals and heights independent, [Heitz14, Sec. 2.3 and App. A]), which gives every scattering order
// of the BSDF that the single-scattering model (microfacet_bsdf.hpp) leaves out ([Heitz14, Sec. 4.3
// and 7]: rho = rho_1 + rho_2+). Conductors (weight multiplied by the unpolarized Fresnel reflectance)
// and dielectrics (reflection with probability F, else refraction by [GeomBSDF24, eq. 15a]; total internal
// reflection; both sides of the interface).
//
// Header-only, depends on Eigen and the other model headers only. Randomness comes from the
// caller's generator (any object with `double uniform()` in [0, 1)).
//
// The walk, derived from the Smith assumption:
//   * Heights. Let C1 be the CDF of the height distribution. Seen along an upward direction w
//     (w.z > 0) a point at height h is unoccluded with probability G1(w, h) = C1(h)^Lambda(w)
//     ([Heitz14, App. A]: masking of the Smith surface conditioned on height; its average over the
//     visible heights is 1/(1 + Lambda)). Hence a ray travelling upward from height h passes
//     height h' > h without meeting the surface with probability (C1(h)/C1(h'))^Lambda(w); it
//     escapes with probability C1(h)^Lambda(w), otherwise its next intersection is at
//     C1(h') = C1(h) U^(-1/Lambda(w)) for U uniform in (G1, 1]. A ray travelling downward
//     (w.z < 0) meets the surface at the rate of the front-facing projected area, 1 + Lambda(-w)
//     per unit of crossed signed area [GeomBSDF24, eq. 3Xc], so it passes h' < h with probability
//     (C1(h')/C1(h))^(1 + Lambda(-w)): the next intersection is at C1(h') = C1(h) U^(1/(1 + Lambda(-w))).
//     A ray arriving from outside starts at h = +inf (C1 = 1).
//   * Normals. At an intersection the facet normal is distributed as the visible normals of the
//     direction the ray came from, D_{-w}(m) ~ max(0, -w.m) D(m) [Heitz14, eq. 13]; for an upward ray
//     -w points below the horizon (sample_visible_normal_any extends the exact samplers of
//     ndf.hpp to that case).
//   * Scattering. Mirror: reflect [GeomBSDF24, eq. 13a]. Conductor: reflect, weight *= F (complex index).
//     Dielectric: reflect with probability F, else refract [GeomBSDF24, eq. 15a] into the other medium.
//     The medium below is the same Smith surface seen from below (heights -h, normals mirrored,
//     [GeomBSDF24, "Inherent Assumptions"]), so the walk continues in a mirrored frame: z -> -z, h -> -h.
//     In every frame "up" is away from the interface: escaping up in the frame of the medium
//     above is reflection, in the frame of the medium below transmission.
//   * Under Smith the walk depends on the heights only through C1(h): any continuous height
//     distribution gives the same BSDF. Uniform and Gaussian distributions are provided (the
//     tests check that they agree).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "microsim/models/beckmann_slope_sampler.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/models/ndf.hpp"

namespace microsim::models {

// ---------------------------------------------------------------------------------------------
// Height distributions
// ---------------------------------------------------------------------------------------------

enum class HeightDistribution { Uniform, Gaussian };

inline const char* to_string(HeightDistribution h) {
  return h == HeightDistribution::Uniform ? "uniform" : "gaussian";
}

struct SmithHeights {
  HeightDistribution kind = HeightDistribution::Uniform;

  // CDF C1(h). Uniform on [-1, 1]; Gaussian: standard normal.
  double C1(double h) const {
    if (kind == HeightDistribution::Uniform) return std::clamp(0.5 * (h + 1.0), 0.0, 1.0);
    return 0.5 * std::erfc(-h / std::sqrt(2.0));
  }
  // Inverse CDF. C1^-1(0) = -inf only for the Gaussian; uniform heights stay in [-1, 1].
  double invC1(double u) const {
    if (kind == HeightDistribution::Uniform) return 2.0 * std::clamp(u, 0.0, 1.0) - 1.0;
    return normal_quantile(u);
  }

  // Standard normal quantile: Abramowitz & Stegun 26.2.23 as a start, then Newton steps on
  // erfc (converges to full double precision in 2-3 steps from that start).
  static double normal_quantile(double u) {
    if (!(u > 0.0)) return -std::numeric_limits<double>::infinity();
    if (!(u < 1.0)) return std::numeric_limits<double>::infinity();
    const double p = std::min(u, 1.0 - u);
    const double t = std::sqrt(-2.0 * std::log(p));
    double x = t - (2.515517 + 0.802853 * t + 0.010328 * t * t) /
                       (1.0 + 1.432788 * t + 0.189269 * t * t + 0.001308 * t * t * t);
    x = (u < 0.5) ? -x : x;
    for (int it = 0; it < 4; ++it) {
      const double c = 0.5 * std::erfc(-x / std::sqrt(2.0));
      const double pdf = std::exp(-0.5 * x * x) / std::sqrt(2.0 * detail::kPi);
      if (!(pdf > 0.0)) break;
      // Newton on the smaller tail for relative accuracy
      const double dx = (u < 0.5) ? (c - u) / pdf : ((1.0 - u) - 0.5 * std::erfc(x / std::sqrt(2.0))) / pdf;
      x -= dx;
      if (std::abs(dx) < 1e-15 * (1.0 + std::abs(x))) break;
    }
    return x;
  }
};

// ---------------------------------------------------------------------------------------------
// Visible normals for any direction (also below the horizon)
// ---------------------------------------------------------------------------------------------

// Samples m with density max(0, u.m) D(m) / int max(0, u.m) D(m) dm for any unit u with a
// nonzero visible area (for u.z < 0 that area is |u.z| Lambda(-u): the downward-facing view sees
// the backs of the slopes that face it). u.z >= 0: Ndf::sample_visible_normal (exact). u.z < 0:
// the same constructions continued below the horizon:
//   GGX: alpha = 1 GGX is the normal distribution of a hemisphere; seen from below the horizon
//     its visible part projects onto the disk perpendicular to the stretched view as the lune
//     between the half disk and the half ellipse compressed by |vs.z|, i.e. the same linear map
//     p2 -> (1 - s) h + s p2, s = (1 + vs.z)/2, which now maps [-h, h] onto [|vs.z| h, h].
//   Beckmann: the visible slope density (mu - x)+ P2(x) P2(y) with mu = cot(theta') < 0 (the
//     same closed-form CDF, detail::beckmann_visible_slope_quantile).
inline Vec3 sample_visible_normal_any(const Ndf& ndf, const Vec3& u, double u1, double u2) {
  if (u.z() >= 0.0) return ndf.sample_visible_normal(u, u1, u2);
  constexpr double one_minus = 1.0 - 0x1p-53;
  u1 = std::clamp(u1, 0.0, one_minus);
  u2 = std::clamp(u2, 0.0, one_minus);
  const Vec3 vs = Vec3(ndf.alpha_x * u.x(), ndf.alpha_y * u.y(), u.z()).normalized();
  const double lensq = vs.x() * vs.x() + vs.y() * vs.y();
  if (!(lensq > 0.0)) return Vec3(0.0, 0.0, 1.0);  // straight down: nothing visible (never hit)
  const double len = std::sqrt(lensq);
  if (ndf.kind == Distribution::GGX) {
    const Vec3 t1 = Vec3(-vs.y(), vs.x(), 0.0) / len;
    const Vec3 t2 = vs.cross(t1);
    const double r = std::sqrt(u1), phi = 2.0 * detail::kPi * u2;
    const double p1 = r * std::cos(phi);
    double p2 = r * std::sin(phi);
    const double h = std::sqrt(std::max(0.0, 1.0 - p1 * p1));
    const double s = 0.5 * (1.0 + vs.z());
    p2 = (1.0 - s) * h + s * p2;
    const double p3 = std::sqrt(std::max(0.0, 1.0 - p1 * p1 - p2 * p2));
    const Vec3 nh = p1 * t1 + p2 * t2 + p3 * vs;
    return Vec3(ndf.alpha_x * nh.x(), ndf.alpha_y * nh.y(), std::max(0.0, nh.z())).normalized();
  }
  const double cphi = vs.x() / len, sphi = vs.y() / len;
  // mu < -20: the walk never hits from such directions (Lambda < 1e-170); clamp for safety.
  const double mu = std::max(vs.z() / len, -20.0);
  const double xt = detail::beckmann_visible_slope_quantile(mu, std::max(u1, 1e-300));
  const double yt = detail::beckmann_visible_slope_quantile(detail::kInf, std::max(u2, 1e-300));
  const double sx = ndf.alpha_x * (cphi * xt - sphi * yt);
  const double sy = ndf.alpha_y * (sphi * xt + cphi * yt);
  return Vec3(-sx, -sy, 1.0).normalized();
}

// sample_visible_normal_any with the Beckmann slope quantiles of beckmann_slope_sampler.hpp (the same
// function to ~1e-14, several times faster: the walk inverts two slope CDFs per event); GGX unchanged.
// leg_lambda (optional): Lambda of the ray's leg that arrives along -u, i.e. Lambda(u) for u.z > 0 and
// Lambda(-u) for u.z < 0, which gives the slope CDF's normalization without erfc: mu (1 + Lambda(u)),
// resp. -mu Lambda(-u) (mu = cot of the stretched view).
inline Vec3 sample_visible_normal_fast(const Ndf& ndf, const Vec3& u, double u1, double u2,
                                       double leg_lambda = std::numeric_limits<double>::quiet_NaN()) {
  if (ndf.kind != Distribution::Beckmann) return sample_visible_normal_any(ndf, u, u1, u2);
  constexpr double one_minus = 1.0 - 0x1p-53;
  u1 = std::clamp(u1, 0.0, one_minus);
  u2 = std::clamp(u2, 0.0, one_minus);
  const Vec3 vs = Vec3(ndf.alpha_x * u.x(), ndf.alpha_y * u.y(), u.z()).normalized();
  const double lensq = vs.x() * vs.x() + vs.y() * vs.y();
  double cphi = 1.0, sphi = 0.0, mu = detail::kInf;
  if (lensq > 0.0) {
    const double len = std::sqrt(lensq);
    cphi = vs.x() / len;
    sphi = vs.y() / len;
    mu = vs.z() / len;
    if (u.z() < 0.0) mu = std::max(mu, -20.0);  // as sample_visible_normal_any
  } else if (!(u.z() > 0.0)) {
    return Vec3(0.0, 0.0, 1.0);  // straight down: nothing visible (never hit)
  }
  double norm = std::numeric_limits<double>::quiet_NaN();
  if (std::isfinite(mu) && mu > -20.0 && std::isfinite(leg_lambda)) norm = u.z() > 0.0 ? mu * (1.0 + leg_lambda) : -mu * leg_lambda;
  const double xt = detail::fast_beckmann_visible_slope_quantile(mu, std::max(u1, 1e-300), norm);
  const double yt = detail::fast_beckmann_visible_slope_quantile(detail::kInf, std::max(u2, 1e-300));
  const double sx = ndf.alpha_x * (cphi * xt - sphi * yt);
  const double sy = ndf.alpha_y * (sphi * xt + cphi * yt);
  return Vec3(-sx, -sy, 1.0).normalized();
}

// ---------------------------------------------------------------------------------------------
// The walk
// ---------------------------------------------------------------------------------------------

struct WalkExit {
  bool lost = false;        // exceeded max_order scattering events
  bool reflected = true;    // left upward (true) or into the material below (false)
  int order = 0;            // number of scattering events
  Vec3 direction = Vec3::UnitZ();  // outgoing direction (unit, real frame)
  double weight = 1.0;      // product of conductor Fresnel factors (1 for mirror/dielectric)
};

// An escape of a walk tallied with its expected weight (walk_with_expected_escapes): after `order` events,
// upward (reflected) or into the material below, along `direction` (real frame).
struct WalkEscape {
  int order;
  bool reflected;
  Vec3 direction;
  double weight;
};

// A scattering event of the walk: v points back along the arriving ray (current frame), h is
// the height (current frame), `above` tells the frame, weight the product of the Fresnel factors
// before this event.
struct WalkVertex {
  Vec3 v;
  double h;
  bool above;
  double weight;
};

class SmithRandomWalk {
 public:
  SmithRandomWalk(const Ndf& ndf, const Material& material,
                  HeightDistribution heights = HeightDistribution::Uniform, int max_order = 100000)
      : ndf_(ndf), material_(material), heights_{heights}, max_order_(max_order) {}

  // The same walk with the Beckmann slopes of sample_visible_normal_fast (equal to ~1e-14, faster).
  SmithRandomWalk with_fast_slope_sampler() const {
    SmithRandomWalk w = *this;
    w.fast_slopes_ = true;
    return w;
  }
  bool fast_slope_sampler() const { return fast_slopes_; }

  const Ndf& ndf() const { return ndf_; }
  const Material& material() const { return material_; }
  HeightDistribution heights() const { return heights_.kind; }

  // One walk for light arriving from direction wi (pointing away from the surface, wi.z > 0).
  template <class Rng>
  WalkExit walk(const Vec3& wi, Rng& rng) const {
    return walk(wi, rng, [](const WalkVertex&) {});
  }
  // The same walk, calling at_vertex(WalkVertex) at every scattering event before it scatters
  // (the point estimators of models/smith_walk_eval.hpp evaluate the phase function there).
  template <class Rng, class Visitor>
  WalkExit walk(const Vec3& wi, Rng& rng, Visitor&& at_vertex) const {
    return walk_with_expected_escapes(wi, rng, at_vertex, 0, [](const WalkEscape&) {});
  }

  // The walk with the escapes after the events 1 .. expected_orders tallied by their conditional
  // expectations (Rao-Blackwellisation, docs/theory/bsdf.md "Expected escapes"): where the walk draws whether
  // a ray leaving upward from height h escapes (probability g = C1(h)^Lambda(w)), it first calls
  // at_escape({order, side, direction, W g}) with the walk's weight W; the draw then goes on as in walk()
  // (the same uniforms, the same path, the same returned exit). The caller tallies an order either by the
  // expected escapes or by the drawn exit, not both. Each order's expected tally is walk()'s
  // (E[W 1{escape}] = E[W g]); the per-walk spread is smaller (at order 1 only the first height and facet
  // normal are left random). expected_orders = 0 is walk().
  template <class Rng, class Visitor, class EscapeVisitor>
  WalkExit walk_with_expected_escapes(const Vec3& wi, Rng& rng, Visitor&& at_vertex, int expected_orders,
                                      EscapeVisitor&& at_escape) const {
    return escape_walk(wi, rng, at_vertex, expected_orders, false, at_escape);
  }

  // The walk with the escapes after the events 1 .. forced_orders tallied by their expectations and not
  // drawn (docs/theory/bsdf.md "Forced continuation"): where walk() draws whether a ray leaving upward from
  // height h escapes (probability g = C1(h)^Lambda(w)), this walk calls at_escape({order, side, direction,
  // W g}) and always goes on, with weight W (1 - g) and the next height drawn given no escape (U uniform in
  // (g, 1], one uniform as in walk()). Every walk thus reaches the event forced_orders + 1 (unless g = 1:
  // then it ends there with weight 0) and adds to every order up to it; from there on it is walk() (the
  // escape drawn; the returned exit has the weight W). Each order's expected tally is walk()'s: the
  // escaping and the continuing branch are both followed, each with its probability as a weight. For a
  // mirror the tallies of a walk sum to 1 (the weights telescope).
  template <class Rng, class Visitor, class EscapeVisitor>
  WalkExit walk_with_forced_continuation(const Vec3& wi, Rng& rng, Visitor&& at_vertex, int forced_orders,
                                         EscapeVisitor&& at_escape) const {
    return escape_walk(wi, rng, at_vertex, forced_orders, true, at_escape);
  }

  // Forced continuation (as walk_with_forced_continuation) through the orders 1 .. forced_orders, with the
  // branch weights held in the window [w_low, w_high] by splitting and Russian roulette (docs/theory/bsdf.md
  // "Weight window"): before each leg after the events 1 .. forced_orders, a branch heavier than w_high goes on
  // as n = ceil(W / w_high) branches of weight W / n (at most kMaxSplit, and none while kMaxBranches are
  // pending), each drawing its own path from there; a branch lighter than w_low goes on with probability
  // W / w_low and weight w_low, else ends. Each order's expected tally is walk()'s (splitting divides a weight
  // among copies of the same branch; the roulette keeps its expectation). Every expected escape of the orders
  // 1 .. forced_orders and every drawn exit of the orders above (their order > forced_orders tells them apart)
  // goes to at_escape, and for conductors and mirrors the roulette's zero-mean correction of the reflected
  // total as an escape of order 0 (no direction); returns the events of all branches, *lost: branches that
  // exceeded max_order.
  // w_low = 0, w_high = inf: walk_with_forced_continuation's tallies.
  static constexpr int kMaxSplit = 64, kMaxBranches = 256;
  template <class Rng, class EscapeVisitor>
  std::uint64_t walk_with_weight_window(const Vec3& wi, Rng& rng, int forced_orders, double w_low, double w_high,
                                        EscapeVisitor&& at_escape, std::uint64_t* lost = nullptr) const {
    Branch pending[kMaxBranches];
    int npending = 0;
    std::uint64_t events = 0;
    pending[npending++] = Branch{-wi, detail::kInf, true, 1.0, 0, false, 0.0};
    while (npending > 0) {
      Branch b = pending[--npending];
      for (;;) {
        const double c = (b.h == detail::kInf) ? 1.0 : heights_.C1(b.h);
        const bool up = b.w.z() > 0.0;
        const double lambda = up ? ndf_.Lambda(b.w) : ndf_.Lambda(-b.w);
        double g = b.g, U_next = -1.0;  // U_next: a drawn escape's refused uniform, reused for the next height
        if (!b.resume) {
          const bool forced = b.order >= 1 && b.order <= forced_orders;
          if (up) {
            g = (lambda == 0.0) ? 1.0 : std::pow(c, lambda);
            const Vec3 out = b.above ? b.w : mirror_z(b.w);
            if (forced) {
              at_escape(WalkEscape{b.order, b.above, out, b.weight * g});
              b.weight *= 1.0 - g;
            } else {
              const double U = rng.uniform();
              if (U < g) {  // drawn escape
                at_escape(WalkEscape{b.order, b.above, out, b.weight});
                break;
              }
              U_next = U;
            }
          }
          if (forced && !hold_in_window(b, g, w_low, w_high, pending, npending, rng, at_escape)) break;
        }
        b.resume = false;
        b.h = heights_.invC1(std::clamp(next_c(b.w, c, lambda, g, U_next, rng), 0.0, 1.0));
        if (b.order + 1 > max_order_ || !scatter_at(rng, b.w, b.h, b.above, b.weight, lambda)) {
          if (lost) ++*lost;
          break;
        }
        ++b.order;
        ++events;
      }
    }
    return events;
  }

 private:
  // A branch of walk_with_weight_window.
  struct Branch {
    Vec3 w;       // direction of travel (current frame)
    double h;     // height (current frame)
    bool above;   // frame
    double weight;
    int order;    // events so far
    bool resume;  // a split copy: the escape of this leg is tallied; the next height is still to draw
    double g;     // with resume: the escape probability of this leg
  };

  // The weight window of walk_with_weight_window after a forced event (escape probability g of the leg):
  // Russian roulette below w_low (its zero-mean change of the total to at_escape as order 0, mirrors and
  // conductors), splitting above w_high into pending copies. False where the branch ends.
  template <class Rng, class EscapeVisitor>
  bool hold_in_window(Branch& b, double g, double w_low, double w_high, Branch* pending, int& npending, Rng& rng,
                      EscapeVisitor& at_escape) const {
    if (!(b.weight > 0.0)) return false;
    if (b.weight < w_low) {  // Russian roulette
      const bool survives = rng.uniform() * w_low < b.weight;
      // the roulette's change of the branch's weight, W - (w_low or 0), has mean 0: a correction of the
      // total (order 0) that keeps a mirror walk's total exactly 1 (its branches' weights all leave, above)
      if (material_.kind != MaterialKind::Dielectric)
        at_escape(WalkEscape{0, true, Vec3::UnitZ(), b.weight - (survives ? w_low : 0.0)});
      if (!survives) return false;
      b.weight = w_low;
    } else if (b.weight > w_high) {  // splitting: this branch and n - 1 pending copies
      const int n = static_cast<int>(
          std::min<double>({double(kMaxSplit), double(kMaxBranches - npending), std::ceil(b.weight / w_high)}));
      if (n > 1) {
        b.weight /= n;
        Branch copy = b;
        copy.resume = true;
        copy.g = g;
        for (int k = 1; k < n; ++k) pending[npending++] = copy;
      }
    }
    return true;
  }

  // C1 of the next intersection of a leg along w from C1 = c, given no escape. Upward: C1(h') = c U^(-1/Lambda)
  // with U uniform on (g, 1] (a drawn escape's refused uniform U_next >= 0, else a new one); downward:
  // C1(h') = c U^(1/(1 + Lambda(-w))), U uniform on (0, 1]; horizontal: Lambda = inf, it hits where it is.
  template <class Rng>
  double next_c(const Vec3& w, double c, double lambda, double g, double U_next, Rng& rng) const {
    if (w.z() > 0.0) {
      const double U = U_next >= 0.0 ? U_next : g + (1.0 - g) * (1.0 - rng.uniform());  // on [g, 1]
      return c * std::pow(std::min(U, 1.0), -1.0 / lambda);
    }
    if (w.z() < 0.0) return c * std::pow(1.0 - rng.uniform(), 1.0 / (1.0 + lambda));
    return c;
  }

  // A visible normal m of the view v (the direction the ray came from, [Heitz14, eq. 13]) with v.m > 0:
  // v.m > 0 by construction, a rounding-level v.m <= 0 (grazing visible normal) is redrawn (at most 16 draws).
  // leg_lambda: see sample_visible_normal_fast. False where none was found.
  template <class Rng>
  bool draw_visible_normal(Rng& rng, const Vec3& v, double leg_lambda, Vec3& m, double& vm) const {
    vm = 0.0;
    for (int tries = 0; tries < 16 && !(vm > 0.0); ++tries) {
      const double u1 = rng.uniform(), u2 = rng.uniform();
      m = fast_slopes_ ? sample_visible_normal_fast(ndf_, v, u1, u2, leg_lambda) : sample_visible_normal_any(ndf_, v, u1, u2);
      vm = v.dot(m);
    }
    return vm > 0.0;
  }

  // The material's choice at a facet m (v.m = vm > 0) for the ray that came from v: mirror: reflect
  // [GeomBSDF24, eq. 13a]; conductor: reflect, weight *= F; dielectric: reflect with probability F, else
  // refract [GeomBSDF24, eq. 15a] and continue in the other medium's mirrored frame (h -> -h).
  template <class Rng>
  void scatter(Rng& rng, const Vec3& v, const Vec3& m, double vm, Vec3& w, double& h, bool& above,
               double& weight) const {
    switch (material_.kind) {
      case MaterialKind::Mirror:
        w = reflect(v, m);
        break;
      case MaterialKind::Conductor:
        weight *= material_.reflectance(vm, true);
        w = reflect(v, m);
        break;
      case MaterialKind::Dielectric: {
        const double F = material_.reflectance(vm, above);
        if (rng.uniform() < F) {
          w = reflect(v, m);
        } else {
          Vec3 t;
          const double n = above ? material_.eta : 1.0 / material_.eta;  // far / near
          if (!refract(v, m, 1.0 / n, &t)) {  // cannot happen when F < 1 (TIR gives F = 1)
            w = reflect(v, m);
          } else {
            w = mirror_z(t).normalized();
            h = -h;
            above = !above;
          }
        }
        break;
      }
    }
    w.normalize();
  }

  // One scattering event of walk_with_weight_window at height h: a visible normal of the arriving direction
  // w (leg_lambda: Lambda of the leg, see sample_visible_normal_fast), then the material's choice; w, h, above
  // and weight updated. False where no visible normal was found.
  template <class Rng>
  bool scatter_at(Rng& rng, Vec3& w, double& h, bool& above, double& weight, double leg_lambda) const {
    const Vec3 v = -w;
    Vec3 m;
    double vm;
    if (!draw_visible_normal(rng, v, leg_lambda, m, vm)) return false;
    scatter(rng, v, m, vm, w, h, above, weight);
    return true;
  }

  // walk_with_expected_escapes (forced = false) and walk_with_forced_continuation (forced = true).
  template <class Rng, class Visitor, class EscapeVisitor>
  WalkExit escape_walk(const Vec3& wi, Rng& rng, Visitor&& at_vertex, int expected_orders, bool forced,
                       EscapeVisitor&& at_escape) const {
    WalkExit out;
    Vec3 w = -wi;       // propagation direction in the current frame
    double h = detail::kInf;
    bool above = true;  // current frame: the medium above (true) or the mirrored medium below
    // the exit after `order` events: along w (the weight as it is), or lost
    auto leave = [&](int order, bool lost) -> WalkExit {
      out.lost = lost;
      out.order = order;
      if (!lost) {
        out.reflected = above;
        out.direction = above ? w : mirror_z(w);
      }
      return out;
    };
    for (int order = 0;; ++order) {
      // --- next intersection height (or escape)
      const double c = (h == detail::kInf) ? 1.0 : heights_.C1(h);
      double c_next = c;  // horizontal: Lambda = inf, hits where it is
      if (w.z() > 0.0) {
        const double lambda = ndf_.Lambda(w);
        const double g1 = (lambda == 0.0) ? 1.0 : std::pow(c, lambda);
        // expected escape W g1 tallied; the escape itself still drawn (continuing with W, probability 1 - g1)
        if (order <= expected_orders) at_escape(WalkEscape{order, above, above ? w : mirror_z(w), out.weight * g1});
        if (order <= expected_orders && forced) {
          // continue with the weight of no escape; U uniform in (g1, 1]
          const double U = g1 + (1.0 - g1) * (1.0 - rng.uniform());
          out.weight *= 1.0 - g1;
          if (!(out.weight > 0.0) || !(U > 0.0)) {  // g1 = 1: nothing continues
            out.weight = 0.0;
            return leave(order, false);
          }
          c_next = c * std::pow(std::min(U, 1.0), -1.0 / lambda);
        } else {
          const double U = rng.uniform();
          if (U < g1) return leave(order, false);  // escapes
          c_next = c * std::pow(U, -1.0 / lambda);
        }
      } else if (w.z() < 0.0) {
        const double lambda = ndf_.Lambda(-w);
        const double U = 1.0 - rng.uniform();  // (0, 1]
        c_next = c * std::pow(U, 1.0 / (1.0 + lambda));
      }
      h = heights_.invC1(std::clamp(c_next, 0.0, 1.0));
      if (order + 1 > max_order_) return leave(order, true);
      // --- facet normal: visible normals of the direction the ray came from [Heitz14, eq. 13]
      const Vec3 v = -w;
      Vec3 m;
      double vm;
      if (!draw_visible_normal(rng, v, std::numeric_limits<double>::quiet_NaN(), m, vm)) return leave(order, true);
      at_vertex(WalkVertex{v, h, above, out.weight});
      scatter(rng, v, m, vm, w, h, above, out.weight);
    }
  }

  Ndf ndf_;
  Material material_;
  SmithHeights heights_;
  int max_order_;
  bool fast_slopes_ = false;
};

// Per-order albedos of n walks (serial; the measure layer runs the parallel, binned version).
// orders = K: orders 1 .. K-1 separately, K and above together in the last slot.
struct WalkAlbedos {
  int orders = 4;
  std::uint64_t n = 0, lost = 0;
  // [side][k], side 0 reflected, 1 transmitted; k = 0 .. K-1 orders, k = K total.
  std::vector<double> sum[2], sum2[2];
  explicit WalkAlbedos(int K = 4) : orders(K) {
    for (int s = 0; s < 2; ++s) {
      sum[s].assign(K + 1, 0.0);
      sum2[s].assign(K + 1, 0.0);
    }
  }
  void add(const WalkExit& e) {
    ++n;
    if (e.lost) {
      ++lost;
      return;
    }
    const int s = e.reflected ? 0 : 1;
    const int k = std::min(e.order, orders) - 1;
    if (k < 0) return;
    sum[s][k] += e.weight;
    sum2[s][k] += e.weight * e.weight;
    sum[s][orders] += e.weight;
    sum2[s][orders] += e.weight * e.weight;
  }
  double mean(int side, int k) const { return n ? sum[side][k] / n : 0.0; }
  // Standard error of the mean of the per-walk contribution (0 or the walk's weight).
  double stderr_(int side, int k) const {
    if (n < 2) return 0.0;
    const double m = mean(side, k);
    return std::sqrt(std::max(0.0, sum2[side][k] / n - m * m) / (n - 1));
  }
};

template <class RngFactory>
WalkAlbedos smith_walk_albedos(const SmithRandomWalk& model, const Vec3& wi, std::uint64_t n,
                               int orders, RngFactory make_rng) {
  WalkAlbedos a(orders);
  for (std::uint64_t k = 0; k < n; ++k) {
    auto rng = make_rng(k);
    a.add(model.walk(wi, rng));
  }
  return a;
}

}  // namespace microsim::models
