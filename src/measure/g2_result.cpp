// The estimates of a G2 result and their standard errors, from its per-replicate counts
// (measure/g2_result.hpp).
#include "microsim/measure/g2_result.hpp"

#include <array>
#include <vector>

#include "microsim/measure/replicates.hpp"

namespace microsim {

models::G2Forms G2Result::smith_numeric() const {
  return models::g2_forms_from_lambda(lambda_o, lambda_i, models::azimuth_difference(o, i));
}

std::array<double, 4> form_values(const models::G2Forms& f) {
  return {f.separable, f.height_correlated, f.direction_correlated, f.height_direction_correlated};
}

namespace {
models::G2Forms from_array(const std::array<double, 4>& a) {
  return {a[0], a[1], a[2], a[3]};
}
}  // namespace

Estimate G2Result::g2() const {
  std::vector<std::uint64_t> x(replicates, 0);
  for (const G2NormalBin& nb : bins)
    for (int q = 0; q < replicates; ++q) x[q] += nb.visible_both_r[q];
  return replicate_mean(x, static_cast<double>(replicates) / samples);
}
Estimate G2Result::g1_o() const {
  std::vector<std::uint64_t> x(replicates, 0);
  for (const G2NormalBin& nb : bins)
    for (int q = 0; q < replicates; ++q) x[q] += nb.visible_o_r[q];
  return replicate_mean(x, static_cast<double>(replicates) / samples);
}
Estimate G2Result::g1_i() const {
  std::vector<std::uint64_t> x(replicates, 0);
  for (const G2NormalBin& nb : bins)
    for (int q = 0; q < replicates; ++q) x[q] += nb.visible_i_r[q];
  return replicate_mean(x, static_cast<double>(replicates) / samples);
}
Estimate G2Result::bin_g2(int b) const { return replicate_ratio(bins[b].visible_both_r, bins[b].samples_r); }
Estimate G2Result::bin_g1_o(int b) const { return replicate_ratio(bins[b].visible_o_r, bins[b].samples_r); }
Estimate G2Result::bin_g1_i(int b) const { return replicate_ratio(bins[b].visible_i_r, bins[b].samples_r); }

namespace {
// A bin's counts: samples, visible from o, from i, from both.
struct BinCounts {
  double n = 0, o = 0, i = 0, both = 0;
};
BinCounts counts_without(const G2NormalBin& nb, int rep) {  // rep < 0: all replicates
  BinCounts c{static_cast<double>(nb.samples), static_cast<double>(nb.visible_o),
              static_cast<double>(nb.visible_i), static_cast<double>(nb.visible_both)};
  if (rep >= 0) {
    c.n -= nb.samples_r[rep];
    c.o -= nb.visible_o_r[rep];
    c.i -= nb.visible_i_r[rep];
    c.both -= nb.visible_both_r[rep];
  }
  return c;
}
// The four forms from the bin's g1_o, g1_i, and g2 minus each.
void forms_and_diff(const BinCounts& c, double phi, std::array<double, 4>& value,
                    std::array<double, 4>& diff) {
  value = form_values(models::g2_forms_from_g1(c.o / c.n, c.i / c.n, phi));
  for (int k = 0; k < 4; ++k) diff[k] = c.both / c.n - value[k];
}
}  // namespace

G2Result::FormsFromG1 G2Result::bin_forms_from_g1(int b) const {
  FormsFromG1 out;
  const G2NormalBin& nb = bins[b];
  if (nb.samples == 0) return out;
  const double phi = models::azimuth_difference(o, i);
  std::array<double, 4> value, diff, v, d;
  forms_and_diff(counts_without(nb, -1), phi, value, diff);
  std::array<std::vector<double>, 4> without;
  for (int q = 0; q < replicates; ++q) {
    const BinCounts c = counts_without(nb, q);
    if (!(c.n > 0)) continue;  // the bin's only samples were in replicate q
    forms_and_diff(c, phi, v, d);
    for (int k = 0; k < 4; ++k) without[k].push_back(d[k]);
  }
  std::array<double, 4> se{};
  for (int k = 0; k < 4; ++k) se[k] = jackknife(diff[k], without[k]).stderr_;
  out.value = from_array(value);
  out.diff = from_array(diff);
  out.diff_stderr = from_array(se);
  return out;
}

G2Result::FormsFromG1 G2Result::forms_from_g1() const {
  const double phi = models::azimuth_difference(o, i);
  // sum_b w_b (value_b, diff_b) over the bins with samples, without replicate `rep` (< 0: none).
  auto average = [&](int rep, std::array<double, 4>& value, std::array<double, 4>& diff) {
    value = {};
    diff = {};
    std::array<double, 4> v, d;
    for (int b = 0; b < binning.size(); ++b) {
      if (bins[b].weight <= 0 || bins[b].samples == 0) continue;
      const BinCounts c = counts_without(bins[b], rep);
      if (!(c.n > 0)) continue;
      forms_and_diff(c, phi, v, d);
      const double w = bins[b].weight / weight;
      for (int k = 0; k < 4; ++k) {
        value[k] += w * v[k];
        diff[k] += w * d[k];
      }
    }
  };
  std::array<double, 4> value, diff, v, d;
  average(-1, value, diff);
  std::array<std::vector<double>, 4> without;
  for (int q = 0; q < replicates; ++q) {
    average(q, v, d);
    for (int k = 0; k < 4; ++k) without[k].push_back(d[k]);
  }
  std::array<double, 4> se{};
  for (int k = 0; k < 4; ++k) se[k] = jackknife(diff[k], without[k]).stderr_;
  FormsFromG1 out;
  out.value = from_array(value);
  out.diff = from_array(diff);
  out.diff_stderr = from_array(se);
  return out;
}

DirectionBinning g2_normal_binning(const G2Options& o) {
  return DirectionBinning(o.normal_theta_bins, o.normal_phi_bins, kPi);
}

}  // namespace microsim
