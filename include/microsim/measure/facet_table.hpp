// Per-facet data the estimators need (unit normal m_f, area A_f, normal bin) and the draw of
// facets with probability proportional to a per-facet weight, in little memory: a heightfield's
// normals and areas are derived from its heights when needed (a cross product of two grid
// edges), so that only the bin index is stored per facet (2 bytes for up to 65534 bins).
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "microsim/measure/binning.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// Direction-independent facet data, computed once and shared by the directions of a run.
// It refers to the heights of the surface it was built from (which must outlive it; moving
// the surface is fine, copying it and dropping the original is not).
class FacetTable {
 public:
  FacetTable() = default;
  FacetTable(const Microsurface& s, const DirectionBinning& binning);

  std::size_t size() const { return size_; }
  // Unit normal m_f and area A_f of facet k. Heightfields: exact from the heights (the same
  // cross product as Tracer::facet_of_hit), in double.
  void normal_area(std::size_t k, Vec3& m, double& a) const {
    if (heights_) {
      const Vec3 c = heightfield_cross(k);
      const double len = c.norm();
      a = 0.5 * len;
      m = len > 0 ? Vec3(c / len) : Vec3::UnitZ();
      return;
    }
    m = normal_[k].cast<double>();
    a = area_[k];
  }
  // 2 A_f m_f: the facet's weights A_f (v.m_f) as 0.5 cross(k).v without a square root.
  Vec3 cross(std::size_t k) const {
    if (heights_) return heightfield_cross(k);
    return (2.0 * static_cast<double>(area_[k])) * normal_[k].cast<double>();
  }
  // f(k, cross(k)) for k in [k0, k1) in order: the same values as cross(k), with the cell of
  // a heightfield facet found by one division for the run instead of one per facet.
  template <class F>
  void for_each_cross(std::size_t k0, std::size_t k1, F&& f) const {
    if (!heights_) {
      for (std::size_t k = k0; k < k1; ++k) f(k, cross(k));
      return;
    }
    const bool region = k0 < region_facets_;
    const std::size_t width = region ? region_w_ : nx_, base_i = region ? region_i0_ : 0;
    const std::size_t cell = (region ? k0 : k0 - region_facets_) / 2;
    std::size_t i0 = base_i + cell % width, j0 = (region ? region_j0_ : 0) + cell / width;
    for (std::size_t k = k0; k < k1; ++k) {
      f(k, cell_cross(i0, j0, k % 2));
      if (k % 2 == 1 && ++i0 == base_i + width) {
        i0 = base_i;
        ++j0;
      }
    }
  }
  Vec3 normal(std::size_t k) const {
    Vec3 m;
    double a;
    normal_area(k, m, a);
    return m;
  }
  double area(std::size_t k) const {
    Vec3 m;
    double a;
    normal_area(k, m, a);
    return a;
  }
  // A hint for a bin(k) call a little later (no effect on any result); k may be out of range.
  void prefetch(std::size_t k) const {
    if (k < bin16_.size()) __builtin_prefetch(bin16_.data() + k);
  }
  // The same hint for facets [k0, k1) (at most a row of cells): their bins and, on a
  // heightfield, the two rows of heights that their cross products read.
  void prefetch_range(std::size_t k0, std::size_t k1) const {
    if (k1 <= k0) return;
    prefetch(k0);
    prefetch(k1 - 1);
    if (!heights_ || k0 < region_facets_) return;
    for (std::size_t k : {k0, k1 - 1}) {
      const std::size_t cell = (k - region_facets_) / 2, j0 = cell / nx_;
      const std::size_t i0 = cell - j0 * nx_, j1 = j0 + 1 == ny_ ? 0 : j0 + 1;
      __builtin_prefetch(heights_ + j0 * nx_ + i0);
      __builtin_prefetch(heights_ + j1 * nx_ + i0);
    }
  }
  int bin(std::size_t k) const {
    if (!bin16_.empty()) return bin16_[k] == kNoBin16 ? -1 : bin16_[k];
    return bin32_[k];
  }
  // The bins as stored, for loops that read many: bin(k) is bins16()[k] when bins16() is not
  // null (kNoBin16: none), else bin32()[k].
  static constexpr std::uint16_t kNoBin16 = 0xFFFF;
  const std::uint16_t* bins16() const { return bin16_.empty() ? nullptr : bin16_.data(); }
  const int* bins32() const { return bin32_.empty() ? nullptr : bin32_.data(); }
  // Meshes: facets pressed against an opposite-facing twin with the same three vertex
  // positions (walls of touching boxes, [GeomBSDF24, Fig. 6]): no ray can reach them, so area sampling
  // counts them occluded without tracing (an occlusion ray leaving one starts inside the
  // neighbour).
  bool buried(std::size_t k) const { return !buried_.empty() && buried_[k]; }
  // Bytes held per facet (for the memory reports of the benchmark).
  double bytes_per_facet() const;

