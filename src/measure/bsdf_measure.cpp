#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/exit_counts.hpp"
#include "microsim/measure/groove_models.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/sampling.hpp"
#include "microsim/measure/spectral_tally.hpp"
#include "microsim/measure/smith_walk_budget.hpp"
#include "microsim/measure/table_run_sums.hpp"
#include "microsim/measure/vcavity_measure.hpp"
#include "path_sums_exchange.hpp"
#include "walk_passes.hpp"
#include "microsim/surface/generators.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <type_traits>

namespace microsim {

// ---------------------------------------------------------------------------------------------
// HemisphereMap
// ---------------------------------------------------------------------------------------------

namespace {

// Exact integral of 1 - max(a^2, b^2) over a triangle on which max(a^2, b^2) is one of the two
// squares (decided at the centroid): the edge-midpoint rule is exact for quadratics.
double triangle_integral(const Vec2& p0, const Vec2& p1, const Vec2& p2) {
  const Vec2 c = (p0 + p1 + p2) / 3.0;
  const bool use_a = std::abs(c.x()) >= std::abs(c.y());
  auto g = [&](const Vec2& q) { return 1.0 - (use_a ? q.x() * q.x() : q.y() * q.y()); };
  const double area = 0.5 * std::abs((p1 - p0).x() * (p2 - p0).y() - (p1 - p0).y() * (p2 - p0).x());
  return area * (g(0.5 * (p0 + p1)) + g(0.5 * (p1 + p2)) + g(0.5 * (p2 + p0))) / 3.0;
}

}  // namespace

HemisphereMap::HemisphereMap(int resolution)
    : res_(resolution),
      edge_margin_(16 * 0.5 * resolution * (4 / kPi * (kAzimuthError + 2e-15) + 4e-15)) {
  if (resolution < 1) throw ParameterError("{resolution} must be at least 1");
  cos_integral_.resize(static_cast<std::size_t>(res_) * res_);
  const double h = 2.0 / res_;
  for (int j = 0; j < res_; ++j)
    for (int i = 0; i < res_; ++i) {
      // The global diagonals |a| = |b| run along pixel diagonals only, so splitting every pixel
      // by its two diagonals leaves triangles on which the integrand is one quadratic.
      const Vec2 p00(-1 + i * h, -1 + j * h), p10(-1 + (i + 1) * h, -1 + j * h);
      const Vec2 p01(-1 + i * h, -1 + (j + 1) * h), p11(-1 + (i + 1) * h, -1 + (j + 1) * h);
      const Vec2 c = 0.25 * (p00 + p10 + p01 + p11);
      const double sum = triangle_integral(p00, p10, c) + triangle_integral(p10, p11, c) +
                         triangle_integral(p11, p01, c) + triangle_integral(p01, p00, c);
      cos_integral_[static_cast<std::size_t>(j) * res_ + i] = 0.5 * kPi * sum;  // d omega = pi/2 da db
    }
}

namespace {

// The square coordinates at radius r > 0 and azimuth phi in [-pi/4, 7pi/4) (the concentric map
// backwards), one expression per sector; its sector is sector_of(phi).
int sector_of(double phi) {
  return phi < 0.25 * kPi ? 0 : phi < 0.75 * kPi ? 1 : phi < 1.25 * kPi ? 2 : 3;
}
Vec2 square_of(double r, double phi) {
  const double q = 4.0 / kPi;
  switch (sector_of(phi)) {
    case 0: return Vec2(r, r * phi * q);
    case 1: return Vec2(r * (0.5 * kPi - phi) * q, r);
    case 2: return Vec2(-r, -r * (phi - kPi) * q);
    default: return Vec2(-r * (1.5 * kPi - phi) * q, -r);
  }
}

// atan(k / 16), k = 0 .. 16 (azimuth_near).
struct AtanTable {
  double v[17];
  AtanTable() {
    for (int k = 0; k <= 16; ++k) v[k] = std::atan(k / 16.0);
  }
};
const AtanTable kAtanOfSixteenths;

}  // namespace

double azimuth_near(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const bool steep = ay > ax;
  const double num = steep ? ax : ay, den = steep ? ay : ax;
  const int k = static_cast<int>(num / den * 16 + 0.5);
  const double c = k * (1.0 / 16);
  const double u = (num - c * den) / (den + c * num);
  const double u2 = u * u;
  double a = kAtanOfSixteenths.v[k] +
             u * (1 - u2 * (1.0 / 3 - u2 * (1.0 / 5 - u2 * (1.0 / 7 - u2 * (1.0 / 9)))));
  if (steep) a = 0.5 * kPi - a;
  if (x < 0) a = kPi - a;
  return std::signbit(y) ? -a : a;
}

Vec2 HemisphereMap::to_square(const Vec3& d) const {
  const double z = std::min(1.0, std::abs(d.z()) / d.norm());
  const double r = std::sqrt(std::max(0.0, 1.0 - z));
  if (r == 0.0) return Vec2(0.0, 0.0);
  double phi = std::atan2(d.y(), d.x());  // (-pi, pi]
  if (phi < -0.25 * kPi) phi += 2 * kPi;  // [-pi/4, 7pi/4)
  return square_of(r, phi);
}

Vec3 HemisphereMap::from_square(double a, double b) const {
  double r, phi;
  if (a == 0.0 && b == 0.0) return Vec3(0, 0, 1);
  if (std::abs(a) >= std::abs(b)) {
    r = a;
    phi = 0.25 * kPi * b / a;
  } else {
    r = b;
    phi = 0.5 * kPi - 0.25 * kPi * a / b;
  }
  const double s = r * std::sqrt(std::max(0.0, 2.0 - r * r));
  return Vec3(s * std::cos(phi), s * std::sin(phi), 1.0 - r * r);
}

namespace {
int pixel_of_square(const Vec2& sq, int res) {
  const int i = std::clamp(static_cast<int>(std::floor((sq.x() + 1.0) * 0.5 * res)), 0, res - 1);
  const int j = std::clamp(static_cast<int>(std::floor((sq.y() + 1.0) * 0.5 * res)), 0, res - 1);
  return j * res + i;
}
}  // namespace

int HemisphereMap::pixel_of_exact(const Vec3& d) const { return pixel_of_square(to_square(d), res_); }

int HemisphereMap::pixel_of(const Vec3& d, double edge_margin) const {
  // As to_square, with the azimuth of azimuth_near: r is the same, and so is the sector unless
  // the azimuth is within kSectorMargin of a sector border (then std::atan2's might be across).
  // In its sector the radial coordinate is +-r (the same), the angular one moves by at most
  // 4/pi |phi - phi'| plus rounding, i.e. less than edge_margin_ pixels: unless it is that near
  // a pixel border, its pixel is to_square's.
  const double z = std::min(1.0, std::abs(d.z()) / d.norm());
  const double r = std::sqrt(std::max(0.0, 1.0 - z));
  const double ax = std::abs(d.x()), ay = std::abs(d.y());
  if (!(r > 0.0) || !(std::max(ax, ay) >= 1e-150 && std::max(ax, ay) <= 1e150)) return pixel_of_exact(d);
  double phi = azimuth_near(d.y(), d.x());
  const double m = kSectorMargin;
  if (std::abs(phi + 0.25 * kPi) <= m) return pixel_of_exact(d);
  if (phi < -0.25 * kPi) phi += 2 * kPi;
  const int sector = sector_of(phi);
  if (std::abs(phi - 0.25 * kPi) <= m || std::abs(phi - 0.75 * kPi) <= m ||
      std::abs(phi - 1.25 * kPi) <= m)
    return pixel_of_exact(d);
  const Vec2 sq = square_of(r, phi);
  const double x = ((sector % 2 == 0 ? sq.y() : sq.x()) + 1.0) * 0.5 * res_;
  const double f = x - std::floor(x);
  if (!(f >= edge_margin && f <= 1 - edge_margin)) return pixel_of_exact(d);
  return pixel_of_square(sq, res_);
}

// ---------------------------------------------------------------------------------------------
// InPlaneBins
// ---------------------------------------------------------------------------------------------

InPlaneBins::InPlaneBins(double phi_i, int n_bins)
    : n_(n_bins), width_(kPi / std::max(1, n_bins)), delta_(0.5 * kPi / std::max(1, n_bins)),
      sin_delta_(std::sin(delta_)) {
  s_ = Vec3(-std::cos(phi_i), -std::sin(phi_i), 0.0);
  p_ = Vec3::UnitZ().cross(s_);
}

int InPlaneBins::bin_of(const Vec3& d0, double band_margin) const {
  // |d.p| > sin(delta) for d = d0 / |d0|, on squares: where |d0.p| / |d0| exceeds
  // sin(delta) + band_margin, bin_of_exact's |d.p| (d0 normalised, then the product: within a
  // few 1e-16 of it) exceeds sin(delta). Squares only where they are normal numbers.
  const double n2 = d0.squaredNorm();
  if (n2 >= 1e-200 && n2 <= 1e200) {
    const double sb0 = d0.dot(p_), lim = sin_delta_ + band_margin;
    if (sb0 * sb0 > lim * lim * n2) return -1;
  }
  return bin_of_exact(d0);
}

int InPlaneBins::bin_of_exact(const Vec3& d0) const {
  const Vec3 d = d0.normalized();
  const double sb = d.dot(p_);
  if (std::abs(sb) > sin_delta_) return -1;
  const double psi = std::atan2(d.dot(s_), std::abs(d.z()));
  const int b = static_cast<int>(std::floor((psi + 0.5 * kPi) / width_));
  return std::clamp(b, 0, n_ - 1);
}

double InPlaneBins::cos_integral(int b) const {
  return (delta_ + std::sin(delta_) * std::cos(delta_)) * (std::sin(psi_hi(b)) - std::sin(psi_lo(b)));
}

Vec3 InPlaneBins::direction(double psi, double beta, bool above) const {
  const Vec3 n = above ? Vec3::UnitZ() : Vec3(-Vec3::UnitZ());
  return std::cos(beta) * (std::sin(psi) * s_ + std::cos(psi) * n) + std::sin(beta) * p_;
}

double InPlaneBins::cos_weighted_average(int b, bool above,
                                         const std::function<double(const Vec3&)>& f) const {
  static const double x6[6] = {-0.9324695142031521, -0.6612093864662645, -0.2386191860831969,
                               0.2386191860831969,  0.6612093864662645,  0.9324695142031521};
  static const double w6[6] = {0.1713244923791704, 0.3607615730481386, 0.4679139345726910,
                               0.4679139345726910, 0.3607615730481386, 0.1713244923791704};
  const double p0 = psi_lo(b), p1 = psi_hi(b);
  double num = 0.0, den = 0.0;
  for (int u = 0; u < 6; ++u) {
    const double psi = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * x6[u];
    for (int v = 0; v < 6; ++v) {
      const double beta = delta_ * x6[v];
      const double w = w6[u] * w6[v] * std::cos(beta) * std::cos(beta) * std::cos(psi);
      num += w * f(direction(psi, beta, above));
      den += w;
    }
  }
  return den > 0 ? num / den : 0.0;
}

// ---------------------------------------------------------------------------------------------
// Tallies
// ---------------------------------------------------------------------------------------------

BsdfTally::BsdfTally(int K, int npix, int nplane) : orders(K), pixels(npix), plane_bins(nplane) {
  const std::size_t s = 2 * static_cast<std::size_t>(K + 1);
  albedo.assign(s, 0.0);
  albedo2.assign(s, 0.0);
  pix.assign(s * npix, 0.0);
  pix2.assign(s * npix, 0.0);
  plane.assign(s * nplane, 0.0);
  plane2.assign(s * nplane, 0.0);
}

BsdfTally BsdfTally::first_moments(int K, int npix, int nplane) {
  BsdfTally t;
  t.orders = K;
  t.pixels = npix;
  t.plane_bins = nplane;
  const std::size_t s = 2 * static_cast<std::size_t>(K + 1);
  t.albedo.assign(s, 0.0);
  t.pix.assign(s * npix, 0.0);
  t.plane.assign(s * nplane, 0.0);
  return t;
}

void BsdfTally::add_exit(int s, int order, double w, int px, int b) {
  const int k = std::min(order, orders) - 1;
  const double w2 = w * w;
  both2 += w2;  // a path leaves on one side only
  for (int slot : {k, orders}) {
    albedo[a_index(s, slot)] += w;
    albedo2[a_index(s, slot)] += w2;
    if (px >= 0) {
      pix[p_index(s, slot, px)] += w;
      pix2[p_index(s, slot, px)] += w2;
    }
    if (b >= 0) {
      plane[b_index(s, slot, b)] += w;
      plane2[b_index(s, slot, b)] += w2;
    }
  }
}

BsdfTally& BsdfTally::operator+=(const BsdfTally& o) {
  if (albedo.empty()) return *this = o;
  if (o.albedo.empty()) return *this;
  auto add = [](std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) throw std::logic_error("BsdfTally: adding tallies of other shapes or moments");
    for (std::size_t k = 0; k < a.size(); ++k) a[k] += b[k];
  };
  for_each_moment([&](const char*, auto sum, auto second) {
    add(this->*sum, o.*sum);
    add(this->*second, o.*second);
  });
  both2 += o.both2;
  add_fields(*this, o);
  return *this;
}

