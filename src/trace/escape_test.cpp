#include "microsim/trace/escape_test.hpp"
#include "microsim/trace/tile_border.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace microsim {

namespace {
constexpr int kMaxSteps = 4096;  // cells and blocks visited before giving up (the tracer decides)
// The finest pyramid level kept: blocks of 4 x 4 cells (finer, the cells' own corners decide).
constexpr int kMinLevel = 2;
inline long wrap(long i, long n) {
  if (i >= 0 && i < n) return i;  // nearly always: no division
  if (i >= n && i < 2 * n) return i - n;
  if (i < 0 && i >= -n) return i + n;
  i %= n;
  return i < 0 ? i + n : i;
}
}  // namespace

EscapeTest::EscapeTest(const Tracer& tracer, double lower) : tracer_(tracer) {
  const Microsurface& s = tracer.surface();
  if (s.kind() != Microsurface::Kind::Heightfield || !s.macro().periodic || s.has_region()) return;
  nx_ = s.nx();
  ny_ = s.ny();
  dx_ = s.dx();
  dy_ = s.dy();
  x0_ = -0.5 * s.macro().size_x;
  y0_ = -0.5 * s.macro().size_y;
  h_ = s.heights().data();
  grid_ = static_cast<const float*>(
      rtcGetGeometryBufferData(rtcGetGeometry(tracer.scene(), 0), RTC_BUFFER_TYPE_VERTEX, 0));
  gw_ = static_cast<std::size_t>(nx_) + 3;  // Tracer: one periodic cell around the tile
  // Steepest facet slope (|grad h|), for turning horizontal errors into heights.
  double slope2 = 0;
  for (long j = 0; j < ny_; ++j)
    for (long i = 0; i < nx_; ++i) {
      const std::size_t r0 = static_cast<std::size_t>(j) * nx_, r1 = static_cast<std::size_t>(j + 1 == ny_ ? 0 : j + 1) * nx_;
      const long i1 = i + 1 == nx_ ? 0 : i + 1;
      const double h00 = h_[r0 + i], h10 = h_[r0 + i1], h01 = h_[r1 + i], h11 = h_[r1 + i1];
      const double a0 = (h10 - h00) / dx_, b0 = (h01 - h00) / dy_;
      const double a1 = (h11 - h01) / dx_, b1 = (h11 - h10) / dy_;
      slope2 = std::max({slope2, a0 * a0 + b0 * b0, a1 * a1 + b1 * b1});
    }
  const double slope = std::sqrt(slope2);
  // Magnitudes: coordinates within R of the origin of the tile (tile, heights, the half cell a
  // query runs past the border); one Embree query at most `longest` long (to the slab's face, or
  // past the tile's border: Tracer::trace). eps: 2^-24 of their sum bounds each float rounding
  // (vertex x, y; the ray's origin and direction over a query; Embree's arithmetic relative to
  // the ray origin), the double arithmetic here is far below it.
  const double L = std::max(s.macro().size_x, s.macro().size_y), cell = std::min(dx_, dy_);
  const double zr = tracer.z_top() - tracer.z_bottom();
  const double R = L + std::max(std::abs(tracer.z_top()), std::abs(tracer.z_bottom())) + cell;
  const double longest = zr + 2 * L + cell;
  const double eps = std::ldexp(R + longest + L, -24);
  // 8 times the rounding, horizontally (delta) and vertically; a horizontal error delta moves
  // the surface under the ray by at most slope * delta, and a ray passing beside an edge by
  // delta sees at most twice the slope between the two planes there.
  const double delta = 8 * eps;
  margin_ = delta * (1 + 2 * slope);
  shrink_ = 2 * delta / cell;  // the facet's neighbours may reach this far into it (cell units)
  if (!(shrink_ < 0.05) || !std::isfinite(margin_)) return;  // float grid too coarse for cells this small
  // Pyramid: level 1 from the vertices, then 2 x 2 blocks of the level below.
  for (int side = 0; side < 2; ++side) {
    long w = nx_, hgt = ny_;
    int L2 = 0;
    while (w > 1 || hgt > 1 || L2 == 0) {
      const long pw = w, ph = hgt;
      w = (w + 1) / 2;
      hgt = (hgt + 1) / 2;
      ++L2;
      std::vector<float> lev(static_cast<std::size_t>(w) * hgt);
      const long size = 1L << L2;
      if (L2 == 1) {
        tbb::parallel_for(0L, hgt, [&](long bj) {
          for (long bi = 0; bi < w; ++bi) {
            float m = -std::numeric_limits<float>::infinity();
            for (long j = bj * size; j <= std::min((bj + 1) * size, ny_); ++j) {
              const float* row = h_ + static_cast<std::size_t>(j == ny_ ? 0 : j) * nx_;
              for (long i = bi * size; i <= std::min((bi + 1) * size, nx_); ++i) {
                const float v = row[i == nx_ ? 0 : i];
                m = std::max(m, side == 0 ? v : -v);
              }
            }
            lev[static_cast<std::size_t>(bj) * w + bi] = m;
          }
        });
      } else {
        const std::vector<float>& below = levels_[side].back();
        for (long bj = 0; bj < hgt; ++bj)
          for (long bi = 0; bi < w; ++bi) {
            float m = -std::numeric_limits<float>::infinity();
            for (long cj = 2 * bj; cj < std::min(2 * bj + 2, ph); ++cj)
              for (long ci = 2 * bi; ci < std::min(2 * bi + 2, pw); ++ci)
                m = std::max(m, below[static_cast<std::size_t>(cj) * pw + ci]);
            lev[static_cast<std::size_t>(bj) * w + bi] = m;
          }
      }
      if (side == 0) {
        bw_.push_back(w);
        bh_.push_back(hgt);
      }
      levels_[side].push_back(std::move(lev));
    }
    top_[side] = levels_[side].back()[0];
    if (levels_[side].size() > 1) std::vector<float>().swap(levels_[side][0]);  // level 1: not traversed
    if (lower != 0)
      for (auto& lev : levels_[side])
        for (float& m : lev) m = static_cast<float>(m - lower);
  }
  applies_ = true;
}

