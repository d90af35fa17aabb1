#include "microsim/measure/polarized_walk.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/replicates.hpp"
#include "microsim/measure/bsdf_options.hpp"
#include "microsim/measure/hemisphere_map.hpp"
#include "microsim/measure/in_plane_bins.hpp"
#include "microsim/tally_fields.hpp"

namespace microsim {

using models::Material;
using models::MaterialKind;
using models::Mueller;

// ---------------------------------------------------------------------------------------------
// One path's matrices

namespace {
// The Fresnel matrix of one event for one material, in the facet's s/p frames.
Mueller facet_mueller(const WalkFacet& f, const Material& mat) {
  if (mat.kind == MaterialKind::Conductor) {
    // models::facet_reflection_mueller with the amplitudes computed once: the same values
    // (fresnel_conductor squares these amplitudes).
    const models::FresnelAmplitudes a = models::fresnel_conductor_amplitudes(f.cos_i, mat.eta, mat.k);
    return models::fresnel_mueller(std::norm(a.rs), std::norm(a.rp), a.rs * std::conj(a.rp));
  }
  if (f.refracted) return models::facet_transmission_mueller(mat, f.cos_i, f.front);
  return models::facet_reflection_mueller(mat, f.cos_i, f.front);
}
}  // namespace

void walk_path_muellers(const Vec3& wi, const std::vector<WalkFacet>& facets, const Vec3& exit,
                        const Material* materials, int count, Mueller* out) {
  // The rotations into each facet's s axis, and the last one into the exit's frame, are the
  // same for every material: computed once.
  thread_local std::vector<Mueller> rotations;
  rotations.resize(facets.size() + 1);
  Vec3 x = models::stokes_frame(wi);
  double probability = 1.0;
  for (std::size_t e = 0; e < facets.size(); ++e) {
    const WalkFacet& f = facets[e];
    const Vec3 d = f.travel.normalized();
    Vec3 s = f.normal.normalized().cross(d);
    const double sn = s.norm();
    s = sn > 1e-12 ? Vec3(s / sn) : x;  // normal incidence: every axis is an s axis
    rotations[e] = models::frame_change(d, x, s);
    x = s;
    probability *= f.probability;
  }
  const Vec3 d_out = exit.normalized();
  rotations[facets.size()] = models::frame_change(d_out, x, models::stokes_frame(d_out));
  for (int l = 0; l < count; ++l) {
    Mueller M = Mueller::Identity();
    for (std::size_t e = 0; e < facets.size(); ++e) M = facet_mueller(facets[e], materials[l]) * (rotations[e] * M);
    M = rotations[facets.size()] * M;
    out[l] = probability == 1.0 ? M : Mueller(M / probability);
  }
}

// ---------------------------------------------------------------------------------------------
// The tally

namespace {
Mueller read_matrix(const double* p, double scale) {
  Mueller M;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) M(i, j) = p[4 * i + j] * scale;
  return M;
}
}  // namespace

Mueller PolarizationTally::mean(int k, int l) const {
  return read_matrix(total.data() + index(k, l), paths ? 1.0 / static_cast<double>(paths) : 0.0);
}

Mueller PolarizationTally::replicate_mean(int q, int k, int l) const {
  const std::size_t per_rep = static_cast<std::size_t>(slots()) * wavelengths * 16;
  const double n = paths ? static_cast<double>(paths) / replicates : 0.0;
  return read_matrix(replicate.data() + q * per_rep + index(k, l), n > 0 ? 1.0 / n : 0.0);
}

Mueller PolarizationTally::stderr_(int k, int l) const {
  Mueller out;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) out(i, j) = statistic(k, l, [i, j](const Mueller& M) { return M(i, j); }).stderr_;
  return out;
}