namespace {
// Adds one replicate's first-moment sums, read at `at(i)` for element i of albedo (0), pix (1)
// and plane (2) of `rep_shape`, to t's sums and their replicate spread: Welford's update of
// the sum of squared deviations of the replicate means x = S / n (every replicate has the same
// n paths), stable where the spread is far below the mean. An element that is 0 in the
// replicate and in the sum so far is left as it is: the update would add 0 * 0 to its
// spread (most pixels of a replicate of a few hundred paths are empty).
template <class At>
void add_replicate_sums(BsdfTally& t, std::uint64_t paths, At&& at) {
  const double n = static_cast<double>(paths), k = t.replicates;
  auto welford = [&](double& sum, double& m2, double S) {
    const double x = S / n;
    const double old_mean = k > 0 ? sum / (k * n) : x;
    sum += S;
    m2 += (x - old_mean) * (x - sum / ((k + 1) * n));
  };
  const int K = t.orders;
  const double rt = at(0, t.a_index(0, K)) + at(0, t.a_index(1, K));
  double rt_sum = t.albedo[t.a_index(0, K)] + t.albedo[t.a_index(1, K)];
  welford(rt_sum, t.both2, rt);
  int which = 0;
  BsdfTally::for_each_moment([&](const char*, auto sum, auto second) {
    std::vector<double>& a = t.*sum;
    std::vector<double>& a2 = t.*second;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double S = at(which, i);
      if (S == 0.0 && a[i] == 0.0) continue;
      welford(a[i], a2[i], S);
    }
    ++which;
  });
}
}  // namespace