 private:
  // 2 x area x normal of heightfield facet k; facet 2c = (v00, v10, v01), 2c+1 = (v10, v11, v01)
  // of cell c (Microsurface::facet).
  // With a sample region, its facets come first (Microsurface::facet numbering).
  Vec3 heightfield_cross(std::size_t k) const {
    std::size_t i0, j0;
    if (k < region_facets_) {
      const std::size_t cell = k / 2;
      i0 = region_i0_ + cell % region_w_;
      j0 = region_j0_ + cell / region_w_;
    } else {
      const std::size_t cell = (k - region_facets_) / 2;
      i0 = cell % nx_;
      j0 = cell / nx_;
    }
    return cell_cross(i0, j0, k % 2);
  }
  Vec3 cell_cross(std::size_t i0, std::size_t j0, std::size_t half) const {
    const std::size_t i1 = i0 + 1 == nx_ ? 0 : i0 + 1, j1 = j0 + 1 == ny_ ? 0 : j0 + 1;
    const double h00 = heights_[j0 * nx_ + i0], h10 = heights_[j0 * nx_ + i1];
    const double h01 = heights_[j1 * nx_ + i0], h11 = heights_[j1 * nx_ + i1];
    if (half == 0) return Vec3(-(h10 - h00) * dy_, -(h01 - h00) * dx_, dx_ * dy_);
    return Vec3(-(h11 - h01) * dy_, -(h11 - h10) * dx_, dx_ * dy_);
  }

  std::size_t size_ = 0;
  const float* heights_ = nullptr;  // heightfields only
  std::size_t nx_ = 0, ny_ = 0;
  double dx_ = 0, dy_ = 0;
  std::size_t region_facets_ = 0, region_i0_ = 0, region_j0_ = 0, region_w_ = 1;
  std::vector<Eigen::Vector3f> normal_;  // meshes only
  std::vector<float> area_;              // meshes only
  std::vector<std::uint16_t> bin16_;     // bins when fewer than 65535, else bin32_
  std::vector<int> bin32_;
  std::vector<std::uint8_t> buried_;
};

FacetTable build_facet_table(const Microsurface& s, const DirectionBinning& binning);
// The caller's table when given (checked against the surface), else one built into `own`.
const FacetTable& facet_table_for(const Microsurface& s, const DirectionBinning& binning,
                                  const FacetTable* given, FacetTable& own);

// Draws facet indices with probability proportional to weights w_k >= 0 that are computed on
// demand: the cumulative sums of blocks of kBlock consecutive facets (8 bytes per block), and
// inside the chosen block a scan of its weights. `weight(k)` must be the same deterministic
// function at construction and at every draw. Everything is summed in a fixed order: the
// draws do not depend on the thread count.
class BlockFacetSampler {
 public:
  static constexpr std::size_t kBlock = 16;

