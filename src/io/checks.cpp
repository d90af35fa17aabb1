#include "microsim/io/checks.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <limits>
#include <sstream>

#include "microsim/common.hpp"

namespace microsim {

bool Range::contains(double x) const {
  if (!std::isfinite(x)) return false;
  if (lo_open ? !(x > lo) : !(x >= lo)) return false;
  if (hi_open ? !(x < hi) : !(x <= hi)) return false;
  return true;
}

std::string number_text(double x) {
  std::ostringstream os;
  os.precision(6);
  os << x;
  return os.str();
}

std::string Range::text() const {
  return std::string(lo_open ? "(" : "[") + number_text(lo) + ", " +
         (hi >= 1e300 ? std::string("inf)") : number_text(hi) + (hi_open ? ")" : "]"));
}

void require_in_range(double x, const Range& r, const std::string& name) {
  if (!r.contains(x))
    throw ParameterError(name + (name.empty() ? "" : " ") + "must be a finite number in " + r.text() +
                         " (got " + number_text(x) + ")");
}

double parse_number_in(const std::string& text, const Range& r, const std::string& name) {
  const char* s = text.c_str();
  char* end = nullptr;
  errno = 0;
  double x = std::strtod(s, &end);
  if (text.empty() || end != s + text.size() || std::isspace(static_cast<unsigned char>(text[0])))
    throw ParameterError(name + (name.empty() ? "" : " ") + "must be a finite number in " + r.text() +
                         " (got '" + literal_text(text) + "')");
  require_in_range(x, r, name);
  return x;
}

namespace {
// Decimal digits only (an optional leading '-' when negative values may be accepted).
bool parse_decimal(const std::string& text, bool allow_minus, unsigned long long& magnitude, bool& negative) {
  std::size_t k = 0;
  negative = false;
  if (allow_minus && !text.empty() && text[0] == '-') negative = true, k = 1;
  if (k >= text.size() || text.size() - k > 20) return false;
  magnitude = 0;
  for (; k < text.size(); ++k) {
    if (text[k] < '0' || text[k] > '9') return false;
    unsigned d = text[k] - '0';
    if (magnitude > (~0ull - d) / 10) return false;  // beyond 2^64 - 1
    magnitude = magnitude * 10 + d;
  }
  return true;
}
}  // namespace

long long parse_integer_in(const std::string& text, long long lo, long long hi, const std::string& name) {
  unsigned long long m;
  bool neg;
  const auto fail = [&] {
    return ParameterError(name + (name.empty() ? "" : " ") + "must be an integer in [" + std::to_string(lo) +
                          ", " + std::to_string(hi) + "] (got '" + literal_text(text) + "')");
  };
  if (!parse_decimal(text, true, m, neg)) throw fail();
  const unsigned long long max = static_cast<unsigned long long>(std::numeric_limits<long long>::max());
  if (m > max) throw fail();
  const long long x = neg ? -static_cast<long long>(m) : static_cast<long long>(m);
  if (x < lo || x > hi) throw fail();
  return x;
}

std::uint64_t parse_seed(const std::string& text, const std::string& name) {
  unsigned long long m;
  bool neg;
  if (!parse_decimal(text, false, m, neg))
    throw ParameterError(name + (name.empty() ? "" : " ") +
                         "must be an integer in [0, 18446744073709551615] (got '" + literal_text(text) + "')");
  return m;
}

std::vector<std::string> split_items(const std::string& text, char sep, const std::string& name) {
  std::vector<std::string> items;
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = text.find(sep, start);
    items.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (items.back().empty())
      throw ParameterError(name + " '" + literal_text(text) + "': empty item" +
                           (text.empty() ? "" : std::string(" (a leading, trailing or doubled '") + sep + "')"));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return items;
}

void require_regular_input(const std::string& path, const std::string& name) {
  namespace fs = std::filesystem;
  // Standard input named on purpose (a pipe or a terminal) is the user's choice to read.
  if (path == "-" || path == "/dev/stdin") return;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);  // follows symbolic links
  if (ec || !fs::exists(st) || fs::is_regular_file(st)) return;
  const char* kind = fs::is_directory(st) ? "a folder"
                     : fs::is_fifo(st)    ? "a FIFO"
                     : fs::is_socket(st)  ? "a socket"
                     : fs::is_character_file(st) || fs::is_block_file(st) ? "a device"
                                                                           : "not a regular file";
  throw ParameterError(name + (name.empty() ? "" : " ") + literal_text(path) + ": " + kind +
                       ", not a regular file (inputs are read from regular files)");
}

double available_memory_bytes() {
  double have = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE);
  // What the kernel can give without swapping, on a machine shared with other processes.
  if (std::ifstream meminfo("/proc/meminfo"); meminfo) {
    std::string key;
    double kib;
    while (meminfo >> key >> kib) {
      if (key == "MemAvailable:") {
        if (kib > 0) have = std::min(have, kib * 1024.0);
        break;
      }
      meminfo.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
    }
  }
  struct rlimit rl;
  if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
    have = std::min(have, static_cast<double>(rl.rlim_cur));
  return have;
}

void require_memory(double bytes, const std::string& what) {
  const double have = available_memory_bytes();
  if (std::isfinite(bytes) && bytes <= 0.8 * have) return;
  std::ostringstream os;
  os.precision(3);
  os << what << " needs about " << bytes / (1 << 30) << " GiB, more than 80% of the "
     << have / (1 << 30) << " GiB available";
  throw ParameterError(os.str());
}

}  // namespace microsim