void BsdfTally::add_replicate(const BsdfTally& rep) {
  if (albedo.empty()) *this = BsdfTally(rep.orders, rep.pixels, rep.plane_bins);
  const std::vector<double>* sums[3] = {&rep.albedo, &rep.pix, &rep.plane};
  add_replicate_sums(*this, rep.paths, [&](int which, std::size_t i) { return (*sums[which])[i]; });
  add_fields(*this, rep);
  ++replicates;
}

void BsdfTally::add_replicate(const SpectralTally& rep, int l) {
  if (albedo.empty()) *this = BsdfTally(rep.orders, rep.pixels, rep.plane_bins);
  const std::vector<double>* sums[3] = {&rep.albedo, &rep.pix, &rep.plane};
  const std::size_t L = static_cast<std::size_t>(rep.wavelengths);
  add_replicate_sums(*this, rep.paths, [&](int which, std::size_t i) { return (*sums[which])[i * L + l]; });
  BsdfTally counts;  // the path counts, shared by every wavelength
  rep.put_path_counts(counts);
  add_fields(*this, counts);
  ++replicates;
}

Estimate BsdfTally::estimate(double sum, double sum2, double scale) const {
  if (replicates == 0) return tally_estimate(sum, sum2, paths, scale);
  // sum2: squared deviations of the R replicate means; error sqrt(var / R)
  // (measure/replicates.hpp).
  Estimate e;
  e.n = paths;
  if (paths == 0) return e;
  e.mean = sum / static_cast<double>(paths) * scale;
  if (replicates < 2) return e;
  e.stderr_ = std::sqrt(std::max(0.0, sum2) / (replicates - 1.0) / replicates) * scale;
  // Where every replicate agrees to the last bits (a deterministic tally, e.g. one Fresnel
  // factor per path on a V-groove), the error left is the rounding of the sums, which the
  // replicates share: its bound paths * eps * |mean|.
  e.stderr_ = std::max(e.stderr_, static_cast<double>(paths) * 1.1102230246251565e-16 * std::abs(e.mean));
  return e;
}

Estimate tally_estimate(double sum, double sum2, std::uint64_t n, double scale) {
  Estimate e;
  e.n = n;
  if (n == 0) return e;
  const double m = sum / static_cast<double>(n);
  e.mean = m * scale;
  if (n > 1) {
    const double var = std::max(0.0, sum2 / static_cast<double>(n) - m * m);
    e.stderr_ = std::sqrt(var / static_cast<double>(n - 1)) * scale;
  }
  return e;
}