void EscapeTest::prefetch(std::size_t facet, bool back) const {
  if (!applies_) return;
  const std::size_t cell = facet / 2;
  const long cj = static_cast<long>(cell / static_cast<std::size_t>(nx_));
  const long ci = static_cast<long>(cell - static_cast<std::size_t>(cj) * nx_);
  const int nlev = static_cast<int>(bw_.size());
  for (int s = 0; s < (back ? 2 : 1); ++s)
    for (int L = kMinLevel; L < std::min(nlev, kMinLevel + 3); ++L) {
      const long bi = ci >> L, bj = cj >> L, w = bw_[L - 1], h = bh_[L - 1];
      const float* lev = levels_[s][L - 1].data();
      // the block's row and the rows above and below (the ray's next blocks)
      for (long r = std::max(0L, bj - 1); r <= std::min(h - 1, bj + 1); ++r)
        __builtin_prefetch(lev + static_cast<std::size_t>(r) * w + bi);
    }
}

bool EscapeTest::clear(const Vec3& p, const Vec3& d, std::size_t facet, RaySide side) const {
  if (!applies_) return false;
  const int s = side == RaySide::Front ? 0 : 1;
  if (s == 0 ? !(d.z() > 0) : !(d.z() < 0)) return false;
  const std::size_t cell = facet / 2;
  const long cj = static_cast<long>(cell / static_cast<std::size_t>(nx_));
  const long ci = static_cast<long>(cell - static_cast<std::size_t>(cj) * nx_);
  if (s == 0) return clear_frame(p, d, ci, cj, static_cast<int>(facet % 2), 0);
  return clear_frame(Vec3(p.x(), p.y(), -p.z()), Vec3(d.x(), d.y(), -d.z()), ci, cj, static_cast<int>(facet % 2), 1);
}