namespace {
// The per-path mean of the 16 sums at `at`, divided by a bin's cos integral, with the arithmetic
// of BsdfTally::estimate (sum / paths * (1 / cos)), so that a sum equal to the unpolarized one
// gives the same f bit for bit.
Mueller bin_mean(const std::vector<double>& total, std::size_t at, std::uint64_t paths, double cos_integral) {
  Mueller M = Mueller::Zero();
  if (paths == 0) return M;
  for (int i = 0; i < 16; ++i) M(i / 4, i % 4) = total[at + i] / static_cast<double>(paths) * (1.0 / cos_integral);
  return M;
}
// The standard errors of f element by element at each of `blocks` 16-element blocks from the
// replicates' sums [q][block][16]: the spread of the replicates' per-path means.
std::vector<double> bin_stderrs(const std::vector<double>& reps, std::size_t blocks, int replicates,
                                std::uint64_t paths, const std::vector<double>& cos_integral) {
  std::vector<double> out(blocks * 16, 0.0);
  if (paths == 0 || replicates < 2) return out;
  const double n = static_cast<double>(paths) / replicates;
  const std::size_t per_rep = blocks * 16;
  std::vector<double> inv_cos(blocks);  // 1 / c per block, as replicate_mean's callers divide
  for (std::size_t b = 0; b < blocks; ++b) inv_cos[b] = 1.0 / cos_integral[b % cos_integral.size()];
  // Replicate q's per-path mean f of element `at` (a zero sum is a zero mean: no division).
  auto x = [&](int q, std::size_t at) {
    const double v = reps[q * per_rep + at];
    return v == 0.0 ? 0.0 : v / n * inv_cos[at / 16];
  };
  // replicate_mean's arithmetic element by element (the replicates in order), one replicate's
  // row at a time.
  const double R = static_cast<double>(replicates);
  std::vector<double> mean(per_rep, 0.0), ss(per_rep, 0.0);
  for (int q = 0; q < replicates; ++q)
    for (std::size_t at = 0; at < per_rep; ++at) mean[at] += x(q, at);
  for (double& m : mean) m /= R;
  for (int q = 0; q < replicates; ++q)
    for (std::size_t at = 0; at < per_rep; ++at) {
      const double d = x(q, at) - mean[at];
      ss[at] += d * d;
    }
  for (std::size_t at = 0; at < per_rep; ++at) out[at] = std::sqrt(ss[at] / (R - 1) / R);
  return out;
}
Mueller block_at(const std::vector<double>& v, std::size_t at) {
  Mueller M;
  for (int i = 0; i < 16; ++i) M(i / 4, i % 4) = v[at + i];
  return M;
}
}  // namespace

Mueller PolarizationTally::pixel_f(int l, int px) const { return bin_mean(bins_total, pixel_index(l, px), paths, bin_cos[px]); }
Mueller PolarizationTally::pixel_f_stderr(int l, int px) const { return block_at(bins_stderr, pixel_index(l, px)); }
Mueller PolarizationTally::plane_f(int k, int l, int b) const {
  return bin_mean(plane_total, plane_index(k, l, b), paths, plane_cos[b]);
}
Mueller PolarizationTally::plane_f_stderr(int k, int l, int b) const { return block_at(plane_stderr, plane_index(k, l, b)); }

void PolarizationTally::keep_table_sums_only() {
  for (std::vector<double>* v : {&replicate, &map_replicate, &map_total, &bins_stderr, &plane_total, &plane_stderr})
    std::vector<double>().swap(*v);
}

Estimate PolarizationTally::statistic(int k, int l, const std::function<double(const Mueller&)>& g) const {
  Estimate e;
  e.n = paths;
  if (paths == 0) return e;
  e.mean = g(mean(k, l));
  std::vector<double> x(std::max(replicates, 0));
  for (int q = 0; q < replicates; ++q) x[q] = g(replicate_mean(q, k, l));
  e.stderr_ = microsim::replicate_mean(x).stderr_;  // the replicate values' spread
  return e;
}

namespace {
// sum_px |pol(M_px s)| / sum_px s0(M_px s) over a [k][l][pixel][16] block starting at p.
double resolved_dop(const double* p, int pixels, const models::Stokes& s) {
  double pol = 0.0, flux = 0.0;
  for (int px = 0; px < pixels; ++px) {
    const models::Stokes out = read_matrix(p + 16 * static_cast<std::size_t>(px), 1.0) * s;
    pol += out.tail<3>().norm();
    flux += out[0];
  }
  return flux > 0.0 ? pol / flux : 0.0;
}
}  // namespace