Estimate BsdfResult::albedo(int s, int k, int lambda) const {
  const BsdfTally& t = tally(lambda);
  const auto i = t.a_index(s, k);
  return t.estimate(t.albedo[i], t.albedo2[i]);
}
Estimate BsdfResult::f_pixel(int s, int k, int px, int lambda) const {
  const BsdfTally& t = tally(lambda);
  const auto i = t.p_index(s, k, px);
  return t.estimate(t.pix[i], t.pix2[i], 1.0 / map.pixel_cos_integral(px));
}
Estimate BsdfResult::f_plane(int s, int k, int b, int lambda) const {
  const BsdfTally& t = tally(lambda);
  const auto i = t.b_index(s, k, b);
  return t.estimate(t.plane[i], t.plane2[i], 1.0 / plane.cos_integral(b));
}
// The model's tallies: per walk (replicates == 0), or replicates of walks (measure/smith_walk_budget.hpp).
Estimate BsdfResult::model_albedo(int s, int k) const {
  if (!smith_walk) return {};
  const auto i = smith_walk->a_index(s, k);
  return smith_walk->estimate(smith_walk->albedo[i], smith_walk->albedo2[i]);
}
Estimate BsdfResult::model_f_plane(int s, int k, int b) const {
  if (!smith_walk) return {};
  const auto i = smith_walk->b_index(s, k, b);
  return smith_walk->estimate(smith_walk->plane[i], smith_walk->plane2[i], 1.0 / plane.cos_integral(b));
}

std::string order_key(int k, int orders) {
  if (k == orders) return "total";
  if (k == orders - 1) return "order_" + std::to_string(orders) + "plus";
  return "order_" + std::to_string(k + 1);
}

// ---------------------------------------------------------------------------------------------
// The random walk on the explicit surface
// ---------------------------------------------------------------------------------------------

namespace {

std::uint64_t direction_stream(std::uint64_t base, double theta, double phi) {
  // phi may be negative (tables over -180..180 deg): through a signed integer, which wraps
  // modulo 2^64 as a stream key should (a negative double cast to unsigned is undefined).
  return base + static_cast<std::uint64_t>(static_cast<std::int64_t>(theta * 1e6)) * 7919 +
         static_cast<std::uint64_t>(static_cast<std::int64_t>(phi * 1e6));
}

// The sizes of a unit's tallies: orders, pixels, in-plane bins, wavelengths (1: one tally); first_moments:
// BsdfTally::first_moments (replicates that only enter add_replicate).
struct TallyShape {
  int K, npix, nplane, wavelengths = 1;
  bool first_moments = false;
};
template <class T>
T make_tally(const TallyShape& s) {
  return T(s.K, s.npix, s.nplane);
}
template <>
BsdfTally make_tally<BsdfTally>(const TallyShape& s) {
  return s.first_moments ? BsdfTally::first_moments(s.K, s.npix, s.nplane) : BsdfTally(s.K, s.npix, s.nplane);
}
template <>
SpectralTally make_tally<SpectralTally>(const TallyShape& s) {
  return SpectralTally(s.wavelengths, s.K, s.npix, s.nplane);
}
// The passes of a run's units (walk_passes.hpp).
UnitPasses path_passes(const TallyShape& shape) {
  // A spectral unit holds first moments only, of every wavelength.
  const double bytes = shape.wavelengths > 1 ? 0.5 * walk_tally_bytes(shape.K, shape.npix, shape.nplane) * shape.wavelengths
                                             : walk_tally_bytes(shape.K, shape.npix, shape.nplane);
  // First moments (the Smith walk's replicates, one short unit each): half the bytes, and a pass takes every
  // unit that fits, so that the threads wait for the slowest unit once per run rather than once per few units.
  if (shape.first_moments) return {~std::uint64_t(0), std::max<std::uint64_t>(1, static_cast<std::uint64_t>(2.0 * kPassBytes / bytes))};
  return walk_passes(bytes);
}

// The units of a run of n i.i.d. paths (the Smith walk model): one replicate of n paths.
std::uint64_t path_batches(std::uint64_t n) { return path_plan(1, n).groups(); }

// body(i, tally) for i in [0, n): the units' tallies added in order to a zero tally (progress
// after each pass, from progress0 over progress_span). With `parts` (measure/shards.hpp), only
// the units in `share` are run and each unit's tally is stored in (*parts)[unit] for the caller
// to add in unit order (the same sums, same order).
template <class Body>
BsdfTally run_paths(std::uint64_t n, int K, int npix, int nplane,
                    const std::function<void(double)>& progress, double progress0, double progress_span,
                    Body&& body, std::vector<BsdfTally>* parts = nullptr, UnitRange share = {0, ~std::uint64_t(0)}) {
  const TallyShape shape{K, npix, nplane};
  BsdfTally total(K, npix, nplane);
  run_units<BsdfTally>(
      path_plan(1, n), [&] { return BsdfTally(K, npix, nplane); },
      [&](int, std::uint64_t i, BsdfTally& t) { body(i, t); },
      [&](int, std::uint64_t u, BsdfTally&& part) {
        if (parts) (*parts)[u] = std::move(part);
        else total += part;
      },
      share, path_passes(shape),
      progress ? std::function<void(double)>([&](double f) { progress(progress0 + progress_span * f); }) : nullptr);
  return total;
}

// Replicate tallies handed to `deliver` in replicate order: at once (one process), or, with a
// split, kept as rows of their declared fields (FieldRows, measure/shards.hpp) until exchange()
// brings the other processes' rows, and then all delivered in order, as in one process.
template <class T>
class ReplicatesInOrder {
 public:
  using Deliver = std::function<void(int, const T&)>;
  ReplicatesInOrder(const char* kind, TallySplit* split, UnitRange reps, int replicates, const T& shape,
                    Deliver deliver)
      : split_(split), deliver_(std::move(deliver)) {
    if (!split) return;
    rows_.emplace(kind, static_cast<std::uint64_t>(replicates), reps, shape);
    scratch_ = shape;
  }
  void add(int q, const T& rep) {
    if (rows_) rows_->put(static_cast<std::uint64_t>(q), rep);
    else deliver_(q, rep);
  }
  // After this process's replicates (a split): every replicate, in order.
  void exchange() {
    if (!rows_) return;
    rows_->exchange(*split_);
    for (std::uint64_t q = 0; q < rows_->units(); ++q) {
      rows_->get(q, scratch_);
      deliver_(static_cast<int>(q), scratch_);
    }
  }

