// One measurement split over processes (docs/theory/numerics.md): MPI ranks, or shards
// run one at a time (`--shard K/N`, job arrays, resuming a killed run) and merged afterwards.
//
// Why the split is exact: every ray draws its numbers from CounterRng(seed, stream, index), so a
// ray is the same wherever it is traced, and an estimator's work is made of units whose tallies
// do not depend on which process computed them:
//  * replicates (G1, G2, BSDF: each replicate is a full stratified pass, measure/replicates.hpp;
//    a spectral BSDF's sums of every wavelength and a polarized one's Mueller sums alike), and
//    the sequential batches of the BSDF's Smith random walk: one row of tallies per unit;
//  * single rays (VNDF: i.i.d. origins, integer bin counts): only totals.
// A process computes the units of its share; `exchange` then completes the tallies (an MPI sum,
// or the parts read back by a merge) before the estimator turns them into a result, so the result
// is computed from the same numbers, in the same order, as in one process. Rows are integer
// counts and real sums; every row comes from exactly one process (its other copies are zero), so
// even real sums (weights of a conductor, of a finite object's rays) arrive bit for bit.
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/tally_fields.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

// Half-open range [first, end) of work units.
struct UnitRange {
  std::uint64_t first = 0, end = 0;
  bool contains(std::uint64_t u) const { return u >= first && u < end; }
  std::uint64_t size() const { return end > first ? end - first : 0; }
};

// Share k (0-based) of n over `units`: [floor(k units / n), floor((k + 1) units / n)). The
// shares tile [0, units) exactly; with n > units some are empty.
UnitRange shard_range(std::uint64_t units, int k, int n);

// The tallies of one estimator call. Layout: `units` rows of row_counts integers and row_reals
// reals (units * width values, all zero outside `covered`), then the additive totals
// (tail_counts, tail_reals). Integer totals from several processes are summed; real totals come
// from one process only (the others leave them at zero).
struct Tallies {
  // "g1", "g2", "vndf", "bsdf", "bsdf_model", "bsdf_spectral", "bsdf_mueller", "bsdf_ensemble"
  std::string kind;
  std::uint64_t units = 0;    // replicates, batches or rays
  UnitRange covered;          // the units this process computed
  std::size_t row_counts = 0, row_reals = 0;
  std::vector<std::uint64_t> counts;  // units * row_counts
  std::vector<double> reals;          // units * row_reals
  std::vector<std::uint64_t> tail_counts;
  std::vector<double> tail_reals;

  Tallies() = default;
  Tallies(std::string kind, std::uint64_t units, UnitRange covered, std::size_t row_counts,
          std::size_t row_reals, std::size_t tail_counts, std::size_t tail_reals);
  std::uint64_t* count_row(std::uint64_t u) { return counts.data() + u * row_counts; }
  double* real_row(std::uint64_t u) { return reals.data() + u * row_reals; }
  const std::uint64_t* count_row(std::uint64_t u) const { return counts.data() + u * row_counts; }
  const double* real_row(std::uint64_t u) const { return reals.data() + u * row_reals; }
  // Number of values exchanged (the size of the tallies on the wire: 8 bytes each).
  std::size_t values() const {
    return counts.size() + reals.size() + tail_counts.size() + tail_reals.size();
  }
};

// TraceCounters as integers, one per declared field in declaration order (TraceCounters::
// for_each_field, tally_fields.hpp).
constexpr std::size_t kCounterValues = scalar_field_count<TraceCounters>();
inline void put_counters(const TraceCounters& c, std::uint64_t* out) { pack_fields(c, out); }
inline TraceCounters get_counters(const std::uint64_t* in) {
  TraceCounters c;
  unpack_fields(c, in);
  return c;
}

// How an estimator shares its work with other processes. Estimators take a `TallySplit*` in
// their options (nullptr: compute everything here).
class TallySplit {
 public:
  virtual ~TallySplit() = default;
  // The units of `units` that this process computes.
  virtual UnitRange share(std::uint64_t units) const = 0;
  // Called once per estimator call, in call order, from the calling thread, with this process's
  // units filled in; on return `t` holds the tallies of every unit.
  virtual void exchange(Tallies& t) = 0;
};
inline UnitRange share_of(const TallySplit* split, std::uint64_t units) {
  return split ? split->share(units) : UnitRange{0, units};
}

