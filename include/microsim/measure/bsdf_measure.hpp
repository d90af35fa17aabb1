// The full BSDF of an explicit microsurface, per scattering order, by random walks (docs/theory/bsdf.md): light arrives from l; rays are traced along -l from stratified points of the periodic
// tile; at each hit a mirror reflects, a conductor reflects with weight F (complex index,
// [GeomBSDF24, eq. 8]), a dielectric reflects with probability F and otherwise refracts ([GeomBSDF24, eq. 15a]; total internal
// reflection; both sides of the interface). A ray that leaves upward is reflected, one that
// leaves the slab downward (inside a dielectric) is transmitted. Light is unpolarized.
//
// Tallies per side (reflected / transmitted) and scattering order (1, 2, ..., K-1, K+ and total):
//  * albedo: the mean over rays of the weight that leaves in that cell (with its standard error);
//  * the outgoing hemispheres on an equal-area R x R grid (HemisphereMap), f = p / int_B |cos| dw;
//  * in-plane rows: a narrow band around the plane of incidence (InPlaneBins), f likewise.
// The same tallies for the Smith random-walk model (models/smith_random_walk.hpp) of the
// surface's nominal NDF, and the single-scattering models (models/microfacet_bsdf.hpp) averaged
// over the same bins, go beside them.
//
// Random numbers: CounterRng(seed, stream, ray index); tallies are summed per chunk and merged
// by a deterministic reduction: results do not depend on the number of threads.
#pragma once
#include <functional>
#include <optional>
#include <vector>

#include "microsim/io/output.hpp"
#include "microsim/measure/polarized_walk.hpp"
#include "microsim/measure/shards.hpp"
#include "microsim/measure/timing.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/models/smith_random_walk.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

// Equal-area map of a hemisphere onto the square [-1, 1]^2, pixelated R x R:
// square (a, b) -> unit disk by the concentric map of Shirley and Chiu (r = max(|a|, |b|),
// phi = pi/4 b/a on |a| >= |b|, pi/2 - pi/4 a/b otherwise; area ratio pi/4 everywhere), then
// disk -> hemisphere by Lambert's azimuthal equal-area map (|z| = 1 - r^2, the horizontal part
// r sqrt(2 - r^2) (cos phi, sin phi)). Every pixel subtends 2 pi / R^2 sr. Pixel (i, j): column i
// covers a in [-1 + 2i/R, -1 + 2(i+1)/R], row j covers b likewise; x = +a direction is azimuth
// 0 (+x), b the azimuth 90 degrees (+y). The lower hemisphere uses the same map on (x, y, -z).
class HemisphereMap {
 public:
  explicit HemisphereMap(int resolution = 64);
  int resolution() const { return res_; }
  int size() const { return res_ * res_; }
  // Pixel of a direction (its |z| is used): j * R + i. Exactly the pixel of to_square(d), whose
  // azimuth is std::atan2's; decided with azimuth_near (no atan2) where the square coordinate is
  // further than `edge_margin` pixels from a pixel border and the azimuth further than
  // kSectorMargin from a sector border of the concentric map, else by pixel_of_exact.
  int pixel_of(const Vec3& d) const { return pixel_of(d, edge_margin_); }
  int pixel_of(const Vec3& d, double edge_margin) const;
  int pixel_of_exact(const Vec3& d) const;
  // Bounds for pixel_of: |azimuth_near - std::atan2| (see azimuth_near), the azimuth's distance
  // to a sector border, and (edge_margin_) a pixel border's distance in pixels:
  // R/2 (4/pi (kAzimuthError + 2e-15) + 4e-15), R = resolution, times 16.
  static constexpr double kAzimuthError = 1e-13;
  static constexpr double kSectorMargin = 2 * kAzimuthError;
  // Square coordinates (a, b) of a direction and back (z >= 0 returned).
  Vec2 to_square(const Vec3& d) const;
  Vec3 from_square(double a, double b) const;
  double pixel_solid_angle() const { return 2.0 * kPi / (static_cast<double>(res_) * res_); }
  // Exact int_pixel |cos theta| d omega (the integrand is piecewise quadratic in (a, b)).
  double pixel_cos_integral(int pixel) const { return cos_integral_[pixel]; }