// In the frame where the surface is g = +-h and the ray rises (d.z > 0).
bool EscapeTest::clear_frame(const Vec3& p, const Vec3& d, long ci, long cj, int half, int s) const {
  const double M = margin_, e = shrink_;
  const double u0 = (p.x() - x0_) / dx_, v0 = (p.y() - y0_) / dy_;  // cell units
  const double du = d.x() / dx_, dv = d.y() / dy_, z0 = p.z(), dz = d.z();
  const double inf = std::numeric_limits<double>::infinity();
  // Crossing times by multiplication: their rounding moves a crossing by far less than the
  // margin allows for (the clearances are continuous along the ray).
  const double iu = du != 0 ? 1 / du : 0, iv = dv != 0 ? 1 / dv : 0;
  // Corner heights of cell (i, j) and its triangles' planes in local coordinates (a, b) in [0, 1]^2:
  // half 0 (v00, v10, v01): g00 + (g10 - g00) a + (g01 - g00) b; half 1 (v10, v11, v01):
  // g11 + (g11 - g01) (a - 1) + (g11 - g10) (b - 1) (Microsurface::facet).
  struct Plane {
    double c, ga, gb;  // height at (a, b) = c + ga a + gb b
  };
  auto planes = [&](long i, long j, Plane out[2], double* gmax) {
    // The cell's corners from the tracer's vertex buffer (the rows its traversal just read).
    const float* r0 = grid_ + 3 * (static_cast<std::size_t>(wrap(j, ny_) + 1) * gw_ + wrap(i, nx_) + 1) + 2;
    const float* r1 = r0 + 3 * gw_;
    const double sg = s == 0 ? 1.0 : -1.0;
    const double g00 = sg * r0[0], g10 = sg * r0[3], g01 = sg * r1[0], g11 = sg * r1[3];
    out[0] = {g00, g10 - g00, g01 - g00};
    out[1] = {g11 - (g11 - g01) - (g11 - g10), g11 - g01, g11 - g10};
    if (gmax) *gmax = std::max({g00, g10, g01, g11});
  };
  // Clearance of the ray above plane P of cell (i, j) at t.
  auto clearance = [&](const Plane& P, long i, long j, double t) {
    const double a = u0 + du * t - i, b = v0 + dv * t - j;
    return z0 + dz * t - (P.c + P.ga * a + P.gb * b);
  };
  // Where the ray leaves cell (i, j) (from inside): t and the next cell.
  auto cell_exit = [&](long i, long j, long& ni, long& nj) {
    const double tx = du > 0 ? (i + 1 - u0) * iu : du < 0 ? (i - u0) * iu : inf;
    const double ty = dv > 0 ? (j + 1 - v0) * iv : dv < 0 ? (j - v0) * iv : inf;
    const double t = std::min(tx, ty);
    ni = i + (tx <= t ? (du > 0 ? 1 : -1) : 0);
    nj = j + (ty <= t ? (dv > 0 ? 1 : -1) : 0);
    return t;
  };
  // Half `hf` of cell (i, j) clear of the ray over [ta, tb] (the ray over the cell then).
  auto triangle_clear = [&](const Plane& P, int hf, long i, long j, double ta, double tb) {
    const double wa = u0 + du * ta - i + v0 + dv * ta - j - 1, wb = u0 + du * tb - i + v0 + dv * tb - j - 1;
    // half 0: w <= 0; half 1: w >= 0 (w = a + b - 1, linear in t)
    const bool ina = hf == 0 ? wa <= 0 : wa >= 0, inb = hf == 0 ? wb <= 0 : wb >= 0;
    if (!ina && !inb) return true;
    double a = ta, b = tb;
    if (ina != inb) {
      const double tc = std::min(std::max(ta + (tb - ta) * (wa / (wa - wb)), ta), tb);
      if (ina) b = tc;
      else a = tc;
    }
    return clearance(P, i, j, a) > M && clearance(P, i, j, b) > M;
  };

  // The ray's own cell: over the source facet shrunk by e its hits are the tracer's filter's
  // (rejected); past that the clearance to the source plane grows along the ray, so its value
  // where the ray leaves the shrunk facet bounds it; the cell's other half as any triangle.
  Plane P[2];
  double gmax;
  planes(ci, cj, P, &gmax);
  const double a0 = u0 - ci, b0 = v0 - cj;
  // Constraints c0 + c1 t >= 0 of the shrunk facet.
  double k0[3], k1[3];
  if (half == 0) {
    k0[0] = a0 - e, k1[0] = du;
    k0[1] = b0 - e, k1[1] = dv;
    k0[2] = 1 - 2 * e - a0 - b0, k1[2] = -du - dv;
  } else {
    k0[0] = 1 - e - a0, k1[0] = -du;
    k0[1] = 1 - e - b0, k1[1] = -dv;
    k0[2] = a0 + b0 - 1 - 2 * e, k1[2] = du + dv;
  }
  double t_star = inf;
  for (int c = 0; c < 3; ++c) {
    if (!(k0[c] > 0)) return false;  // at (or rounded past) the facet's border
    if (k1[c] < 0) t_star = std::min(t_star, k0[c] / -k1[c]);
  }
  const Plane& src = P[half];
  const double rise = dz - (src.ga * du + src.gb * dv);  // d(clearance)/dt over the source plane
  if (!(rise > 0)) return false;
  if (t_star == inf || z0 + dz * t_star > top_[s] + M) return true;  // above everything over its own facet
  if (!(clearance(src, ci, cj, t_star) > M)) return false;
  long i, j;
  const double t_cell = cell_exit(ci, cj, i, j);
  if (!triangle_clear(P[1 - half], 1 - half, ci, cj, 0.0, t_cell)) return false;
  double t = t_cell;

  const int nlev = static_cast<int>(bw_.size());  // levels 1 .. nlev; the last is the whole tile
  int start = kMinLevel;
  for (int step = 0; step < kMaxSteps; ++step) {
    const double zt = z0 + dz * t;
    if (zt > top_[s] + M) return true;
    const long wi = wrap(i, nx_), wj = wrap(j, ny_);
    // The cell's own highest corner: no block holding the cell is lower, so below it the
    // triangles decide. Near the surface (after a cell step) it is read first; after a block
    // was skipped the ray is usually high and the blocks come first (the cell's corners are
    // then rarely in cache).
    long ni = i, nj = j;
    double te = inf;
    bool above_cell = false;
    auto cell_test = [&]() {
      planes(i, j, P, &gmax);
      te = cell_exit(i, j, ni, nj);
      if (te == inf) return false;
      above_cell = zt > gmax + M;
      return above_cell || (triangle_clear(P[0], 0, i, j, t, te) && triangle_clear(P[1], 1, i, j, t, te));
    };
    const bool blocks_first = start > kMinLevel;
    if (!blocks_first) {
      if (!cell_test()) return false;
      if (!above_cell) {
        i = ni;
        j = nj;
        t = std::max(t, te);
        continue;
      }
    }
    bool jumped = false;
    for (int L = std::min(start, nlev - 1); L >= kMinLevel; --L) {
      const long bi = wi >> L, bj = wj >> L;
      if (!(zt > levels_[s][L - 1][static_cast<std::size_t>(bj) * bw_[L - 1] + bi] + M)) continue;
      // Above the block's highest vertex where it enters: over all of it. Its bounds unwrapped.
      const long ilo = i - (wi - (bi << L)), ihi = ilo + std::min(1L << L, nx_ - (bi << L));
      const long jlo = j - (wj - (bj << L)), jhi = jlo + std::min(1L << L, ny_ - (bj << L));
      const double tx = du > 0 ? (ihi - u0) * iu : du < 0 ? (ilo - u0) * iu : inf;
      const double ty = dv > 0 ? (jhi - v0) * iv : dv < 0 ? (jlo - v0) * iv : inf;
      const double tb = std::min(tx, ty);
      if (tb == inf) return false;  // vertical: stays over this block (not claimed)
      const long fi = std::min(std::max(static_cast<long>(std::floor(u0 + du * tb)), ilo), ihi - 1);
      const long fj = std::min(std::max(static_cast<long>(std::floor(v0 + dv * tb)), jlo), jhi - 1);
      i = tx <= tb ? (du > 0 ? ihi : ilo - 1) : fi;
      j = ty <= tb ? (dv > 0 ? jhi : jlo - 1) : fj;
      t = std::max(t, tb);
      start = L + 1;
      jumped = true;
      break;
    }
    if (jumped) continue;
    start = kMinLevel;
    if (blocks_first && !cell_test()) return false;
    i = ni;
    j = nj;
    t = std::max(t, te);
  }
  return false;
}

