#include "microsim/measure/facet_table.hpp"

#include <algorithm>
#include <array>

#include <tbb/blocked_range.h>

namespace microsim {

FacetTable::FacetTable(const Microsurface& s, const DirectionBinning& binning) {
  size_ = s.num_facets();
  const bool heightfield = s.kind() == Microsurface::Kind::Heightfield;
  if (heightfield) {
    heights_ = s.heights().data();
    nx_ = static_cast<std::size_t>(s.nx());
    ny_ = static_cast<std::size_t>(s.ny());
    dx_ = s.dx();
    dy_ = s.dy();
    if (s.has_region()) {
      region_facets_ = size_;
      region_i0_ = static_cast<std::size_t>(s.region_i0());
      region_j0_ = static_cast<std::size_t>(s.region_j0());
      region_w_ = static_cast<std::size_t>(s.region_i1() - s.region_i0());
    }
  } else {
    normal_.resize(size_);
    area_.resize(size_);
  }
  const bool small = binning.size() < kNoBin16;
  if (small) bin16_.resize(size_);
  else bin32_.resize(size_);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, size_, 1 << 14),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) {
                        Vec3 m;
                        if (heightfield) {
                          m = normal(k);
                        } else {
                          const Vec3 c = s.facet(k).cross();
                          const double a = 0.5 * c.norm();
                          m = a > 0 ? Vec3(c / (2 * a)) : Vec3::UnitZ();
                          normal_[k] = m.cast<float>();
                          area_[k] = static_cast<float>(a);
                        }
                        const int b = binning.bin_of(m);
                        if (small) bin16_[k] = b < 0 ? kNoBin16 : static_cast<std::uint16_t>(b);
                        else bin32_[k] = b;
                      }
                    });
  if (heightfield) return;
  // Twins: same vertex positions (as a set), opposite normals.
  using Key = std::array<float, 9>;
  std::vector<std::pair<Key, std::uint32_t>> keys(size_);
  for (std::size_t k = 0; k < size_; ++k) {
    std::array<Eigen::Vector3f, 3> p;
    for (int c = 0; c < 3; ++c) p[c] = s.vertices()[s.triangles()[k][c]];
    std::sort(p.begin(), p.end(), [](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
      return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
    });
    Key key;
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) key[3 * c + d] = p[c][d];
    keys[k] = {key, static_cast<std::uint32_t>(k)};
  }
  std::sort(keys.begin(), keys.end());
  buried_.assign(size_, 0);
  for (std::size_t i = 0; i + 1 < size_; ++i)
    for (std::size_t j = i + 1; j < size_ && keys[j].first == keys[i].first; ++j) {
      const std::uint32_t a = keys[i].second, b = keys[j].second;
      if (normal_[a].dot(normal_[b]) < 0) buried_[a] = buried_[b] = 1;
    }
}

double FacetTable::bytes_per_facet() const {
  if (size_ == 0) return 0;
  const double bytes = 12.0 * normal_.size() + 4.0 * area_.size() + 2.0 * bin16_.size() +
                       4.0 * bin32_.size() + buried_.size();
  return bytes / static_cast<double>(size_);
}

FacetTable build_facet_table(const Microsurface& s, const DirectionBinning& binning) {
  return FacetTable(s, binning);
}

const FacetTable& facet_table_for(const Microsurface& s, const DirectionBinning& binning,
                                  const FacetTable* given, FacetTable& own) {
  if (!given) {
    own = build_facet_table(s, binning);
    return own;
  }
  if (given->size() != s.num_facets())
    throw RuntimeFailure("facet table does not match the surface");
  return *given;
}

}  // namespace microsim