 private:
  int res_;
  double edge_margin_;
  std::vector<double> cos_integral_;
};

// atan2(y, x) for finite (x, y) != (0, 0), within HemisphereMap::kAzimuthError of std::atan2
// (which is within 1 ulp of the true angle), on the same branch ((-pi, pi], the sign of y's
// sign bit): atan(t) = atan(c) + atan(u), t = min / max of |x|, |y|, c = round(16 t) / 16,
// u = (t - c) / (1 + c t), |u| <= 1/32, atan(u) by its series to u^9 (remainder below
// |u|^11 / 11 < 3e-18), atan(c) from a table of std::atan; the rounding of about a dozen
// operations adds a few 1e-16. Two divisions, no libm call.
double azimuth_near(double y, double x);

// A narrow band around the plane of incidence, cut into bins of signed polar angle.
// A direction d (either hemisphere; the lower one measured from -n) is written
// d = cos(beta) (sin(psi) s + cos(psi) n') + sin(beta) p, with n' = +-z toward d's side, s the
// horizontal unit vector toward azimuth phi_i + pi (the specular side: psi > 0) and p = n x s.
// Bin b: psi in [-90 + b w, -90 + (b + 1) w] degrees, w = 180 / n_bins, |beta| <= w / 2.
// Exact: int_bin |cos theta| d omega = (delta + sin(delta) cos(delta)) (sin psi1 - sin psi0),
// delta = w / 2 (|cos theta| = cos(beta) cos(psi), d omega = cos(beta) d beta d psi).
class InPlaneBins {
 public:
  InPlaneBins(double phi_i, int n_bins);
  int size() const { return n_; }
  // -1 outside the band. Exactly bin_of_exact(d): a direction clearly outside the band (by more
  // than band_margin in sin(beta), far beyond the rounding of normalising d) is decided without
  // normalising it; the others (inside the band: a few percent of directions) by bin_of_exact.
  int bin_of(const Vec3& d) const { return bin_of(d, kBandMargin); }
  int bin_of(const Vec3& d, double band_margin) const;
  int bin_of_exact(const Vec3& d) const;
  static constexpr double kBandMargin = 1e-12;
  double psi_lo(int b) const { return -0.5 * kPi + b * width_; }
  double psi_hi(int b) const { return -0.5 * kPi + (b + 1) * width_; }
  double psi_center(int b) const { return -0.5 * kPi + (b + 0.5) * width_; }
  double half_width() const { return delta_; }
  double cos_integral(int b) const;
  // Direction at (psi, beta) on the upper (above = true) or lower side.
  Vec3 direction(double psi, double beta, bool above) const;
  // Average of f over the bin weighted by |cos theta| (6 x 6 Gauss-Legendre in (psi, beta)).
  double cos_weighted_average(int b, bool above, const std::function<double(const Vec3&)>& f) const;

 private:
  int n_;
  double width_, delta_;
  double sin_delta_;  // sin(delta_), compared with every direction binned
  Vec3 s_, p_;
};

// Most wavelengths of one spectral run (each adds a set of tallies).
constexpr int kMaxWavelengths = 64;