Estimate PolarizationTally::resolved_degree_of_polarization(int k, int l, const models::Stokes& s) const {
  Estimate e;
  e.n = paths;
  if (paths == 0 || pixels == 0) return e;
  const std::size_t block = static_cast<std::size_t>(pixels) * 16;
  const std::size_t at = (static_cast<std::size_t>(k) * wavelengths + l) * block;
  e.mean = resolved_dop(map_total.data() + at, pixels, s);
  const std::size_t per_rep = static_cast<std::size_t>(slots()) * wavelengths * block;
  std::vector<double> x(std::max(replicates, 0));
  for (int q = 0; q < replicates; ++q) x[q] = resolved_dop(map_replicate.data() + q * per_rep + at, pixels, s);
  e.stderr_ = microsim::replicate_mean(x).stderr_;
  return e;
}

Estimate coherency_min_eigenvalue(const PolarizationTally& t, int k, int l) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4cd> es(models::coherency_matrix(t.mean(k, l)));
  const Eigen::Vector4cd v = es.eigenvectors().col(0);  // the lowest eigenvalue's
  Estimate e = t.statistic(k, l, [&v](const Mueller& M) {
    return (v.adjoint() * models::coherency_matrix(M) * v)(0, 0).real();
  });
  e.mean = es.eigenvalues()(0);
  return e;
}

std::vector<NamedStokes> polarization_inputs() {
  return {{"unpolarized", models::Stokes(1, 0, 0, 0)}, {"s", models::Stokes(1, 1, 0, 0)},
          {"p", models::Stokes(1, -1, 0, 0)},          {"45", models::Stokes(1, 0, 1, 0)},
          {"circular", models::Stokes(1, 0, 0, 1)}};
}

// ---------------------------------------------------------------------------------------------
// The sums of the walked paths

MuellerUnit& MuellerUnit::operator+=(const MuellerUnit& o) {
  // Field by field (tally_fields.hpp): an empty field takes o's, so that a bins_only unit (its
  // bins alone) and the reduction's identity add as the full sums do.
  add_fields(*this, o);
  return *this;
}

// The maps, the widths of the sums and the per-replicate sums of one run.
struct PolarizedSums::Layout {
  PolarizedSumsSetup su;
  int K, L;
  const Material* materials;
  HemisphereMap map{kPolarizationMapResolution};
  bool per_bin;  // su.resolution > 0: a hemisphere map of all orders, the in-plane bins per slot
  HemisphereMap bin_map;
  InPlaneBins plane;
  std::size_t width, map_width, bins_width, plane_width;
  PolarizationTally t;
  std::vector<double> bins_replicate, plane_replicate;  // [q][...]: the errors of the bins
  int summing = 0;  // su.bins_only: the replicate whose sum bins_replicate holds (its only one)

  explicit Layout(const PolarizedSumsSetup& s)
      : su(s), K(s.orders), L(s.spectral.empty() ? 1 : static_cast<int>(s.spectral.size())),
        materials(s.spectral.empty() ? &su.material : su.spectral.data()), per_bin(s.resolution > 0),
        bin_map(per_bin ? polarized_bin_resolution(s.resolution) : 1), plane(s.phi_i, per_bin ? s.resolution : 1) {
    t.orders = K;
    t.wavelengths = L;
    t.replicates = s.replicates;
    t.pixels = map.size();
    if (per_bin) {
      t.bin_resolution = bin_map.resolution();
      t.bin_pixels = bin_map.size();
      t.plane_bins = plane.size();
      for (int px = 0; px < t.bin_pixels; ++px) t.bin_cos.push_back(bin_map.pixel_cos_integral(px));
      for (int b = 0; b < t.plane_bins; ++b) t.plane_cos.push_back(plane.cos_integral(b));
    }
    width = static_cast<std::size_t>(K + 1) * L * 16;
    map_width = width * t.pixels;
    bins_width = static_cast<std::size_t>(L) * t.bin_pixels * 16;
    plane_width = width * t.plane_bins;
    // Each replicate's sum starts at zero and adds its units in order; a bins_only run keeps the
    // replicate being summed alone and adds it to the total when the next one starts.
    if (su.bins_only) {
      bins_replicate.assign(bins_width, 0.0);
      t.bins_total.assign(bins_width, 0.0);
      return;
    }
    t.replicate.assign(width * s.replicates, 0.0);
    t.map_replicate.assign(map_width * s.replicates, 0.0);
    bins_replicate.assign(bins_width * s.replicates, 0.0);
    plane_replicate.assign(plane_width * s.replicates, 0.0);
  }
};

PolarizedSums::PolarizedSums(const PolarizedSumsSetup& setup) : layout_(std::make_unique<Layout>(setup)) {}
PolarizedSums::~PolarizedSums() = default;

