// Per-unit BSDF path sums as rows of one exchange (path_sums_exchange.hpp).
#include "path_sums_exchange.hpp"

#include <algorithm>

#include "microsim/tally_fields.hpp"

namespace microsim {

namespace {

constexpr std::size_t kPathCounts = scalar_field_count<BsdfTally>();
std::size_t path_reals(const BsdfTally& t, bool second) {
  std::size_t n = second ? 1 : 0;  // both2
  BsdfTally::for_each_moment([&](const char*, auto sum, auto) { n += (t.*sum).size() * (second ? 2 : 1); });
  return n;
}
void pack_paths(const BsdfTally& t, bool second, std::uint64_t* c, double* x) {
  pack_fields(t, c);
  BsdfTally::for_each_moment([&](const char*, auto sum, auto) { x = std::copy((t.*sum).begin(), (t.*sum).end(), x); });
  if (!second) return;
  BsdfTally::for_each_moment([&](const char*, auto, auto m2) { x = std::copy((t.*m2).begin(), (t.*m2).end(), x); });
  *x = t.both2;
}
void unpack_paths(BsdfTally& t, bool second, const std::uint64_t* c, const double* x) {
  unpack_fields(t, c);
  const auto read = [&](std::vector<double>& v) {
    std::copy(x, x + v.size(), v.begin());
    x += v.size();
  };
  BsdfTally::for_each_moment([&](const char*, auto sum, auto) { read(t.*sum); });
  if (!second) return;
  BsdfTally::for_each_moment([&](const char*, auto, auto m2) { read(t.*m2); });
  t.both2 = *x;
}

}  // namespace

void exchange_paths(TallySplit& split, const char* kind, UnitRange share, bool second,
                    std::vector<BsdfTally>& units) {
  Tallies t(kind, units.size(), share, kPathCounts, path_reals(units[0], second), 0, 0);
  for (std::size_t u = 0; u < units.size(); ++u)
    if (share.contains(u)) pack_paths(units[u], second, t.count_row(u), t.real_row(u));
  split.exchange(t);
  for (std::size_t u = 0; u < units.size(); ++u) unpack_paths(units[u], second, t.count_row(u), t.real_row(u));
}

}  // namespace microsim
