#include "microsim/measure/ndf_measure.hpp"
#include "microsim/measure/stats.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace microsim {

namespace {
struct Histograms {
  std::vector<double> area;  // [block][bin]
  Histograms& operator+=(const Histograms& o) {
    if (area.empty()) area.assign(o.area.size(), 0.0);
    for (std::size_t k = 0; k < o.area.size(); ++k) area[k] += o.area[k];
    return *this;
  }
};
}  // namespace

NdfResult measure_ndf(const Microsurface& s, const NdfOptions& o) {
  NdfResult r;
  r.bins = DirectionBinning(o.n_theta, o.n_phi, kPi);
  r.sums = facet_sums(s);
  r.macro_area = s.macro().area;
  r.blocks = o.blocks;
  const int nb = o.blocks * o.blocks, nbins = r.bins.size();
  const Macrosurface& macro = s.macro();
  Eigen::AlignedBox3d box = s.bounds();
  // Blocks tile the region a measured patch is sampled in, else the tile or the object's box.
  double x0 = macro.periodic ? -0.5 * macro.size_x : box.min().x();
  double y0 = macro.periodic ? -0.5 * macro.size_y : box.min().y();
  double wx = macro.periodic ? macro.size_x : box.sizes().x();
  double wy = macro.periodic ? macro.size_y : box.sizes().y();
  if (macro.region) {
    x0 = macro.region_x0;
    y0 = macro.region_y0;
    wx = macro.region_x1 - macro.region_x0;
    wy = macro.region_y1 - macro.region_y0;
  }

  const std::size_t n = s.num_facets();
  const std::size_t grain = std::max<std::size_t>(1 << 16, n / 256);
  Histograms h = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, n, grain), Histograms{},
      [&](const tbb::blocked_range<std::size_t>& range, Histograms acc) {
        if (acc.area.empty()) acc.area.assign(static_cast<std::size_t>(nb) * nbins, 0.0);
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          Triangle t = s.facet(k);
          Vec3 c = t.cross();
          double a = 0.5 * c.norm();
          if (a == 0) continue;
          Vec3 centroid = (t.p0 + t.p1 + t.p2) / 3.0;
          int bx = std::clamp(static_cast<int>((centroid.x() - x0) / wx * o.blocks), 0, o.blocks - 1);
          int by = std::clamp(static_cast<int>((centroid.y() - y0) / wy * o.blocks), 0, o.blocks - 1);
          const int bin = r.bins.bin_of(c / (2 * a));
          if (bin < 0) continue;  // non-finite normal: no direction to bin
          acc.area[static_cast<std::size_t>(by * o.blocks + bx) * nbins + bin] += a;
        }
        return acc;
      },
      [](Histograms a, const Histograms& b) { return a += b; });
  if (h.area.empty()) h.area.assign(static_cast<std::size_t>(nb) * nbins, 0.0);

  // Per block: D_b(B) = area_b(B) / ((A / nb) * Omega(B)); D = mean over blocks.
  auto block_stats = [&](auto&& area_of_block, double omega, double& mean, double& se) {
    double sum = 0, sum2 = 0;
    for (int b = 0; b < nb; ++b) {
      double d = area_of_block(b) / (r.macro_area / nb * omega);
      sum += d;
      sum2 += d * d;
    }
    mean = sum / nb;
    double var = nb > 1 ? std::max(0.0, (sum2 - nb * mean * mean) / (nb - 1)) : 0.0;
    se = std::sqrt(var / nb);
  };
  r.d.resize(nbins);
  r.d_stderr.resize(nbins);
  for (int k = 0; k < nbins; ++k)
    block_stats([&](int b) { return h.area[static_cast<std::size_t>(b) * nbins + k]; },
                r.bins.solid_angle(k), r.d[k], r.d_stderr[k]);
  r.ring_d.resize(o.n_theta);
  r.ring_d_stderr.resize(o.n_theta);
  for (int it = 0; it < o.n_theta; ++it)
    block_stats(
        [&](int b) {
          double a = 0;
          for (int ip = 0; ip < o.n_phi; ++ip)
            a += h.area[static_cast<std::size_t>(b) * nbins + r.bins.index(it, ip)];
          return a;
        },
        r.bins.solid_angle_of_ring(it), r.ring_d[it], r.ring_d_stderr[it]);
  return r;
}