TraceHit EscapeTest::no_hit(const Vec3& org, const Vec3& dir, TraceCounters& c, RaySide side) const {
  // Tracer::trace for a periodic heightfield, every query answering "no hit".
  TraceHit out;
  ++c.rays;
  const Macrosurface& macro = tracer_.surface().macro();
  const bool back = side == RaySide::Back;
  Vec3 o = org;
  const double hx = 0.5 * macro.size_x, hy = 0.5 * macro.size_y;
  if (o.x() < -hx || o.x() > hx) o.x() -= macro.size_x * std::floor((o.x() + hx) / macro.size_x);
  if (o.y() < -hy || o.y() > hy) o.y() -= macro.size_y * std::floor((o.y() + hy) / macro.size_y);
  const double z_top = tracer_.z_top(), z_bottom = tracer_.z_bottom();
  for (int segment = 0; segment < 100000; ++segment) {
    const double t_exit = distance_to_tile_border(o, dir, hx, hy);
    double t_slab = std::numeric_limits<double>::infinity();
    if (dir.z() > 0) t_slab = (z_top - o.z()) / dir.z();
    if (dir.z() < 0) t_slab = (z_bottom - o.z()) / dir.z();
    if (t_slab < 0 || t_slab <= t_exit) {
      if (dir.z() < 0) {
        if (back) out.exit_below = true;
        else ++c.lost_below;
      }
      return out;
    }
    o += t_exit * dir;
    reenter_opposite_side(o, dir, macro);
    ++c.border_crossings;
  }
  ++c.unresolved;
  return out;
}

}  // namespace microsim
