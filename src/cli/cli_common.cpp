#include "cli_common.hpp"

#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "microsim/io/checks.hpp"
#include "microsim/version.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/surface_io.hpp"

namespace microsim::cli {

Progress::Progress(const std::string& label, bool quiet)
    : label_(label), enabled_(!quiet && isatty(STDERR_FILENO)),
      start_(std::chrono::steady_clock::now()) {}

void Progress::update(double fraction) {
  if (!enabled_) return;
  double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  double eta = fraction > 0 ? elapsed * (1 - fraction) / fraction : 0;
  int width = 30, filled = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * width);
  std::fprintf(stderr, "\r%s [%s%s] %3.0f%%  elapsed %.0fs  ETA %.0fs   ", label_.c_str(),
               std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(),
               100 * fraction, elapsed, eta);
  std::fflush(stderr);
  shown_ = true;
}

void Progress::finish() {
  if (shown_) std::fprintf(stderr, "\n");
  shown_ = false;
}

void require_extension(const std::string& path, std::initializer_list<const char*> allowed) {
  std::string ext = extension_of(path);
  std::string list;
  for (const char* a : allowed) {
    if (ext == a) return;
    list += std::string(list.empty() ? "" : ", ") + "." + a;
  }
  throw UsageError("-o " + path + ": unsupported output format (use " + list + ")");
}

void write_record(const std::string& path, const Json& j) {
  if (extension_of(path) == "csv") write_csv_rows(path, j);
  else write_json(path, j);
}

void write_record(const GlobalOptions& g, const std::string& path, const Json& j) {
  if (g.keep_record) g.keep_record(path, j);
  else write_record(path, j);
}

Microsurface input_surface(const GlobalOptions& g, const std::string& path) {
  return g.surface_by_name ? g.surface_by_name(path) : load_surface(path);
}

void output_surface(const GlobalOptions& g, const Microsurface& s, const std::string& path) {
  if (g.keep_surface) g.keep_surface(path, s);
  else save_surface(s, path);
}

std::string fmt(double x, int precision) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(precision) << x;
  return os.str();
}

std::string fmt(const Json& x, int precision) {
  return x.is_number() ? fmt(x.get<double>(), precision) : std::string("-");
}

std::string cell(const Json& x, int precision, int width) {
  std::string t = fmt(x, precision);
  for (int digits = precision; t.size() + 1 > static_cast<std::size_t>(width) && digits >= 0; --digits) {
    std::ostringstream os;
    os << std::scientific << std::setprecision(digits) << x.get<double>();
    t = os.str();
  }
  return std::string(std::max<int>(1, width - static_cast<int>(t.size())), ' ') + t;
}

Json run_header(const std::string& command, const GlobalOptions& g) {
  Json j = {{"command", command},
            {"microsim_version", version()},
            {"schema_version", kRecordSchemaVersion},
            {"threads", g.threads > 0 ? g.threads : tbb::this_task_arena::max_concurrency()}};
  if (g.ranks > 0) j["ranks"] = g.ranks;  // MPI processes that shared the work
  return j;
}

std::vector<double> parse_angle_list(const std::string& text, const std::string& option) {
  auto number = [&](const std::string& s) {
    try {
      std::size_t used = 0;
      double x = std::stod(s, &used);
      if (used != s.size() || !std::isfinite(x)) throw std::invalid_argument(s);
      return x;
    } catch (const std::exception&) {
      throw UsageError(option + " '" + text + "': expected a number, a,b,c or start:stop:step");
    }
  };
  std::vector<double> out;
  if (text.find(':') != std::string::npos) {
    const std::vector<std::string> parts = split_items(text, ':', option);
    if (parts.size() != 3) throw UsageError(option + " '" + text + "': expected start:stop:step");
    double a = number(parts[0]), b = number(parts[1]), step = number(parts[2]);
    if (!(step > 0) || b < a)
      throw UsageError(option + " '" + text + "': need step > 0 and stop >= start");
    if ((b - a) / step > 100000) throw UsageError(option + " '" + text + "': too many values");
    for (int k = 0; a + k * step <= b + 1e-9; ++k) out.push_back(a + k * step);
  } else {
    for (const std::string& p : split_items(text, ',', option)) out.push_back(number(p));
  }
  if (out.empty()) throw UsageError(option + " is empty");
  return out;
}

std::vector<double> parse_azimuth_list(const std::string& text, const std::string& option) {
  std::vector<double> phis = parse_angle_list(text, option);
  for (double p : phis)
    if (!(std::abs(p) <= kMaxAzimuthDeg))
      throw UsageError(option + " must be azimuths in [-" + fmt(kMaxAzimuthDeg, 0) + ", " + fmt(kMaxAzimuthDeg, 0) +
                       "] degrees (got " + number_text(p) + ")");
  return phis;
}

void require_above_horizon(const std::vector<double>& thetas, const std::string& option) {
  for (double t : thetas)
    if (!(t >= 0 && t < 90))
      throw UsageError(option + " must be in [0, 90) degrees (got " + fmt(t, 2) + ")");
}

}  // namespace microsim::cli
