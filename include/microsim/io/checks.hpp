// The one set of rules every option and every file header field goes through: a number must be
// finite and inside its documented range, a count must be an integer in range, and anything
// sized by the input (rays, bins, grid cells, mesh vertices) must fit in memory. Each rule
// throws UsageError with one line naming the option or file field and the accepted range, so
// the command line exits 2 before any work or allocation. A NAME or WHAT below is a
// ParameterError's message template (common.hpp): "{rays}" names the parameter rays; a path in it
// is given as literal_text(path). The errors are ParameterErrors.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace microsim {

// An interval of accepted values; ends open or closed. Non-finite values are never accepted.
struct Range {
  double lo, hi;
  bool lo_open = false, hi_open = false;
  bool contains(double x) const;
  std::string text() const;  // "(0, 10]", "[1, 1e+12]", "(0, inf)"
};
// Common ranges.
inline Range positive() { return {0, 1e300, true, false}; }  // (0, inf) for finite numbers
inline Range open_closed(double lo, double hi) { return {lo, hi, true, false}; }
inline Range closed(double lo, double hi) { return {lo, hi, false, false}; }

// Shortest readable form of a number ("0.5", "1e+300", "nan", "-inf").
std::string number_text(double x);

// "NAME must be a finite number in RANGE (got X)" unless r.contains(x).
void require_in_range(double x, const Range& r, const std::string& name);
// Parses the whole of `text` as a finite number in r, or throws naming `name`.
double parse_number_in(const std::string& text, const Range& r, const std::string& name);
// Parses a decimal integer in [lo, hi] (no sign games, no wrap-around, no exponent).
long long parse_integer_in(const std::string& text, long long lo, long long hi, const std::string& name);
// Parses a seed: a decimal integer in [0, 2^64 - 1].
std::uint64_t parse_seed(const std::string& text, const std::string& name);

// The items of a `sep`-separated list; UsageError naming `name` when the list or any item is
// empty (a leading, trailing or doubled separator is a mistake, not an item to skip).
std::vector<std::string> split_items(const std::string& text, char sep, const std::string& name);

// UsageError "NAME PATH: not a regular file (a FIFO ...)" when `path` exists but is a FIFO, a
// device, a socket or a folder: reading one could block forever or never end. Missing files
// are left to the reader's own message. "-" and /dev/stdin pass: standard input named on
// purpose (e.g. `microsim merge /dev/stdin PART2 < PART1`) is read as before.
void require_regular_input(const std::string& path, const std::string& name);

// Bytes the process may use: the memory available now (MemAvailable), physical memory, or the
// address-space limit, whichever is lowest.
double available_memory_bytes();
// UsageError "WHAT needs about X GiB, more than 80% of the Y GiB available" when
// bytes > 0.8 * available (or bytes is not finite).
void require_memory(double bytes, const std::string& what);

}  // namespace microsim
