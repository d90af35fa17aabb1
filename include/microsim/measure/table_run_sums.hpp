// The tallies of a run that enters only a renderer table's azimuthal averages (the turned runs
// of BsdfTableOptions::table_azimuths, BsdfOptions::table_sums_only). The table reads the mean
// f of the reflected total per pixel (table_f: .bsdf, .binary) or the Mueller bins (.pbsdf) and
// writes no error for these runs: they sum their replicates' first moments without the spread
// (the same sums, in the same order, as add_replicate), and once finished keep only what the
// table reads.
#pragma once
#include "microsim/measure/bsdf_result.hpp"
#include "microsim/measure/spectral_tally.hpp"

namespace microsim {

// Replicate rep's first moments and counts added to t as BsdfTally::add_replicate adds them (its
// Welford update adds S to the sum: the same sums bit for bit), the second moments left alone.
void add_replicate_first_moments(BsdfTally& t, const BsdfTally& rep);
// The same for wavelength l of a spectral replicate.
void add_replicate_first_moments(BsdfTally& t, const SpectralTally& rep, int l);

// Frees what a table does not read of a finished table-only run: every second moment, the
// in-plane sums and the pixel sums of every slot but the reflected total (K of side 0), which
// stay as pix[px] (pix.size() == pixels), unless `keep_f` is false (a .pbsdf reads the Mueller
// bins only: no pixel sums). The counts stay (BsdfTable::paths).
void keep_table_sums_only(BsdfResult& r, bool keep_f);

// f_pixel(side, k, px, lambda).mean without its error, bit for bit, from the first moment alone;
// of a result kept by keep_table_sums_only, the reflected total's only (std::logic_error for
// another slot).
double f_pixel_mean(const BsdfResult& r, int side, int k, int px, int lambda = -1);

}  // namespace microsim