  template <class Weight>
  BlockFacetSampler(std::size_t n, const Weight& weight)
      : BlockFacetSampler(n, Blocks{}, [&](std::size_t k0, std::size_t k1, double* w) {
          for (std::size_t k = k0; k < k1; ++k) w[k - k0] = weight(k);
        }) {}
  // The same with the weights of a block computed at once: block_weights(k0, k1, w) sets
  // w[k - k0] = w_k for k in [k0, k1) (at most kBlock facets).
  struct Blocks {};
  template <class BlockWeights>
  BlockFacetSampler(std::size_t n, Blocks, const BlockWeights& block_weights)
      : n_(n), cdf_((n + kBlock - 1) / kBlock) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cdf_.size(), 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        double w[kBlock];
                        for (std::size_t b = r.begin(); b != r.end(); ++b) {
                          const std::size_t k0 = b * kBlock, k1 = std::min(n_, k0 + kBlock);
                          block_weights(k0, k1, w);
                          double s = 0;
                          for (std::size_t k = k0; k < k1; ++k) s += w[k - k0];
                          cdf_[b] = s;
                        }
                      });
    for (std::size_t b = 1; b < cdf_.size(); ++b) cdf_[b] += cdf_[b - 1];
  }
  double total() const { return cdf_.empty() ? 0.0 : cdf_.back(); }

  // The facet k whose slice [W_{k-1}, W_k) of the cumulative weights holds u, u in [0, total);
  // never a facet of zero weight.
  template <class Weight>
  std::size_t draw(double u, const Weight& weight) const {
    return draw(u, Blocks{}, [&](std::size_t k0, std::size_t k1, double* w) {
      for (std::size_t k = k0; k < k1; ++k) w[k - k0] = weight(k);
    });
  }
  // `hint` (optional): the block of an earlier draw, updated. Draws with increasing u (a
  // stratified pass) then search forward from it instead of over the whole table; the block
  // found is the same.
  template <class BlockWeights>
  std::size_t draw(double u, Blocks, const BlockWeights& block_weights,
                   std::size_t* hint = nullptr) const {
    return draw_in(block(u, hint), u, block_weights);
  }
  // draw() in two steps, for callers that load a block's data (prefetch) before drawing in
  // it: the block of kBlock facets that u falls in (hint as for draw), then the facet.
  std::size_t block(double u, std::size_t* hint = nullptr) const {
    std::size_t b = hint ? upper_block(u, *hint) : upper_block(u, 0);
    if (hint) *hint = b;
    b = std::min(b, cdf_.size() - 1);
    while (b > 0 && cdf_[b] == cdf_[b - 1]) --b;  // never an empty block
    return b;
  }
  template <class BlockWeights>
  std::size_t draw_in(std::size_t b, double u, const BlockWeights& block_weights) const {
    const double local = u - (b > 0 ? cdf_[b - 1] : 0.0);
    std::size_t last = b * kBlock;  // last facet of positive weight seen (rounding fallback)
    double s = 0;
    const std::size_t k0 = b * kBlock, k1 = std::min(n_, k0 + kBlock);
    double ws[kBlock];
    block_weights(k0, k1, ws);
    for (std::size_t k = k0; k < k1; ++k) {
      const double w = ws[k - k0];
      if (w <= 0) continue;
      s += w;
      last = k;
      if (s > local) return k;
    }
    return last;
  }
  double bytes() const { return 8.0 * cdf_.size(); }

 private:
  // The first block b with cdf_[b] > u (std::upper_bound), searched by doubling steps from
  // `from` when every block before it is <= u, else over the whole table.
  std::size_t upper_block(double u, std::size_t from) const {
    if (from >= cdf_.size() || (from > 0 && cdf_[from - 1] > u))
      return std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin();
    std::size_t lo = from, step = 1;  // every block before lo is <= u
    while (lo + step < cdf_.size() && cdf_[lo + step - 1] <= u) {
      lo += step;
      step *= 2;
    }
    const std::size_t hi = std::min(cdf_.size(), lo + step);
    return std::upper_bound(cdf_.begin() + lo, cdf_.begin() + hi, u) - cdf_.begin();
  }

 private:
  std::size_t n_;
  std::vector<double> cdf_;
};

}  // namespace microsim