MuellerUnit PolarizedSums::make_unit() const {
  MuellerUnit u;
  if (layout_->su.bins_only) {
    u.bins.assign(layout_->bins_width, 0.0);
    return u;
  }
  u.sums.assign(layout_->width, 0.0);
  u.map.assign(layout_->map_width, 0.0);
  u.bins.assign(layout_->bins_width, 0.0);
  u.plane.assign(layout_->plane_width, 0.0);
  return u;
}

namespace {
// p[a] += w0 * M(a / 4, a % 4) for the 16 elements.
void add_matrix(double* p, double w0, const Mueller& M) {
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) p[4 * a + b] += w0 * M(a, b);
}
}  // namespace

void PolarizedSums::add_path(const WalkEnd& e, const std::vector<WalkFacet>& facets, MuellerUnit& acc) const {
  const Layout& y = *layout_;
  ++acc.paths;
  if (e.kind != WalkEnd::Reflected) return;
  const int K = y.K, L = y.L;
  const double w0 = y.su.ray_weight;
  Mueller M[kMaxWavelengths];
  walk_path_muellers(y.su.wi, facets, e.direction, y.materials, L, M);
  const int k = std::min(e.order, K) - 1;
  // A finite object's ray reflected below the base plane counts in the albedo only.
  const bool above = e.direction.z() > 0.0;
  if (y.per_bin && above) {
    const int bp = y.bin_map.pixel_of(e.direction), b = y.su.bins_only ? -1 : y.plane.bin_of(e.direction);
    for (int l = 0; l < L; ++l) add_matrix(acc.bins.data() + (static_cast<std::size_t>(l) * y.t.bin_pixels + bp) * 16, w0, M[l]);
    if (b >= 0)
      for (int slot : {k, K})
        for (int l = 0; l < L; ++l)
          add_matrix(acc.plane.data() + ((static_cast<std::size_t>(slot) * L + l) * y.t.plane_bins + b) * 16, w0, M[l]);
  }
  if (y.su.bins_only) return;
  const int px = above ? y.map.pixel_of(e.direction) : -1;
  for (int slot : {k, K})
    for (int l = 0; l < L; ++l) {
      const std::size_t at = static_cast<std::size_t>(slot) * L + l;
      add_matrix(acc.sums.data() + at * 16, w0, M[l]);
      if (px >= 0) add_matrix(acc.map.data() + (at * y.t.pixels + px) * 16, w0, M[l]);
    }
}

void PolarizedSums::add_unit(int q, const MuellerUnit& part) {
  Layout& y = *layout_;
  auto add = [](double* to, const std::vector<double>& from) {
    for (std::size_t i = 0; i < from.size(); ++i) to[i] += from[i];
  };
  if (y.su.bins_only) {
    if (q != y.summing) add_summed_replicate(), y.summing = q;
    add(y.bins_replicate.data(), part.bins);
    y.t.paths += part.paths;
    return;
  }
  add(y.t.replicate.data() + y.width * q, part.sums);
  add(y.t.map_replicate.data() + y.map_width * q, part.map);
  add(y.bins_replicate.data() + y.bins_width * q, part.bins);
  add(y.plane_replicate.data() + y.plane_width * q, part.plane);
  y.t.paths += part.paths;
}

void PolarizedSums::add_summed_replicate() {
  Layout& y = *layout_;
  // finish()'s total: the replicates' sums added in order to a zero sum.
  for (std::size_t i = 0; i < y.bins_width; ++i) {
    y.t.bins_total[i] += y.bins_replicate[i];
    y.bins_replicate[i] = 0.0;
  }
}

PolarizationTally PolarizedSums::finish() {
  Layout& y = *layout_;
  PolarizationTally& t = y.t;
  if (y.su.bins_only) {
    add_summed_replicate();
    return std::move(t);
  }
  // The replicates added in order.
  auto total = [&](std::vector<double>& out, const std::vector<double>& reps, std::size_t w) {
    out.assign(w, 0.0);
    for (int q = 0; q < t.replicates; ++q)
      for (std::size_t i = 0; i < w; ++i) out[i] += reps[w * q + i];
  };
  total(t.total, t.replicate, y.width);
  total(t.map_total, t.map_replicate, y.map_width);
  total(t.bins_total, y.bins_replicate, y.bins_width);
  total(t.plane_total, y.plane_replicate, y.plane_width);
  if (y.per_bin) {
    t.bins_stderr = bin_stderrs(y.bins_replicate, y.bins_width / 16, t.replicates, t.paths, t.bin_cos);
    t.plane_stderr = bin_stderrs(y.plane_replicate, y.plane_width / 16, t.replicates, t.paths, t.plane_cos);
  }
  return std::move(t);
}

}  // namespace microsim

