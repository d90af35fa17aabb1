#include "microsim/measure/polarized_walk.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/measure/replicates.hpp"

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
  std::vector<double> x(replicates);
  for (std::size_t at = 0; at < per_rep; ++at) {
    const double c = cos_integral[(at / 16) % cos_integral.size()];
    for (int q = 0; q < replicates; ++q) x[q] = reps[q * per_rep + at] / n * (1.0 / c);
    out[at] = microsim::replicate_mean(x).stderr_;
  }
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
// The walk

namespace {
// The units of the unpolarized tallies (path_plan, measure/replicates.hpp), so the sums are
// added in the same order.
struct UnitSums {
  std::vector<double> sums;   // [k][l][16]
  std::vector<double> map;    // [k][l][pixel][16]
  std::vector<double> bins;   // [l][bin pixel][16]
  std::vector<double> plane;  // [k][l][b][16]
  std::uint64_t paths = 0;
  UnitSums& operator+=(const UnitSums& o) {
    if (sums.empty()) return *this = o;
    for (std::size_t i = 0; i < sums.size(); ++i) sums[i] += o.sums[i];
    for (std::size_t i = 0; i < map.size(); ++i) map[i] += o.map[i];
    for (std::size_t i = 0; i < bins.size(); ++i) bins[i] += o.bins[i];
    for (std::size_t i = 0; i < plane.size(); ++i) plane[i] += o.plane[i];
    paths += o.paths;
    return *this;
  }
};
// Units run at once: at most this many bytes of unit sums.
constexpr double kPassBytes = 64.0 * 1024 * 1024;
}  // namespace