struct BsdfOptions {
  models::Material material = models::Material::mirror();
  // A spectral conductor: the conductor's index at each wavelength (nm, increasing). Every path
  // is traced once and carries one weight per wavelength (the product of that wavelength's
  // Fresnel reflectances); each wavelength gets its own tallies (BsdfResult::spectral).
  // `material` is then the conductor at the first wavelength (the models beside the
  // measurement and the record's scalar fields). Empty: the single `material`.
  std::vector<double> wavelengths_nm;
  std::vector<models::Material> spectral;
  double theta_i = 0.0, phi_i = 0.0;  // incidence, radians (light direction l)
  int orders = 4;                     // K: orders 1 .. K-1 separately, K and above together
  std::uint64_t rays = 1000000;
  std::uint64_t seed = 1;
  int resolution = 64;  // hemisphere map R (R x R pixels); also the number of in-plane bins
  int max_events = 10000;  // a walk longer than this is counted unterminated (lost)
  // Smith random-walk model: walks of the nominal NDF (0 = none); same seed, own stream.
  std::uint64_t model_walks = 0;
  // > 0: the walks tally expected escapes and their number is chosen from a pilot so that the walk's
  // standard error of every albedo slot is at most this fraction of the measurement's
  // (measure/smith_walk_budget.hpp), at most kWalkCapFactor model_walks; <= 0: exactly model_walks
  // walks with drawn escapes.
  double model_error_fraction = 1.0;
  // false: measure only (no analytic model beside the measurement: no single-scattering
  // integrals, no Smith walk, no V-groove closed forms), for tables where models cost time.
  bool models = true;
  // Independent randomized replicates the explicit surface's rays are split into: standard
  // errors of the replicate means (measure/replicates.hpp).
  int replicates = 32;
  // Mueller matrices along every reflected path, per order and wavelength
  // (measure/polarized_walk.hpp), built from the facets of the walk's own paths. Periodic
  // tiles and finite objects, in one process or split (measure/shards.hpp).
  bool polarized = false;
  // The run enters only a renderer table's azimuthal averages (measure/table_run_sums.hpp): its
  // replicates add their first moments without their spread; no errors for it.
  bool table_sums_only = false;
  // Called from the calling thread with the fraction of work done (progress display).
  std::function<void(double)> progress;
  // Other processes sharing the replicates and the model's batches (measure/shards.hpp);
  // nullptr: all computed here.
  TallySplit* split = nullptr;
};

struct SpectralTally;

// Mergeable sums. Index conventions: side s (0 reflected, 1 transmitted), slot k (0 .. K-1 for
// orders 1 .. K+, K for the total). The first moments are sums over paths of the weight that
// left in the cell. The second moments depend on how the paths were drawn:
//  * replicates == 0 (i.i.d. paths, the Smith walk): sums over paths of the squared weight;
//  * replicates = R >= 1 (R stratified replicates of paths / R paths, the explicit surface):
//    the sums of squared deviations of the R replicate means from their mean (add_replicate).
struct BsdfTally {
  int orders = 4, pixels = 0, plane_bins = 0;
  int replicates = 0;
  std::vector<double> albedo, albedo2;  // [s][k]
  std::vector<double> pix, pix2;        // [s][k][pixel]
  std::vector<double> plane, plane2;    // [s][k][bin]
  double both2 = 0;                     // second moment of reflected + transmitted (total)
  std::uint64_t paths = 0;              // rays (walks) started
  std::uint64_t lost = 0;               // ended without leaving (tracer loss, wrong-side hit)
  std::uint64_t unterminated = 0;       // more than max_events scattering events
  std::uint64_t events = 0;             // scattering events, all paths
  TraceCounters counters;