 private:
  TallySplit* split_;
  Deliver deliver_;
  std::optional<FieldRows<T>> rows_;
  T scratch_;
};

// Where the walk's Mueller unit sums go (polarized runs): into the run's PolarizedSums unit by
// unit (one process); with a split, summed per replicate (from zero, in unit order) and kept
// until every process's replicates are in (ReplicatesInOrder). A replicate's sum in
// PolarizedSums starts at zero and 0 + S is S: the same sums bit for bit.
class ReplicateMuellerSums {
 public:
  ReplicateMuellerSums(PolarizedSums& sums, TallySplit* split, UnitRange reps, int replicates)
      : sums_(sums), split_(split != nullptr),
        replicates_("bsdf_mueller", split, reps, replicates, sums.make_unit(),
                    [&sums](int q, const MuellerUnit& u) { sums.add_unit(q, u); }) {}
  MuellerUnit make_unit() const { return sums_.make_unit(); }
  // Unit g of the `groups` units of replicate q, in unit order.
  void add_unit(int q, std::uint64_t g, std::uint64_t groups, const MuellerUnit& unit) {
    if (!split_) return sums_.add_unit(q, unit);
    if (g == 0) replicate_ = sums_.make_unit();
    replicate_ += unit;
    if (g + 1 == groups) replicates_.add(q, replicate_);
  }
  void exchange() { replicates_.exchange(); }