Json surface_checks_json(const FacetSums& f, const Microsurface& s) {
  const Macrosurface& m = s.macro();
  Vec3 eq1b = f.sum_area_normal / m.area;
  Json j;
  j["eq_1b_sum_area_normal_over_A"] = {eq1b.x(), eq1b.y(), eq1b.z()};
  j["eq_1b_error"] = (eq1b - m.normal).norm();
  j["eq_1c_sum_area_cos_over_A"] = f.sum_area_cos / m.area;
  j["eq_1c_error"] = std::abs(f.sum_area_cos / m.area - 1.0);
  j["total_area_over_A"] = f.total_area / m.area;
  j["slope_mean_x"] = f.slope_mean_x;
  j["slope_mean_y"] = f.slope_mean_y;
  j["slope_var_x"] = f.slope_var_x;
  j["slope_var_y"] = f.slope_var_y;
  j["slope_cov_xy"] = f.slope_cov_xy;
  // Beckmann and GGX-with-finite-variance both parameterise slope variance as alpha^2/2 per
  // axis for Beckmann [Heitz14, Sec. 3.3]: the moment fit of alpha.
  j["fitted_alpha_x"] = std::sqrt(2 * f.slope_var_x);
  j["fitted_alpha_y"] = std::sqrt(2 * f.slope_var_y);
  if (s.nominal) {
    j["nominal_alpha_x"] = s.nominal->alpha_x;
    j["nominal_alpha_y"] = s.nominal->alpha_y;
  }
  return j;
}

Table ndf_table_spec() {
  Table t;
  t.error = ErrorKind::Blocks;
  const ErrorKind N = ErrorKind::None;
  t.spec.columns = {
      {"theta_lo_deg", Merge::Key, N, "deg", "lower zenith edge of the ring of normal bins"},
      {"theta_hi_deg", Merge::Key, N, "deg", "upper zenith edge of the ring"},
      {"d", Merge::Measured, ErrorKind::Blocks, "1/sr",
       "D averaged over the ring's azimuths: facet area with normal in the bin / (A * solid angle of the bin)"},
      {"d_nominal", Merge::Copy, N, "1/sr", "the nominal NDF's D averaged over the same bins (null without one)"}};
  t.spec.comparisons = {{"d", "d_nominal", ModelKind::Nominal, "z", "", ""}};
  return t;
}

Table ndf_table(const NdfResult& r, const Microsurface& s) {
  Table t = ndf_table_spec();
  for (int it = 0; it < r.bins.n_theta(); ++it) {
    Json row;
    row["theta_lo_deg"] = deg(r.bins.theta_lo(it));
    row["theta_hi_deg"] = deg(r.bins.theta_hi(it));
    row["d"] = r.ring_d[it];
    row["d_stderr"] = r.ring_d_stderr[it];
    if (s.nominal) {
      double sum = 0;
      for (int ip = 0; ip < r.bins.n_phi(); ++ip)
        sum += r.bins.bin_average(r.bins.index(it, ip), [&](const Vec3& m) { return s.nominal->D(m); });
      const double model = sum / r.bins.n_phi();
      row["d_nominal"] = model;
      row["z"] = z_json(r.ring_d[it], model, r.ring_d_stderr[it]);
    } else {
      row["d_nominal"] = nullptr;
    }
    t.rows.push_back(row);
  }
  return t;
}

ExrTable ndf_to_exr(const NdfResult& r, const Microsurface& s) {
  ExrTable t;
  t.width = r.bins.n_phi();
  t.height = r.bins.n_theta();
  t.channel_names = {"D", "D_stderr"};
  t.channels = {std::vector<float>(r.d.begin(), r.d.end()),
                std::vector<float>(r.d_stderr.begin(), r.d_stderr.end())};
  if (s.nominal) {
    std::vector<float> model(r.d.size());
    for (int k = 0; k < r.bins.size(); ++k)
      model[k] = static_cast<float>(r.bins.bin_average(k, [&](const Vec3& m) { return s.nominal->D(m); }));
    t.channel_names.push_back("D_nominal");
    t.channels.push_back(model);
  }
  t.attributes = {{"microsim_table", "ndf"},
                  {"parameterization",
                   "pixel (x, y) = bin phi in [x, x+1) * 360/width deg, theta in [y, y+1) * 180/height "
                   "deg; D per steradian, bin-averaged: sum of facet areas / (A * bin solid angle)"},
                  {"surface", s.description.dump()},
                  {"checks", surface_checks_json(r.sums, s).dump()}};
  return t;
}

}  // namespace microsim