  // The counts, declared once (tally_fields.hpp): summed, exchanged between processes.
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f("paths", &BsdfTally::paths);
    f("lost", &BsdfTally::lost);
    f("unterminated", &BsdfTally::unterminated);
    f("events", &BsdfTally::events);
    f("counters", &BsdfTally::counters);
  }
  // The weight sums, each with its second moment (per path; between replicates, Welford's sum
  // of squared deviations of the replicate means): f(name, sum, second moment). both2 apart.
  template <class F>
  static constexpr void for_each_moment(F&& f) {
    f("albedo", &BsdfTally::albedo, &BsdfTally::albedo2);
    f("pix", &BsdfTally::pix, &BsdfTally::pix2);
    f("plane", &BsdfTally::plane, &BsdfTally::plane2);
  }

  BsdfTally() = default;
  BsdfTally(int K, int npix, int nplane);
  int slots() const { return orders + 1; }
  std::size_t a_index(int s, int k) const { return static_cast<std::size_t>(s) * slots() + k; }
  std::size_t p_index(int s, int k, int px) const {
    return (static_cast<std::size_t>(s) * slots() + k) * pixels + px;
  }
  std::size_t b_index(int s, int k, int b) const {
    return (static_cast<std::size_t>(s) * slots() + k) * plane_bins + b;
  }
  // A path that left on side s after `order` >= 1 events, with weight w, pixel px (or -1) and
  // in-plane bin b (or -1).
  void add_exit(int s, int order, double w, int px, int b);
  BsdfTally& operator+=(const BsdfTally& o);
  // Adds one replicate's per-path tally (replicates == 0) as replicate number `replicates`.
  void add_replicate(const BsdfTally& rep);
  // The same for wavelength l of a spectral replicate (the counts are the path's, shared).
  void add_replicate(const SpectralTally& rep, int l);
  // Mean per path of the first moment `sum` (times `scale`) with its standard error.
  Estimate estimate(double sum, double sum2, double scale = 1.0) const;
};

// Mean and standard error of the per-path contribution X (0 or the path's weight) times `scale`.
Estimate tally_estimate(double sum, double sum2, std::uint64_t n, double scale = 1.0);

// The number of Smith walks chosen for the error target (measure/smith_walk_budget.hpp).
struct WalkBudget {
  std::uint64_t walks = 0;                     // the walks run (pilot included)
  double target_ratio = 0.0;                   // walk stderr / measured stderr asked for (0: fixed walks)
  int limiting_side = -1, limiting_slot = -1;  // the albedo slot that needed the most walks (-1: none)
};

struct BsdfResult {
  BsdfOptions options;  // as run (progress callback dropped)
  Vec3 wi;              // light direction l
  HemisphereMap map;
  InPlaneBins plane{0.0, 1};
  BsdfTally measured;                // spectral runs: the first wavelength's tallies
  std::vector<BsdfTally> spectral;    // per wavelength of options.wavelengths_nm (empty if none)
  std::optional<BsdfTally> smith_walk;  // the model's tallies (nominal NDF available)
  WalkBudget model_budget;              // how many walks, for which error
  std::optional<models::Ndf> nominal;
  std::optional<PolarizationTally> polarization;  // options.polarized: the reflected Mueller sums
  Timing timing;        // the whole run (the record's `seconds`)
  Timing model_timing;  // the Smith walk model's part of it (`model_seconds`)

  int wavelengths() const { return static_cast<int>(spectral.size()); }
  // The tallies of wavelength index `lambda` (spectral runs), or `measured` for lambda < 0.
  const BsdfTally& tally(int lambda) const { return lambda < 0 ? measured : spectral[lambda]; }
  Estimate albedo(int side, int k, int lambda = -1) const;
  Estimate f_pixel(int side, int k, int px, int lambda = -1) const;
  Estimate f_plane(int side, int k, int b, int lambda = -1) const;
  Estimate model_albedo(int side, int k) const;
  Estimate model_f_plane(int side, int k, int b) const;
};

// Periodic tiles; finite objects (rays over a window covering the projection, tallies per unit
// of the flux on the macrosurface: a convex mirror object's total albedo is its visible area
// ratio); V-cavity ensembles (each groove traced on its own, measure/vcavity_measure.hpp).
// Throws UsageError for theta_i outside [0, 90) and bad counts.
BsdfResult measure_bsdf(const Tracer& tracer, const BsdfOptions& options);

// Key of slot k: "order_1", ..., "order_<K>plus", "total".
std::string order_key(int k, int orders);

// The record's tables and writers: measure/bsdf_record.hpp.

}  // namespace microsim
