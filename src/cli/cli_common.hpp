// Shared pieces of the command-line layer: global options, progress display, output helpers.
// Each command lives in its own src/cli/cmd_*.cpp and registers itself from main.cpp.
#pragma once
#include <CLI/CLI.hpp>

#include <chrono>
#include <functional>
#include <initializer_list>
#include <string>
#include <vector>

#include "microsim/api/angle_list.hpp"
#include "microsim/api/run_context.hpp"
#include "microsim/api/surface_input.hpp"
#include "microsim/common.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {
class TallySplit;
}

namespace microsim::cli {

struct GlobalOptions {
  int threads = 0;  // 0 = all cores
  bool quiet = false;
  // Work shared with other processes (shards, MPI ranks, a merge's replay; scaleout.hpp):
  // passed to the estimators' options. `ranks` > 0 under MPI (written to the record).
  TallySplit* split = nullptr;
  int ranks = 0;
  // A shard, or an MPI rank other than 0: this process's outputs are not the run's (they are
  // never written) and its verdicts do not end the run.
  bool partial = false;
};

// A command's input surface: the file `path`.
Microsurface input_surface(const GlobalOptions& g, const std::string& path);
// The same as a request's surface: the file, loaded when the request runs.
SurfaceInput input_surface_source(const GlobalOptions& g, const std::string& path);
std::vector<SurfaceInput> input_surface_sources(const GlobalOptions& g, const std::vector<std::string>& paths);
// The run as a request's record knows it: threads, MPI ranks and the shards/MPI split of g.
RunContext run_context(const GlobalOptions& g);
// A command's output surface: saved to `path`.
void output_surface(const GlobalOptions& g, const Microsurface& s, const std::string& path);

// A progress bar with ETA on a terminal; silent in pipes, CI and with --quiet.
class Progress {
 public:
  Progress(const std::string& label, bool quiet);
  ~Progress() { finish(); }
  void update(double fraction);
  void finish();

 private:
  std::string label_;
  bool enabled_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_;
};

// UsageError naming -o and the accepted extensions unless `path` has one of them.
void require_extension(const std::string& path, std::initializer_list<const char*> allowed);
// JSON or CSV (rows only) by extension, atomically.
void write_record(const std::string& path, const Json& j);
// The same (the global options kept for the commands' uniform call).
void write_record(const GlobalOptions& g, const std::string& path, const Json& j);
std::string fmt(double x, int precision = 4);
// A record's number, or "-" where it is null (e.g. a z without an error bar).
std::string fmt(const Json& x, int precision = 4);
// A table cell: fmt(x, precision) right-aligned in `width` columns, at least one space before it;
// a number too long for that (a z of 10^7) in scientific notation instead, so that the columns
// stay aligned.
std::string cell(const Json& x, int precision, int width);
// Fields every JSON record starts with: command, version, threads (and ranks under MPI).
Json run_header(const std::string& command, const GlobalOptions& g);
// The library's angle lists (microsim/api/angle_list.hpp) named by their option ("--theta-i"):
// "a:b:step" (inclusive), "a,b,c" or "a", in degrees.
std::vector<double> parse_angle_list(const std::string& text, const std::string& option);
// parse_angle_list, then an error naming `option` unless every |azimuth| <= kMaxAzimuthDeg.
std::vector<double> parse_azimuth_list(const std::string& text, const std::string& option);
// An error naming `option` unless every angle is in [0, 90).
void require_above_horizon(const std::vector<double>& thetas_deg, const std::string& option);

// Registration of each command (definitions in cmd_*.cpp).
void register_generate(CLI::App& app, const GlobalOptions& g);
void register_info(CLI::App& app, const GlobalOptions& g);
void register_convert(CLI::App& app, const GlobalOptions& g);
void register_measure_ndf(CLI::App& measure, const GlobalOptions& g);
void register_measure_g1(CLI::App& measure, const GlobalOptions& g);
void register_measure_g2(CLI::App& measure, const GlobalOptions& g);
void register_measure_vndf(CLI::App& measure, const GlobalOptions& g);
void register_measure_bsdf(CLI::App& measure, const GlobalOptions& g);
void register_measure_albedo(CLI::App& measure, const GlobalOptions& g);
void register_demo(CLI::App& app, const GlobalOptions& g);
void register_validate(CLI::App& app, const GlobalOptions& g);
void register_render(CLI::App& app, const GlobalOptions& g);
// The documentation's reference pages, printed from the command tree `app` and the record
// tables' specifications (hidden from --help).
void register_reference(CLI::App& app);

}  // namespace microsim::cli