 private:
  PolarizedSums& sums_;
  bool split_;
  ReplicatesInOrder<MuellerUnit> replicates_;
  MuellerUnit replicate_;  // the replicate being summed (a split)
};

// A unit's tallies: the path sums (Unit) and, in a polarized run, the Mueller sums of the same
// paths (empty otherwise).
template <class Unit>
struct WalkUnit {
  Unit sums;
  MuellerUnit mueller;
  WalkUnit& operator+=(const WalkUnit& o) {
    sums += o.sums;
    mueller += o.mueller;
    return *this;
  }
};

// The walks of the replicates in `reps`, body(q, i, sums, mueller) for path i of replicate q:
// each replicate's tally (Rep) is its units' tallies (Unit: BsdfTally, SpectralTally, or
// ExitCounts for paths of weight 1) added in order, and done(q, tally) receives the replicates
// in order, on the calling thread; with `polarized`, the units' Mueller sums go there in the
// same order. Progress after each pass, over progress_span.
template <class Unit, class Rep, class Body, class Done>
void run_replicate_paths(UnitRange reps, int replicates, std::uint64_t n, const TallyShape& shape,
                         const std::function<void(double)>& progress, double progress_span, Body&& body,
                         Done&& done, ReplicateMuellerSums* polarized = nullptr) {
  const UnitPlan plan = path_plan(replicates, n);
  std::optional<Rep> rep;  // the replicate being summed
  run_units<WalkUnit<Unit>>(
      plan,
      [&] { return WalkUnit<Unit>{make_tally<Unit>(shape), polarized ? polarized->make_unit() : MuellerUnit()}; },
      [&](int q, std::uint64_t i, WalkUnit<Unit>& u) { body(q, i, u.sums, u.mueller); },
      [&](int q, std::uint64_t g, WalkUnit<Unit>&& part) {
        if constexpr (std::is_same<Unit, Rep>::value) {
          // x, as 0 + x: a tally's sums start at +0 and never hold -0 (+0 + -0 is +0), uncopied
          if (g == 0) rep.emplace(std::move(part.sums));
          else *rep += part.sums;
        } else {
          if (g == 0) rep.emplace(make_tally<Rep>(shape));
          *rep += part.sums;
        }
        if (polarized) polarized->add_unit(q, g, plan.groups(), part.mueller);
        if (g + 1 == plan.groups()) done(q, std::move(*rep));
      },
      plan.units_of(reps), path_passes(shape),
      progress ? std::function<void(double)>([&](double f) { progress(progress_span * f); }) : nullptr);
}

// A spectral run: a conductor index per wavelength, increasing wavelengths, the first index the
// material's; periodic tiles and finite objects (V-cavity ensembles: one index).
void check_spectral_options(const BsdfOptions& o, const Microsurface& s) {
  if (o.spectral.empty() && o.wavelengths_nm.empty()) return;
  if (o.spectral.size() != o.wavelengths_nm.size())
    throw std::invalid_argument("BsdfOptions: one spectral index per wavelength");
  if (o.spectral.size() > static_cast<std::size_t>(kMaxWavelengths))
    throw ParameterError("{wavelengths}: at most " + std::to_string(kMaxWavelengths) + " wavelengths");
  for (std::size_t l = 0; l < o.spectral.size(); ++l) {
    if (o.spectral[l].kind != models::MaterialKind::Conductor)
      throw std::invalid_argument("BsdfOptions: spectral indices are conductors'");
    if (l > 0 && !(o.wavelengths_nm[l] > o.wavelengths_nm[l - 1]))
      throw ParameterError("{wavelengths} must be increasing");
  }
  if (!(o.material.kind == models::MaterialKind::Conductor && o.material.eta == o.spectral[0].eta &&
        o.material.k == o.spectral[0].k))
    throw std::invalid_argument("BsdfOptions: the material must be the first wavelength's conductor");
  if (is_vcavity(s)) throw ParameterError("{wavelengths}: V-cavity ensembles are measured at one index");
}

// The Smith walks with expected escapes, in replicates of walks driven by shifted Sobol points
// (measure/smith_walk_budget.hpp): a pilot of kWalkPilotPerReplicate walks per replicate, then runs that add
// the next walks of every replicate's sequence until the pooled errors meet the target. Every process of a split
// computes all of them (the same result as one process).
BsdfTally smith_walks_to_error(const models::SmithRandomWalk& walk, BsdfResult& r, std::uint64_t mstream,
                               const std::function<void(double)>& progress, double share) {
  const BsdfOptions& o = r.options;
  const int K = o.orders, npix = r.map.size(), nplane = r.plane.size();
  const int R = std::max(1, o.replicates);
  const std::uint64_t cap = std::max<std::uint64_t>(1, o.model_walks * kWalkCapFactor / static_cast<std::uint64_t>(R));
  const WalkWindow window = walk_window(walk, r.wi, K, o.seed, mstream);
  // The replicates only enter add_replicate: first moments (BsdfTally::first_moments).
  const TallyShape shape{K, npix, nplane, 1, true};
  // Walks first .. first + m - 1 of each replicate of `reps` (the next points of its sequence); the run's
  // replicates are added to the pooled ones side by side once all are in.
  auto run = [&](std::vector<BsdfTally>& reps, std::uint64_t first, std::uint64_t m, double p0, double span) {
    std::vector<WalkNet> nets(R);
    std::vector<BsdfTally> fresh(R);
    tbb::parallel_for(0, R, [&](int q) { nets[q] = walk_net(o.seed, ReplicatePlan::stream(mstream, q), first, m); });
    run_replicate_paths<BsdfTally, BsdfTally>(
        UnitRange{0, static_cast<std::uint64_t>(R)}, R, m, shape, progress ? std::function<void(double)>([&](double f) { progress(p0 + span * f); }) : nullptr, 1.0,
        [&](int q, std::uint64_t j, BsdfTally& acc, MuellerUnit&) {
          smith_walk_expected_path(walk, r.wi, o.seed, ReplicatePlan::stream(mstream, q), first + j, nets[q], r, acc, window);
        },
        [&](int q, BsdfTally&& rep) { fresh[q] = std::move(rep); });
    tbb::parallel_for(0, R, [&](int q) {
      if (reps[q].paths == 0) reps[q] = std::move(fresh[q]);
      else reps[q] += fresh[q];
    });
  };
  std::vector<BsdfTally> reps(R);
  std::uint64_t kept = std::min(kWalkPilotPerReplicate, cap);  // walks per replicate in reps
  run(reps, 0, kept, share, 0.1 * (1.0 - share));
  BsdfTally albedos = replicate_albedos(reps);
  for (int pass = 1;; ++pass) {
    const bool met = smith_walk_target_met(albedos, r, o.model_error_fraction);
    r.model_budget = smith_walk_budget(albedos, r, o.model_error_fraction, cap, pass == 1 ? kWalkPilotMargin : kWalkRerunMargin);
    // a pilot that misses the target by less than its margin is topped up as a pooled run would be
    if (!met && pass == 1 && r.model_budget.walks / static_cast<std::uint64_t>(R) <= kept)
      r.model_budget = smith_walk_budget(albedos, r, o.model_error_fraction, cap, kWalkRerunMargin);
    const std::uint64_t need = std::min(cap, r.model_budget.walks / static_cast<std::uint64_t>(R));
    if (pass > kWalkPasses || need <= kept || met) break;
    run(reps, kept, need - kept, share + (0.1 + 0.9 * (pass - 1) / kWalkPasses) * (1.0 - share), 0.9 / kWalkPasses * (1.0 - share));
    kept = need;
    albedos = replicate_albedos(reps);
  }
  BsdfTally t(K, npix, nplane);
  for (const BsdfTally& rep : reps) t.add_replicate(rep);
  r.model_budget.walks = t.paths;
  return t;
}

void check_polarized_options(const BsdfOptions& o, const Microsurface& s) {
  if (!o.polarized) return;
  if (is_vcavity(s)) throw ParameterError("{polarized}: V-cavity ensembles are not walked with Mueller matrices");
}

void check_bsdf_options(const BsdfOptions& o, const Microsurface& s) {
  if (!(o.theta_i >= 0.0 && o.theta_i < 0.5 * kPi))
    throw ParameterError("{theta_i} must be in [0, 90) degrees");
  if (!std::isfinite(o.phi_i)) throw ParameterError("{phi_i} must be finite");
  if (o.rays == 0) throw ParameterError("{rays} must be positive");
  if (o.orders < 1 || o.orders > 64) throw ParameterError("{orders} must be in [1, 64]");
  if (o.resolution < 1 || o.resolution > 4096) throw ParameterError("{resolution} must be in [1, 4096]");
  check_spectral_options(o, s);
  check_polarized_options(o, s);
}

// The result's options, incidence and bins, before any walk.
BsdfResult start_result(const BsdfOptions& o, const Microsurface& s) {
  BsdfResult r;
  r.options = o;
  r.options.progress = nullptr;
  r.wi = direction_from_angles(o.theta_i, o.phi_i);
  r.map = HemisphereMap(o.resolution);
  r.plane = InPlaneBins(o.phi_i, o.resolution);
  if (o.models) r.nominal = s.nominal;  // no nominal NDF: no microfacet model beside
  return r;
}

// What every path of the explicit surface shares, and one path's walk.
struct SurfaceWalk {
  const Tracer& tracer;
  const BsdfOptions& o;
  Vec3 wi;
  ReplicatePlan plan;
  // Periodic tile: the tile at the top of the slab. Finite object: a window perpendicular to l
  // covering its projection; each ray carries W_perp / (A cos theta_i), so that the tallies are
  // per unit of the flux falling on the macrosurface ([GeomBSDF24, eq. 4a] with the declared area
  // A) and rays that miss the object add nothing. A measured region (a window inside its guard
  // band): rays cover the region's reach and those whose first hit is outside it are misses
  // (measure/bsdf_walk.cpp), weighted like a finite object's.
  bool finite;
  RayWindow window;
  double ray_weight;
  std::uint64_t stream;