PolarizationTally measure_polarization(const Tracer& tracer, const PolarizedWalkSetup& su) {
  const ReplicatePlan plan(su.rays, su.replicates);
  const int K = su.orders;
  const int L = su.spectral.empty() ? 1 : static_cast<int>(su.spectral.size());
  const Material* materials = su.spectral.empty() ? &su.material : su.spectral.data();
  PolarizationTally t;
  t.orders = K;
  t.wavelengths = L;
  t.replicates = plan.replicates;
  const HemisphereMap map(kPolarizationMapResolution);
  const int npix = map.size();
  t.pixels = npix;
  const std::size_t width = static_cast<std::size_t>(K + 1) * L * 16;
  const std::size_t map_width = width * npix;
  // Per-bin tallies (su.resolution > 0): a hemisphere map of all orders, the in-plane bins per slot.
  const bool per_bin = su.resolution > 0;
  const HemisphereMap bin_map(per_bin ? polarized_bin_resolution(su.resolution) : 1);
  const InPlaneBins plane(su.phi_i, per_bin ? su.resolution : 1);
  if (per_bin) {
    t.bin_resolution = bin_map.resolution();
    t.bin_pixels = bin_map.size();
    t.plane_bins = plane.size();
    for (int px = 0; px < t.bin_pixels; ++px) t.bin_cos.push_back(bin_map.pixel_cos_integral(px));
    for (int b = 0; b < t.plane_bins; ++b) t.plane_cos.push_back(plane.cos_integral(b));
  }
  const std::size_t bins_width = static_cast<std::size_t>(L) * t.bin_pixels * 16;
  const std::size_t plane_width = width * t.plane_bins;
  auto path = [&](int q, std::uint64_t i, UnitSums& acc) {
    thread_local std::vector<WalkFacet> facets;
    CounterRng rng(su.seed, ReplicatePlan::stream(su.stream, q), i);
    ++acc.paths;
    const Vec2 ab = plan.strata.point(i, rng);
    TraceCounters counters;
    std::uint64_t events = 0;
    double weights[kMaxWavelengths];
    std::fill(weights, weights + L, 1.0);
    const SpectralWeights sw{su.spectral.data(), L, weights};
    const WalkEnd e = walk_bsdf_path(tracer, su.origin0 + ab.x() * su.e1 + ab.y() * su.e2, -su.wi, su.material, rng,
                                     su.max_events, su.finite, counters, events,
                                     su.spectral.empty() ? nullptr : &sw, &facets);
    if (e.kind != WalkEnd::Reflected) return;
    Mueller M[kMaxWavelengths];
    walk_path_muellers(su.wi, facets, e.direction, materials, L, M);
    const int k = std::min(e.order, K) - 1;
    // A finite object's ray reflected below the base plane counts in the albedo only.
    const bool above = e.direction.z() > 0.0;
    const int px = above ? map.pixel_of(e.direction) : -1;
    if (per_bin && above) {
      const int bp = bin_map.pixel_of(e.direction), b = plane.bin_of(e.direction);
      for (int l = 0; l < L; ++l) {
        double* p = acc.bins.data() + (static_cast<std::size_t>(l) * t.bin_pixels + bp) * 16;
        for (int a = 0; a < 16; ++a) p[a] += su.ray_weight * M[l](a / 4, a % 4);
      }
      if (b >= 0)
        for (int slot : {k, K})
          for (int l = 0; l < L; ++l) {
            double* p = acc.plane.data() + ((static_cast<std::size_t>(slot) * L + l) * t.plane_bins + b) * 16;
            for (int a = 0; a < 16; ++a) p[a] += su.ray_weight * M[l](a / 4, a % 4);
          }
    }
    for (int slot : {k, K})
      for (int l = 0; l < L; ++l) {
        double* p = acc.sums.data() + (static_cast<std::size_t>(slot) * L + l) * 16;
        double* q = px < 0 ? nullptr : acc.map.data() + ((static_cast<std::size_t>(slot) * L + l) * npix + px) * 16;
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b) {
            const double w = su.ray_weight * M[l](a, b);
            p[4 * a + b] += w;
            if (q) q[4 * a + b] += w;
          }
      }
  };

  // Each replicate's sum starts at zero and adds its units in order, then the replicates are
  // added in order.
  t.total.assign(width, 0.0);
  t.replicate.assign(width * plan.replicates, 0.0);
  t.map_total.assign(map_width, 0.0);
  t.map_replicate.assign(map_width * plan.replicates, 0.0);
  t.bins_total.assign(bins_width, 0.0);
  std::vector<double> bins_replicate(bins_width * plan.replicates, 0.0);
  t.plane_total.assign(plane_width, 0.0);
  std::vector<double> plane_replicate(plane_width * plan.replicates, 0.0);
  const std::uint64_t per_pass = std::max<std::uint64_t>(
      16, static_cast<std::uint64_t>(kPassBytes / (8.0 * (width + map_width + bins_width + plane_width))));
  auto make = [&] {
    UnitSums u;
    u.sums.assign(width, 0.0);
    u.map.assign(map_width, 0.0);
    u.bins.assign(bins_width, 0.0);
    u.plane.assign(plane_width, 0.0);
    return u;
  };
  auto add_to_replicate = [&](int q, std::uint64_t, UnitSums&& part) {
    double* rep = t.replicate.data() + width * q;
    for (std::size_t i = 0; i < width; ++i) rep[i] += part.sums[i];
    double* rep_map = t.map_replicate.data() + map_width * q;
    for (std::size_t i = 0; i < map_width; ++i) rep_map[i] += part.map[i];
    double* rep_bins = bins_replicate.data() + bins_width * q;
    for (std::size_t i = 0; i < bins_width; ++i) rep_bins[i] += part.bins[i];
    double* rep_plane = plane_replicate.data() + plane_width * q;
    for (std::size_t i = 0; i < plane_width; ++i) rep_plane[i] += part.plane[i];
    t.paths += part.paths;
  };
  run_units<UnitSums>(path_plan(plan.replicates, plan.per_replicate()), make, path, add_to_replicate,
                      {0, ~std::uint64_t(0)}, UnitPasses{~std::uint64_t(0), per_pass});
  for (int q = 0; q < plan.replicates; ++q) {
    for (std::size_t i = 0; i < width; ++i) t.total[i] += t.replicate[width * q + i];
    for (std::size_t i = 0; i < map_width; ++i) t.map_total[i] += t.map_replicate[map_width * q + i];
    for (std::size_t i = 0; i < bins_width; ++i) t.bins_total[i] += bins_replicate[bins_width * q + i];
    for (std::size_t i = 0; i < plane_width; ++i) t.plane_total[i] += plane_replicate[plane_width * q + i];
  }
  if (per_bin) {
    t.bins_stderr = bin_stderrs(bins_replicate, bins_width / 16, t.replicates, t.paths, t.bin_cos);
    t.plane_stderr = bin_stderrs(plane_replicate, plane_width / 16, t.replicates, t.paths, t.plane_cos);
  }
  return t;
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