// The per-unit tallies of a declared struct (tally_fields.hpp) as the rows of one exchange: unit
// u's row holds its fields in declaration order, the integers in its count row and the reals in
// its real row, so every declared field crosses (shards, merge, MPI) and no other. A process puts
// the units of its share; after exchange() every row is complete and get() reads unit u back.
// Every unit has the shape of `shape` (vectors at the same lengths); a unit of another shape is
// a std::logic_error.
template <class T, class D = AllFields<T>>
class FieldRows {
 public:
  FieldRows(const char* kind, std::uint64_t units, UnitRange share, const T& shape)
      : sizes_(field_sizes<T, D>(shape)), rows_(kind, units, share, sizes_.counts, sizes_.reals, 0, 0) {}
  // Unit u of this process's share.
  void put(std::uint64_t u, const T& x) {
    check_shape(x);
    if (!rows_.covered.contains(u)) throw std::logic_error("FieldRows: unit outside this process's share");
    pack_fields<T, D>(x, rows_.count_row(u), rows_.real_row(u));
  }
  void exchange(TallySplit& split) { split.exchange(rows_); }
  // Unit u (any unit, after the exchange) into x, a tally of the units' shape.
  void get(std::uint64_t u, T& x) const {
    check_shape(x);
    unpack_fields<T, D>(x, rows_.count_row(u), rows_.real_row(u));
  }
  std::uint64_t units() const { return rows_.units; }

 private:
  void check_shape(const T& x) const {
    const FieldSizes s = field_sizes<T, D>(x);
    if (s.counts != sizes_.counts || s.reals != sizes_.reals)
      throw std::logic_error("FieldRows: a unit's fields differ in size from the rows'");
  }
  FieldSizes sizes_;
  Tallies rows_;
};

// --- Shards ---------------------------------------------------------------------------------

// Shard k (1-based, as on the command line) of n: computes its share of every estimator call and
// keeps the tallies for the partial record (the exchange leaves them partial).
class ShardRecorder : public TallySplit {
 public:
  ShardRecorder(int k, int n);
  UnitRange share(std::uint64_t units) const override { return shard_range(units, k_ - 1, n_); }
  void exchange(Tallies& t) override { entries_.push_back(t); }
  const std::vector<Tallies>& entries() const { return entries_; }
  int index() const { return k_; }
  int count() const { return n_; }

 private:
  int k_, n_;
  std::vector<Tallies> entries_;
};

// "K/N" with 1 <= K <= N (UsageError naming --shard otherwise).
std::pair<int, int> parse_shard(const std::string& text);

// Where shard K of N writes its partial record: OUTPUT.shard-K-of-N.json.
std::string shard_path(const std::string& output, int k, int n);

// Replays a run from merged tallies: computes no unit, and each exchange receives the next
// merged entry (a mismatch of kind or size is a RuntimeFailure: the command that replays is not
// the one the parts came from).
class TallyReplay : public TallySplit {
 public:
  explicit TallyReplay(std::vector<Tallies> entries) : entries_(std::move(entries)) {}
  UnitRange share(std::uint64_t) const override { return {0, 0}; }
  void exchange(Tallies& t) override;
  // Every entry consumed (else the replay ended early: a RuntimeFailure).
  void finish() const;

 private:
  std::vector<Tallies> entries_;
  std::size_t next_ = 0;
};

// --- Partial records ------------------------------------------------------------------------

// The run a shard belongs to: the command's arguments (output replaced by kOutputPlaceholder,
// no --shard, --threads or --quiet), every input file with its size and content hash, and a
// fingerprint over all of them and the program version.
constexpr const char* kOutputPlaceholder = "{output}";
constexpr const char* kPartialFormat = "microsim-partial-1";
struct RunIdentity {
  std::vector<std::string> command;
  std::string output;  // the -o of the shard's command line
  struct Input {
    std::string path;
    std::uint64_t bytes = 0;
    std::string hash;  // FNV-1a 64 of the content, hex
  };
  std::vector<Input> inputs;
  std::string version;
  std::string fingerprint() const;
};
// FNV-1a 64 of a file's content as 16 hex digits (RuntimeFailure if unreadable).
std::string file_hash(const std::string& path, std::uint64_t* bytes = nullptr);
// From the words after the program name: drops --shard, --threads and --quiet, replaces the
// value of -o/--output by the placeholder, and hashes every word that names an existing file.
RunIdentity identify_run(const std::vector<std::string>& args, const std::string& version);

// The partial record of one shard (format in docs/reference/file-formats.md).
Json partial_json(const RunIdentity& run, const ShardRecorder& shard, double seconds);

// Merged parts: the run, the shard count, and the tallies of every estimator call complete.
struct MergedRun {
  RunIdentity run;
  int shards = 0;
  std::vector<Tallies> entries;
};
// Checks that the parts (name, record) are partial records of one run (same fingerprint, command,
// inputs and entry layout), that shards 1..N each appear exactly once and that every entry's
// covered units tile [0, units) exactly; throws UsageError naming the missing, duplicated or
// foreign part. Rows are placed, integer totals summed, real totals summed in shard order.
MergedRun merge_partials(const std::vector<std::pair<std::string, Json>>& parts);

}  // namespace microsim