namespace microsim {

namespace {
Json matrix_json(const Mueller& M) {
  Json rows = Json::array();
  for (int i = 0; i < 4; ++i) rows.push_back({M(i, 0), M(i, 1), M(i, 2), M(i, 3)});
  return rows;
}
// Slot k's key, as the albedo's (order_key in measure/bsdf_measure.hpp).
std::string slot_key(int k, int orders) {
  if (k == orders) return "total";
  if (k == orders - 1) return "order_" + std::to_string(orders) + "plus";
  return "order_" + std::to_string(k + 1);
}
}  // namespace

Json polarization_json(const PolarizationTally& t, const std::vector<double>& wavelengths_nm) {
  Json j;
  j["frames"] = "in: stokes_frame(l), out: stokes_frame(o) of each path's exit direction";
  j["wavelengths_nm"] = wavelengths_nm;
  j["map_resolution"] = kPolarizationMapResolution;
  Json reflected = Json::object();
  for (int k = 0; k <= t.orders; ++k) {
    Json per_l = Json::array();
    for (int l = 0; l < t.wavelengths; ++l) {
      Json e;
      e["mueller"] = matrix_json(t.mean(k, l));
      e["mueller_stderr"] = matrix_json(t.stderr_(k, l));
      Json dop = Json::object(), dop_se = Json::object();
      for (const NamedStokes& in : polarization_inputs()) {
        const models::Stokes s = in.s;
        const Estimate d = t.statistic(k, l, [s](const Mueller& M) {
          return models::degree_of_polarization(M * s);
        });
        dop[in.name] = d.mean;
        dop_se[in.name] = d.stderr_;
      }
      e["degree_of_polarization"] = dop;
      e["degree_of_polarization_stderr"] = dop_se;
      Json rdop = Json::object(), rdop_se = Json::object();
      for (const NamedStokes& in : polarization_inputs()) {
        const Estimate d = t.resolved_degree_of_polarization(k, l, in.s);
        rdop[in.name] = d.mean;
        rdop_se[in.name] = d.stderr_;
      }
      e["resolved_degree_of_polarization"] = rdop;
      e["resolved_degree_of_polarization_stderr"] = rdop_se;
      const Estimate ev = coherency_min_eigenvalue(t, k, l);
      e["coherency_min_eigenvalue"] = ev.mean;
      e["coherency_min_eigenvalue_stderr"] = ev.stderr_;
      per_l.push_back(e);
    }
    reflected[slot_key(k, t.orders)] = per_l;
  }
  j["reflected"] = reflected;
  if (t.bin_pixels > 0) {
    Json f = Json::array(), se = Json::array();
    for (int l = 0; l < t.wavelengths; ++l) {
      Json fl = Json::array(), sel = Json::array();
      for (int px = 0; px < t.bin_pixels; ++px) {
        fl.push_back(matrix_json(t.pixel_f(l, px)));
        sel.push_back(matrix_json(t.pixel_f_stderr(l, px)));
      }
      f.push_back(fl);
      se.push_back(sel);
    }
    j["bins"] = {{"resolution", t.bin_resolution}, {"order", "total"}, {"f", f}, {"f_stderr", se}};
  }
  if (t.plane_bins > 0) {
    Json plane = Json::object();
    for (int k = 0; k <= t.orders; ++k) {
      Json f = Json::array(), se = Json::array();
      for (int l = 0; l < t.wavelengths; ++l) {
        Json fl = Json::array(), sel = Json::array();
        for (int b = 0; b < t.plane_bins; ++b) {
          fl.push_back(matrix_json(t.plane_f(k, l, b)));
          sel.push_back(matrix_json(t.plane_f_stderr(k, l, b)));
        }
        f.push_back(fl);
        se.push_back(sel);
      }
      plane[slot_key(k, t.orders)] = {{"f", f}, {"f_stderr", se}};
    }
    j["in_plane"] = plane;
  }
  return j;
}

}  // namespace microsim
