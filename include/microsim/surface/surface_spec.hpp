// The surface spec: every kind of surface `microsim generate KIND` builds, with a table of its
// options (name, type, default, accepted range, the generator parameter each sets), and the one
// route from options given as text (command line, preset TOML, suite entry, Python keywords) to
// a generator call. The command line registers its options from this table and the suites and
// Python call it, so a surface means the same everywhere.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "microsim/io/checks.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim {

// One option of a kind: `--NAME` on the command line, the key NAME in a preset or a suite
// entry's "args", the keyword NAME with '_' for '-' in Python.
struct SurfaceOption {
  enum class Type { Integer, Number, Seed, Text, Flag };
  // How a value is checked: a number in `range`, any finite number, an integer in [lo, hi], a
  // seed in [0, 2^64 - 1], or only converted (a number) / taken as it is (text).
  enum class Check { None, Range, Finite, Integer, Seed };
  std::string name;
  Type type = Type::Number;
  Check check = Check::None;
  Range range{0, 0};
  long long lo = 0, hi = 0;
  std::string default_text;  // the default as --help shows it; "" = none shown (derived or unset)
  bool required = false;
  std::string help;
  std::string sets;  // the generator parameter(s) it sets, e.g. "GaussianParams::alpha_x"
};

struct SurfaceKind {
  std::string name, help;
  std::string output_help, config_help;  // the command line's -o and --config
  std::vector<SurfaceOption> options;
  // The option of that name, or nullptr.
  const SurfaceOption* option(const std::string& name) const;
  // "resolution, size, ..." in table order.
  std::string option_names() const;
};

// Every kind, in the order of `microsim generate --help`.
const std::vector<SurfaceKind>& surface_kinds();
// "gaussian, flat, ..." in that order.
std::string surface_kind_names();
// The kind of that name; UsageError "unknown surface kind 'X' (known: ...)" otherwise.
const SurfaceKind& surface_kind(const std::string& name);

// A surface to generate: its kind and the options given, as text (flags "true" or "false").
// Options not given keep the generator's defaults (or derived values, e.g. alpha-y from alpha-x).
struct SurfaceRequest {
  std::string kind;
  std::map<std::string, std::string> options;
};

// The parameter an option of the table sets, as a ParameterError's message names it (common.hpp):
// its name with '_' for '-' in braces ("pixel-size": "{pixel_size}"), the command line's option
// and Python's keyword once spelled.
std::string surface_option_placeholder(const std::string& option);

// Sets (or replaces) one option after checking it against the table: UsageError "unknown option
// 'NAME' for 'KIND' (known: ...)", or a ParameterError for a bad value
// ("{alpha}: must be a finite number in (0, 10] (got -1)").
void set_surface_option(SurfaceRequest& r, const std::string& name, const std::string& value);

// Reads a preset (surfaces/*.toml, by read_preset_file: the command line's --config reads it
// the same way) into r, each key through set_surface_option. UsageError naming the file (and the
// line) for what read_preset_file refuses, an unknown key or a bad value
// ("PATH: line 2: {alpha}: must be a finite number in (0, 10] (got -1)").
void read_surface_preset(SurfaceRequest& r, const std::string& path);

// Checks every option and their combinations (and, when output_path is not empty, that the
// surface can be saved in that format), in the order and with the messages of `microsim
// generate`, then builds the surface. UsageError for anything refused.
Microsurface generate_surface(const SurfaceRequest& r, const std::string& output_path = "");
// The checks of generate_surface without building anything (to refuse before writing).
void check_surface_request(const SurfaceRequest& r, const std::string& output_path = "");

// ParameterError "{output} PATH: unknown surface format (use .exr, .ply, .obj or .off)" unless `path` ends
// in one of them.
void require_surface_extension(const std::string& path);

// What `microsim generate` tells after saving the surface at `path`: a one- or few-line summary
// (computed only when with_summary), warnings shown always, notes shown with the summary.
struct SurfaceReport {
  std::string summary;
  std::vector<std::string> warnings, notes;
};
SurfaceReport surface_report(const SurfaceRequest& r, const Microsurface& s, const std::string& path,
                             bool with_summary);

}  // namespace microsim
