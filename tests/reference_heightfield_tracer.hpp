// An independent tracer for periodic heightfields, for checks of the library's Embree tracer:
// double precision, no Embree, no origin offsets and no filters. A 2D digital differential
// analyser walks the cells of the infinite periodic grid in the order the ray crosses them and
// intersects the two triangles of each cell as planes z = A + B u + C v over the cell's local
// coordinates (u, v) in [0, 1]^2, split like Microsurface::facet (along the (i+1, j)-(i, j+1)
// diagonal). A ray leaving a facet of a graph upward can never meet that facet's plane again,
// so only that facet is skipped. Used by tests/test_walk_reference.cpp and analysis/walk_audit.cpp.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "microsim/surface/microsurface.hpp"

namespace microsim {

class ReferenceHeightfieldTracer {
 public:
  // `other_diagonal`: split every cell along (i, j)-(i+1, j+1) instead, a different surface
  // (for power checks: a comparison must notice it).
  explicit ReferenceHeightfieldTracer(const Microsurface& s, bool other_diagonal = false)
      : s_(s), nx_(s.nx()), ny_(s.ny()), dx_(s.dx()), dy_(s.dy()), x0_(-0.5 * s.macro().size_x),
        y0_(-0.5 * s.macro().size_y), other_(other_diagonal) {
    hmin_ = std::numeric_limits<double>::infinity();
    hmax_ = -hmin_;
    for (float h : s.heights()) {
      hmin_ = std::min(hmin_, static_cast<double>(h));
      hmax_ = std::max(hmax_, static_cast<double>(h));
    }
  }

  struct Hit {
    bool hit = false, backface = false, lost = false;  // lost: left below every vertex, or no end
    Vec3 p, n;           // hit point (copy inside the tile), unit facet normal
    std::size_t facet = 0;  // Microsurface::facet_index of the cell's triangle
  };

  // First hit along o + t d, t > 0, skipping facet `skip` (-1: none).
  Hit first_hit(const Vec3& o, const Vec3& d, long skip) const {
    Hit out;
    const double inf = std::numeric_limits<double>::infinity();
    const double ox = (o.x() - x0_) / dx_, oy = (o.y() - y0_) / dy_;
    const double ux = d.x() / dx_, uy = d.y() / dy_;  // cells per unit of t
    long i = static_cast<long>(std::floor(ox)), j = static_cast<long>(std::floor(oy));
    const int sx = ux > 0 ? 1 : (ux < 0 ? -1 : 0), sy = uy > 0 ? 1 : (uy < 0 ? -1 : 0);
    double tmx = sx > 0 ? (i + 1 - ox) / ux : (sx < 0 ? (i - ox) / ux : inf);
    double tmy = sy > 0 ? (j + 1 - oy) / uy : (sy < 0 ? (j - oy) / uy : inf);
    const double tdx = sx ? 1.0 / std::abs(ux) : inf, tdy = sy ? 1.0 / std::abs(uy) : inf;
    double t_in = 0;
    const double tmin = 1e-12 * dx_, eps = 1e-10;
    for (long step = 0; step < 100000000; ++step) {
      const double t_out = std::min(tmx, tmy);
      const double za = o.z() + d.z() * t_in;
      const double zb = std::isfinite(t_out) ? o.z() + d.z() * t_out : (d.z() > 0 ? inf : -inf);
      const double h00 = h(i, j), h10 = h(i + 1, j), h01 = h(i, j + 1), h11 = h(i + 1, j + 1);
      if (std::min(za, zb) <= std::max({h00, h10, h01, h11}) + 1e-12) {
        double best = inf;
        for (int half = 0; half < 2; ++half) {
          const std::size_t f = s_.facet_index(wrap(i, nx_), wrap(j, ny_), half);
          if (static_cast<long>(f) == skip) continue;
          double A, B, C;  // plane z = A + B u + C v of the triangle
          if (!other_) {
            if (half == 0) A = h00, B = h10 - h00, C = h01 - h00;  // (v00, v10, v01)
            else A = h10 + h01 - h11, B = h11 - h01, C = h11 - h10;  // (v10, v11, v01)
          } else {
            if (half == 0) A = h00, B = h10 - h00, C = h11 - h10;  // (v00, v10, v11)
            else A = h00, B = h11 - h01, C = h01 - h00;           // (v00, v11, v01)
          }
          const double u0 = ox - i, v0 = oy - j;
          const double denom = d.z() - B * ux - C * uy;  // d . (-B/dx, -C/dy, 1)
          if (denom == 0) continue;
          const double t = (A + B * u0 + C * v0 - o.z()) / denom;
          if (!(t > tmin) || t >= best) continue;
          const double u = u0 + t * ux, v = v0 + t * uy;
          bool in;
          if (!other_) in = half == 0 ? (u >= -eps && v >= -eps && u + v <= 1 + eps)
                                      : (u <= 1 + eps && v <= 1 + eps && u + v >= 1 - eps);
          else in = half == 0 ? (u <= 1 + eps && v >= -eps && v <= u + eps)
                              : (u >= -eps && v <= 1 + eps && v >= u - eps);
          if (!in) continue;
          best = t;
          out.hit = true;
          out.backface = denom > 0;
          out.facet = f;
          out.n = Vec3(-B / dx_, -C / dy_, 1.0).normalized();
        }
        if (out.hit) {
          out.p = o + best * d;
          const double Lx = s_.macro().size_x, Ly = s_.macro().size_y;
          out.p.x() -= Lx * std::floor((out.p.x() - x0_) / Lx);
          out.p.y() -= Ly * std::floor((out.p.y() - y0_) / Ly);
          return out;
        }
      }
      if (d.z() > 0 && zb > hmax_) return out;  // above every vertex: escaped
      if ((d.z() < 0 && zb < hmin_ - 1e-9) || !std::isfinite(t_out)) {
        out.lost = d.z() <= 0;
        return out;
      }
      t_in = t_out;
      if (tmx < tmy) {
        i += sx;
        tmx += tdx;
      } else {
        j += sy;
        tmy += tdy;
      }
    }
    out.lost = true;
    return out;
  }

  struct Walk {
    int order = 0;
    bool lost = false;  // ended below the surface, on a back face, or past max_events
    std::vector<std::size_t> facets;
  };
  // A mirror random walk ([GeomBSDF24, eq. 13a] at every hit) from o along d.
  Walk mirror_walk(Vec3 o, Vec3 d, int max_events) const {
    Walk w;
    long skip = -1;
    for (;; ++w.order) {
      const Hit hit = first_hit(o, d, skip);
      if (!hit.hit) {
        w.lost = hit.lost || d.z() <= 0 || w.order == 0;
        return w;
      }
      if (hit.backface || w.order + 1 > max_events) {
        w.lost = true;
        return w;
      }
      w.facets.push_back(hit.facet);
      d = d - 2.0 * d.dot(hit.n) * hit.n;
      d.normalize();
      o = hit.p;
      skip = static_cast<long>(hit.facet);
    }
  }

 private:
  double h(long i, long j) const { return s_.height(i, j); }
  static long wrap(long i, long n) { return ((i % n) + n) % n; }
  const Microsurface& s_;
  long nx_, ny_;
  double dx_, dy_, x0_, y0_, hmin_ = 0, hmax_ = 0;
  bool other_;
};

}  // namespace microsim
