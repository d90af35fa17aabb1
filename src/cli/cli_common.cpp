#include "cli_common.hpp"

#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "microsim/api/record_file.hpp"
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
  require_output_format(path, allowed);
}

void write_record(const std::string& path, const Json& j) { write_record_file(path, j); }

void write_record(const GlobalOptions&, const std::string& path, const Json& j) { write_record(path, j); }

Microsurface input_surface(const GlobalOptions&, const std::string& path) { return load_surface(path); }

SurfaceInput input_surface_source(const GlobalOptions&, const std::string& path) { return surface_file(path); }

std::vector<SurfaceInput> input_surface_sources(const GlobalOptions& g, const std::vector<std::string>& paths) {
  std::vector<SurfaceInput> sources;
  for (const std::string& p : paths) sources.push_back(input_surface_source(g, p));
  return sources;
}

RunContext run_context(const GlobalOptions& g) {
  RunContext ctx;
  ctx.threads = g.threads;
  ctx.ranks = g.ranks;
  ctx.split = g.split;
  return ctx;
}

void output_surface(const GlobalOptions&, const Microsurface& s, const std::string& path) { save_surface(s, path); }

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
  return record_header(command, run_context(g));
}

namespace {
// The library's name of the parameter an option sets: "--theta-i" is theta_i.
std::string parameter_of(const std::string& option) {
  std::string name = option.substr(option.find_first_not_of('-'));
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}
}  // namespace

std::vector<double> parse_angle_list(const std::string& text, const std::string& option) {
  return angle_list(text, parameter_of(option)).degrees;
}

std::vector<double> parse_azimuth_list(const std::string& text, const std::string& option) {
  return azimuth_list(text, parameter_of(option)).degrees;
}

void require_above_horizon(const std::vector<double>& thetas, const std::string& option) {
  microsim::require_above_horizon(thetas, parameter_of(option));
}

}  // namespace microsim::cli