  SurfaceWalk(const Tracer& t, const BsdfOptions& opt, const Vec3& l, std::uint64_t s)
      : tracer(t), o(opt), wi(l), plan(opt.rays, opt.replicates), finite(t.surface().macro().finite_object()),
        window(make_ray_window(t, l)),
        ray_weight(finite || t.surface().macro().region
                       ? window.area_perp / (t.surface().macro().area * l.z())
                       : 1.0),
        stream(s) {}

  // Path i of replicate q into a unit's tally t (its counts); the facets kept when `facets`.
  template <class T>
  WalkEnd walk(int q, std::uint64_t i, T& t, const SpectralWeights* sw, std::vector<WalkFacet>* facets) const {
    CounterRng rng(o.seed, ReplicatePlan::stream(stream, q), i);
    ++t.paths;
    const Vec2 ab = plan.strata.point(i, rng);
    return walk_bsdf_path(tracer, window.origin0 + ab.x() * window.e1 + ab.y() * window.e2, -wi, o.material, rng,
                          o.max_events, finite, t.counters, t.events, sw, facets);
  }
};

// The facets of the path being walked on this thread (polarized runs).
std::vector<WalkFacet>& walk_facets() {
  thread_local std::vector<WalkFacet> facets;
  return facets;
}

// The facets of a polarized path, then its Mueller matrices (nothing for an unpolarized run).
void add_polarized_path(PolarizedSums* polarized, const WalkEnd& e, MuellerUnit& m) {
  if (polarized) polarized->add_path(e, walk_facets(), m);
}
std::vector<WalkFacet>* polarized_facets(PolarizedSums* polarized) {
  return polarized ? &walk_facets() : nullptr;
}

// A finished replicate into the run's tally: with its spread, or its first moments alone for a
// table-only run (measure/table_run_sums.hpp).
void add_run_replicate(BsdfTally& into, const BsdfTally& rep, bool table_sums_only) {
  if (table_sums_only) add_replicate_first_moments(into, rep);
  else into.add_replicate(rep);
}

// A spectral run: one walk per path, a weight per wavelength (bsdf_walk.hpp); each wavelength's
// tallies receive exactly what a run with that wavelength's index alone would. With a split the
// replicates enter in order once every process's have arrived (ReplicatesInOrder).
void walk_spectral_paths(const SurfaceWalk& w, BsdfResult& r, PolarizedSums* polarized, ReplicateMuellerSums* msums,
                         UnitRange reps, const std::function<void(double)>& progress, double share) {
  const BsdfOptions& o = w.o;
  const int L = static_cast<int>(o.spectral.size());
  const TallyShape shape{o.orders, r.map.size(), r.plane.size(), L};
  r.spectral.assign(L, BsdfTally(o.orders, r.map.size(), r.plane.size()));
  ReplicatesInOrder<SpectralTally> spectral_reps(
      "bsdf_spectral", o.split, reps, w.plan.replicates, make_tally<SpectralTally>(shape),
      [&](int, const SpectralTally& rep) {
        for (int l = 0; l < L; ++l)
          if (o.table_sums_only) add_replicate_first_moments(r.spectral[l], rep, l);
          else r.spectral[l].add_replicate(rep, l);
      });
  run_replicate_paths<SpectralTally, SpectralTally>(
      reps, w.plan.replicates, w.plan.per_replicate(), shape, progress, share,
      [&](int q, std::uint64_t i, SpectralTally& t, MuellerUnit& m) {
        double weights[kMaxWavelengths];
        std::fill(weights, weights + L, 1.0);
        const SpectralWeights sw{o.spectral.data(), L, weights};
        const WalkEnd e = w.walk(q, i, t, &sw, polarized_facets(polarized));
        record_walk_end(t, e, weights, w.ray_weight, r.map, r.plane);
        add_polarized_path(polarized, e, m);
      },
      [&](int q, SpectralTally&& rep) {
        spectral_reps.add(q, rep);
        rep = SpectralTally();  // the finished replicate's memory back (L tallies wide)
      },
      msums);
  spectral_reps.exchange();
  r.measured = r.spectral[0];
}

// The explicit surface's paths, replicates one after the other, each a stratified pass of its
// own stream; their sums and spread give the calibrated errors (measure/replicates.hpp). A
// polarized run keeps every path's facets and adds its Mueller matrices to `polarized`.
void walk_surface(const SurfaceWalk& w, BsdfResult& r, PolarizedSums* polarized,
                  const std::function<void(double)>& progress, double share) {
  using models::MaterialKind;
  const BsdfOptions& o = w.o;
  const int K = o.orders, npix = r.map.size(), nplane = r.plane.size();
  const TallyShape shape{K, npix, nplane, 1};
  r.measured = BsdfTally(K, npix, nplane);
  const UnitRange reps = share_of(o.split, static_cast<std::uint64_t>(w.plan.replicates));
  // A polarized run's Mueller sums enter in replicate order, with a split too.
  std::optional<ReplicateMuellerSums> mueller_sums;
  if (polarized) mueller_sums.emplace(*polarized, o.split, reps, w.plan.replicates);
  ReplicateMuellerSums* const msums = mueller_sums ? &*mueller_sums : nullptr;
  if (!o.spectral.empty()) {
    walk_spectral_paths(w, r, polarized, msums, reps, progress, share);
    if (msums) msums->exchange();
    return;
  }
  // With a split, the replicates of this process are kept until the others' arrive; the
  // replicates then enter add_replicate in order, as in one process.
  std::vector<BsdfTally> kept(o.split ? w.plan.replicates : 0, BsdfTally(K, npix, nplane));
  auto keep = [&](int q, BsdfTally&& rep) {
    if (o.split) kept[q] = std::move(rep);
    else add_run_replicate(r.measured, rep, o.table_sums_only);
  };
  // Every exit of weight exactly 1 (mirror, dielectric; rays of weight 1): integer counts
  // (measure/exit_counts.hpp), the same tallies bit for bit. A unit counts in 32 bits.
  const bool unit_weight = w.ray_weight == 1.0 &&
                           (o.material.kind == MaterialKind::Mirror || o.material.kind == MaterialKind::Dielectric) &&
                           w.plan.per_replicate() < (std::uint64_t(1) << 32);
  if (unit_weight) {
    run_replicate_paths<ExitCounts<std::uint32_t>, ExitCounts<std::uint64_t>>(
        reps, w.plan.replicates, w.plan.per_replicate(), shape, progress, share,
        [&](int q, std::uint64_t i, ExitCounts<std::uint32_t>& t, MuellerUnit& m) {
          const WalkEnd e = w.walk(q, i, t, nullptr, polarized_facets(polarized));
          record_walk_end(t, e, r.map, r.plane);
          add_polarized_path(polarized, e, m);
        },
        [&](int q, ExitCounts<std::uint64_t>&& rep) { keep(q, rep.tally()); }, msums);
  } else {
    run_replicate_paths<BsdfTally, BsdfTally>(
        reps, w.plan.replicates, w.plan.per_replicate(), shape, progress, share,
        [&](int q, std::uint64_t i, BsdfTally& t, MuellerUnit& m) {
          const WalkEnd e = w.walk(q, i, t, nullptr, polarized_facets(polarized));
          record_walk_end(t, e, w.ray_weight, r.map, r.plane);
          add_polarized_path(polarized, e, m);
        },
        keep, msums);
  }
  if (o.split) {
    exchange_paths(*o.split, "bsdf", reps, false, kept);
    for (const BsdfTally& rep : kept) add_run_replicate(r.measured, rep, o.table_sums_only);
  }
  if (msums) msums->exchange();
}

// The explicit surface's tallies (V-cavity ensembles: every groove traced on its own as an
// infinite periodic groove), and the polarized sums of the same paths.
void measure_surface(const Tracer& tracer, BsdfResult& r, std::uint64_t stream,
                     const std::function<void(double)>& progress, double share) {
  const BsdfOptions& o = r.options;
  const Microsurface& s = tracer.surface();
  if (is_vcavity(s)) {
    r.measured = trace_vcavity_bsdf(s, o, r.wi, r.map, r.plane, stream);
    if (progress) progress(share);
    return;
  }
  const SurfaceWalk w(tracer, o, r.wi, stream);
  std::optional<PolarizedSums> polarized;
  if (o.polarized)
    polarized.emplace(PolarizedSumsSetup{r.wi, w.ray_weight, w.plan.replicates, o.orders, o.material, o.spectral,
                                         o.phi_i, o.resolution, o.table_sums_only});
  walk_surface(w, r, polarized ? &*polarized : nullptr, progress, share);
  if (polarized) r.polarization = polarized->finish();
}

// The Smith random-walk model of the nominal NDF beside the measurement (same seed, own stream).
void measure_smith_model(BsdfResult& r, const std::function<void(double)>& progress, double share) {
  using namespace microsim::models;
  const BsdfOptions& o = r.options;
  const int K = o.orders, npix = r.map.size(), nplane = r.plane.size();
  const Vec3 wi = r.wi;
  const SmithRandomWalk walk(*r.nominal, o.material, HeightDistribution::Uniform, o.max_events);
  const std::uint64_t mstream = direction_stream(0x5A17000000ull, o.theta_i, o.phi_i);
  if (o.model_error_fraction > 0.0) {
    r.smith_walk = smith_walks_to_error(walk.with_fast_slope_sampler(), r, mstream, progress, share);
    return;
  }
  struct Rng {
    CounterRng c;
    double uniform() { return c.uniform(); }
  };
  auto model_path = [&](std::uint64_t i, BsdfTally& t) {
    Rng rng{CounterRng(o.seed, mstream, i)};
    ++t.paths;
    const WalkExit e = walk.walk(wi, rng);
    t.events += static_cast<std::uint64_t>(e.order);
    if (e.lost) {
      ++t.unterminated;
      return;
    }
    t.add_exit(e.reflected ? 0 : 1, e.order, e.weight, r.map.pixel_of(e.direction), r.plane.bin_of(e.direction));
  };
  if (!o.split) {
    r.smith_walk = run_paths(o.model_walks, K, npix, nplane, progress, share, 1.0 - share, model_path);
    return;
  }
  // The model's sequential units shared like replicates, then summed in unit order.
  const std::uint64_t nb = path_batches(o.model_walks);
  const UnitRange mine = o.split->share(nb);
  std::vector<BsdfTally> parts(nb, BsdfTally(K, npix, nplane));
  run_paths(o.model_walks, K, npix, nplane, progress, share, 1.0 - share, model_path, &parts, mine);
  exchange_paths(*o.split, "bsdf_model", mine, true, parts);
  BsdfTally total(K, npix, nplane);
  for (const BsdfTally& p : parts) total += p;
  r.smith_walk = std::move(total);
}

}  // namespace

BsdfResult measure_bsdf(const Tracer& tracer, const BsdfOptions& o) {
  const Microsurface& s = tracer.surface();
  check_bsdf_options(o, s);
  const Stopwatch clock;
  BsdfResult r = start_result(o, s);
  const bool with_model = o.models && s.nominal && o.model_walks > 0;
  const double share = with_model ? 0.8 : 1.0;  // of the progress
  measure_surface(tracer, r, direction_stream(0xB5DF0000ull, o.theta_i, o.phi_i), o.progress, share);
  if (with_model) {
    const Stopwatch model_clock;
    measure_smith_model(r, o.progress, share);
    r.model_timing = model_clock.elapsed();
  }
  r.timing = clock.elapsed();
  return r;
}

}  // namespace microsim
