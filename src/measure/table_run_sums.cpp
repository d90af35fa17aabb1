#include "microsim/measure/table_run_sums.hpp"

#include <stdexcept>

#include "microsim/tally_fields.hpp"

namespace microsim {

namespace {
// sum += S element by element: Welford's update of the sum in add_replicate_sums (which skips
// S = 0 on a zero sum, the same value).
template <class At>
void add_sums(std::vector<double>& sum, At&& at) {
  for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += at(i);
}
}  // namespace

void add_replicate_first_moments(BsdfTally& t, const BsdfTally& rep) {
  if (t.albedo.empty()) t = BsdfTally(rep.orders, rep.pixels, rep.plane_bins);
  add_sums(t.albedo, [&](std::size_t i) { return rep.albedo[i]; });
  add_sums(t.pix, [&](std::size_t i) { return rep.pix[i]; });
  add_sums(t.plane, [&](std::size_t i) { return rep.plane[i]; });
  add_fields(t, rep);
  ++t.replicates;
}

void add_replicate_first_moments(BsdfTally& t, const SpectralTally& rep, int l) {
  if (t.albedo.empty()) t = BsdfTally(rep.orders, rep.pixels, rep.plane_bins);
  const std::size_t L = static_cast<std::size_t>(rep.wavelengths);
  add_sums(t.albedo, [&](std::size_t i) { return rep.albedo[i * L + l]; });
  add_sums(t.pix, [&](std::size_t i) { return rep.pix[i * L + l]; });
  add_sums(t.plane, [&](std::size_t i) { return rep.plane[i * L + l]; });
  BsdfTally counts;  // the path counts, shared by every wavelength
  rep.put_path_counts(counts);
  add_fields(t, counts);
  ++t.replicates;
}

namespace {
// t's pixel sums of the reflected total (slot K of side 0) alone, at pix[px], and its counts.
void keep_reflected_total(BsdfTally& t, bool keep_f) {
  if (keep_f) {
    const auto total = t.pix.begin() + static_cast<std::ptrdiff_t>(t.p_index(0, t.orders, 0));
    std::vector<double>(total, total + t.pixels).swap(t.pix);
  } else {
    std::vector<double>().swap(t.pix);
  }
  for (std::vector<double>* v : {&t.albedo2, &t.pix2, &t.plane, &t.plane2}) std::vector<double>().swap(*v);
}
}  // namespace

void keep_table_sums_only(BsdfResult& r, bool keep_f) {
  if (!r.spectral.empty()) {
    // A spectral table reads each wavelength's tallies; `measured` (the first wavelength's) only
    // for its counts.
    BsdfTally counts;
    add_fields(counts, r.measured);
    counts.orders = r.measured.orders;
    counts.replicates = r.measured.replicates;
    r.measured = std::move(counts);
    for (BsdfTally& t : r.spectral) keep_reflected_total(t, keep_f);
  } else {
    keep_reflected_total(r.measured, keep_f);
  }
  r.smith_walk.reset();
  if (r.polarization) r.polarization->keep_table_sums_only();
}

double f_pixel_mean(const BsdfResult& r, int side, int k, int px, int lambda) {
  const BsdfTally& t = r.tally(lambda);
  // A kept table-only tally holds the reflected total alone (pix.size() == pixels; a full one
  // holds at least 2 slots).
  const bool total_only = t.pix.size() == static_cast<std::size_t>(t.pixels);
  if (total_only && (side != 0 || k != t.orders))
    throw std::logic_error("f_pixel_mean: a table-only run keeps the reflected total alone");
  // BsdfTally::estimate's mean (and tally_estimate's): sum / paths * scale, 0 without paths.
  if (t.paths == 0) return 0.0;
  const double sum = t.pix[total_only ? static_cast<std::size_t>(px) : t.p_index(side, k, px)];
  return sum / static_cast<double>(t.paths) * (1.0 / r.map.pixel_cos_integral(px));
}

}  // namespace microsim
