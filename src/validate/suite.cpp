// Suites of validation entries (JSON files).
#include "checks_common.hpp"
#include "microsim/io/checks.hpp"

#include <set>

#include "microsim/io/json_input.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/surface_io.hpp"

namespace microsim::validation {

// ---------------------------------------------------------------------------------------------
// Suites.

namespace {
[[noreturn]] void suite_error(const std::string& file, const std::string& what) {
  throw ParameterError("{suite} " + literal_text(file) + ": " + literal_text(what));
}

// A positive integer (JSON integer, or a number with an integral value such as 1e6).
std::uint64_t get_count(const Json& j, const char* key, const std::string& file, const std::string& where) {
  const Json& x = j[key];
  if (!x.is_number() || !(x.get<double>() >= 1) || x.get<double>() != std::floor(x.get<double>()) ||
      x.get<double>() > 9e18)
    suite_error(file, where + ": " + key + " must be a positive integer");
  return x.is_number_unsigned() ? x.get<std::uint64_t>() : static_cast<std::uint64_t>(x.get<double>());
}

// A JSON value read as T, or UsageError naming the file, the entry and the key with what it
// must be (the parser's own text names neither).
template <class T>
T get_typed(const Json& j, const char* key, const std::string& file, const std::string& where, const char* expected) {
  try {
    return j[key].get<T>();
  } catch (const Json::exception&) {
    suite_error(file, where + ": " + key + " must be " + expected + " (got " + j[key].dump() + ")");
  }
}

// A seed: a JSON integer in [0, 2^64 - 1] (a negative value would wrap around and a fraction
// would be cut, both silently).
std::uint64_t get_seed(const Json& x, const std::string& file, const std::string& where, const std::string& key) {
  if (x.is_number_unsigned() || (x.is_number_integer() && x.get<std::int64_t>() >= 0)) return x.get<std::uint64_t>();
  if (x.is_number_float() && x.get<double>() >= 0 && x.get<double>() < 18446744073709551616.0 &&
      x.get<double>() == std::floor(x.get<double>()))
    return static_cast<std::uint64_t>(x.get<double>());
  suite_error(file, where + ": " + key + " must be an integer in [0, 2^64-1] (got " + x.dump() + ")");
}

void read_options(const Json& j, Options& o, const std::string& file, const std::string& where) {
  if (j.contains("theta_deg"))
    o.theta_deg = get_typed<std::vector<double>>(j, "theta_deg", file, where, "an array of numbers");
  if (j.contains("phi_deg")) o.phi_deg = get_typed<std::vector<double>>(j, "phi_deg", file, where, "an array of numbers");
  if (j.contains("rays")) o.rays = get_count(j, "rays", file, where);
  if (j.contains("seed")) o.seed = get_seed(j["seed"], file, where, "seed");
  if (j.contains("checks")) {
    o.checks = get_typed<std::vector<std::string>>(j, "checks", file, where, "an array of check names");
    if (o.checks.empty()) suite_error(file, where + ": checks is empty (leave it out to run every check)");
  }
  if (j.contains("ndf_theta_bins")) o.ndf_theta_bins = static_cast<int>(get_count(j, "ndf_theta_bins", file, where));
  if (j.contains("ndf_phi_bins")) o.ndf_phi_bins = static_cast<int>(get_count(j, "ndf_phi_bins", file, where));
  if (j.contains("min_ring_mass")) o.min_ring_mass = get_typed<double>(j, "min_ring_mass", file, where, "a number");
  if (j.contains("min_bin_count")) o.min_bin_count = get_count(j, "min_bin_count", file, where);
  for (double t : o.theta_deg)
    if (!(t >= 0 && t < 90)) suite_error(file, where + ": theta_deg must be in [0, 90) degrees");
  for (double p : o.phi_deg)
    if (!(std::abs(p) <= 3600)) suite_error(file, where + ": phi_deg must be azimuths in [-3600, 3600] degrees");
  if (o.theta_deg.empty() || o.phi_deg.empty()) suite_error(file, where + ": empty theta_deg or phi_deg");
  if (o.ndf_theta_bins > 3600 || o.ndf_phi_bins > 7200)
    suite_error(file, where + ": ndf_theta_bins in [1, 3600], ndf_phi_bins in [1, 7200]");
  if (!(o.min_ring_mass >= 0)) suite_error(file, where + ": min_ring_mass must be >= 0");
}

bool is_option_key(const std::string& k) {
  static const char* keys[] = {"theta_deg", "phi_deg", "rays", "seed", "checks", "ndf_theta_bins",
                               "ndf_phi_bins", "min_ring_mass", "min_bin_count"};
  return std::find(std::begin(keys), std::end(keys), k) != std::end(keys);
}

Json read_suite_json(const std::string& path) {
  require_regular_input(path, "{suite}");
  std::ifstream in(path);
  if (!in) throw ParameterError("{suite} " + literal_text(path) + ": cannot read the file");
  Json j;
  try {
    j = parse_json_input(in, "{suite} " + literal_text(path), JsonLimits{64, std::size_t(16) << 20, true});
  } catch (const Json::exception& e) {
    suite_error(path, std::string("not valid JSON (") + e.what() + ")");
  }
  if (!j.is_object()) suite_error(path, "expected a JSON object");
  return j;
}

// The options every entry starts from (`defaults`, else the built-in ones).
Options read_suite_defaults(const Json& j, const std::string& path) {
  Options defaults;
  if (j.contains("defaults")) {
    if (!j["defaults"].is_object()) suite_error(path, "defaults must be an object");
    for (auto it = j["defaults"].begin(); it != j["defaults"].end(); ++it)
      if (!is_option_key(it.key())) suite_error(path, "defaults: unknown field '" + it.key() + "'");
    read_options(j["defaults"], defaults, path, "defaults");
  }
  return defaults;
}

// A preset named relative to the suite is looked up beside the suite file, then in its parent
// folder (surfaces/); the absolute path.
std::string entry_preset(const Json& e, const std::string& path, const std::string& where,
                         const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  if (!e["preset"].is_string()) suite_error(path, where + ": preset must be a string");
  fs::path p = e["preset"].get<std::string>();
  if (p.is_relative()) {
    fs::path a = dir / p, b = dir.parent_path() / p;
    p = fs::exists(a) ? a : b;
  }
  if (!fs::exists(p)) suite_error(path, where + ": preset " + e["preset"].get<std::string>() + " not found");
  return fs::absolute(p).lexically_normal().string();
}

// The generator's options as the command line would give them (booleans as true/false).
std::vector<std::pair<std::string, std::string>> entry_args(const Json& e, const std::string& path,
                                                            const std::string& where) {
  if (!e["args"].is_object()) suite_error(path, where + ": args must be an object");
  std::vector<std::pair<std::string, std::string>> args;
  for (auto it = e["args"].begin(); it != e["args"].end(); ++it) {
    std::string value = it.value().is_string() ? it.value().get<std::string>() : it.value().dump();
    if (it.value().is_boolean()) value = it.value().get<bool>() ? "true" : "false";
    args.emplace_back(it.key(), value);
  }
  return args;
}

// Distinct seeds: the surfaces of an ensemble count as independent samples.
std::vector<std::uint64_t> entry_seeds(const Json& e, const std::string& path, const std::string& where) {
  if (!e["seeds"].is_array()) suite_error(path, where + ": seeds must be an array of integers in [0, 2^64-1]");
  std::vector<std::uint64_t> seeds;
  std::set<std::uint64_t> seen;
  for (const Json& x : e["seeds"]) {
    seeds.push_back(get_seed(x, path, where, "seeds"));
    if (!seen.insert(seeds.back()).second)
      suite_error(path, where + ": seeds: " + std::to_string(seeds.back()) +
                            " is given twice (the surfaces of an ensemble must be independent)");
  }
  return seeds;
}

SuiteEntry read_suite_entry(const Json& e, const std::string& path, const std::filesystem::path& dir,
                            const Options& defaults) {
  SuiteEntry entry;
  if (!e.is_object() || !e.contains("name") || !e["name"].is_string())
    suite_error(path, "every entry needs a string 'name'");
  entry.name = e["name"].get<std::string>();
  const std::string where = "entry " + entry.name;
  for (auto it = e.begin(); it != e.end(); ++it)
    if (it.key() != "name" && it.key() != "generate" && it.key() != "preset" &&
        it.key() != "args" && it.key() != "seeds" && it.key() != "format" &&
        !is_option_key(it.key()))
      suite_error(path, where + ": unknown field '" + it.key() + "'");
  if (!e.contains("generate") || !e["generate"].is_string())
    suite_error(path, where + ": needs 'generate' (a generator kind, as in microsim generate KIND)");
  entry.generate = e["generate"].get<std::string>();
  if (e.contains("preset")) entry.preset = entry_preset(e, path, where, dir);
  if (e.contains("args")) entry.args = entry_args(e, path, where);
  if (e.contains("seeds")) entry.seeds = entry_seeds(e, path, where);
  if (e.contains("format")) {
    entry.format = e["format"].is_string() ? e["format"].get<std::string>() : "";
    if (entry.format != "exr" && entry.format != "ply" && entry.format != "obj" && entry.format != "off")
      suite_error(path, where + ": format must be exr, ply, obj or off");
  }
  entry.options = defaults;
  read_options(e, entry.options, path, where);
  return entry;
}
}  // namespace

Suite load_suite(const std::string& path) {
  namespace fs = std::filesystem;
  const Json j = read_suite_json(path);
  Suite s;
  s.file = path;
  s.name = j.value("name", fs::path(path).stem().string());
  s.description = j.value("description", "");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "name" && it.key() != "description" && it.key() != "significance" &&
        it.key() != "defaults" && it.key() != "entries")
      suite_error(path, "unknown field '" + it.key() + "'");
  if (j.contains("significance")) {
    if (!j["significance"].is_number()) suite_error(path, "significance must be a number");
    s.significance = j["significance"].get<double>();
    if (!(s.significance > 0 && s.significance < 1)) suite_error(path, "significance must be in (0, 1)");
  }
  const Options defaults = read_suite_defaults(j, path);
  if (!j.contains("entries") || !j["entries"].is_array() || j["entries"].empty())
    suite_error(path, "needs a non-empty 'entries' array");
  const fs::path dir = fs::path(path).parent_path();
  for (const Json& e : j["entries"]) s.entries.push_back(read_suite_entry(e, path, dir, defaults));
  return s;
}

std::string find_suite(const std::string& name, const std::vector<std::string>& dirs) {
  namespace fs = std::filesystem;
  const bool a_path = name.find('/') != std::string::npos || fs::path(name).extension() == ".json";
  if (a_path && fs::exists(name)) require_regular_input(name, "{suite}");
  if (fs::is_regular_file(name)) return name;
  for (const std::string& d : dirs) {
    fs::path p = fs::path(d) / (name + ".json");
    if (fs::is_regular_file(p)) return p.string();
  }
  // A suite found in several directories (source and build tree) is named once.
  std::set<std::string> names;
  for (const std::string& d : dirs)
    for (const std::string& n : list_suites(d)) names.insert(n);
  std::string known;
  for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
  throw ParameterError("{suite} " + literal_text(name) + ": no such suite (known: " +
                       literal_text(known.empty() ? "none" : known) + ")");
}

std::vector<std::string> list_suites(const std::string& dir) {
  namespace fs = std::filesystem;
  std::vector<std::string> names;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return names;
  for (const auto& f : fs::directory_iterator(dir, ec))
    if (f.path().extension() == ".json") names.push_back(f.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

SurfaceRequest surface_request(const SuiteEntry& e, std::optional<std::uint64_t> seed) {
  SurfaceRequest r{e.generate, {}};
  surface_kind(e.generate);  // an unknown kind first
  if (!e.preset.empty()) read_surface_preset(r, e.preset);
  for (const auto& [key, value] : e.args) set_surface_option(r, key, value);
  if (seed) set_surface_option(r, "seed", std::to_string(*seed));
  return r;
}

Microsurface generate_entry(const SuiteEntry& e, const std::string& suite_file, std::optional<std::uint64_t> seed,
                            const std::string& path, std::vector<std::string>* warnings) {
  try {
    const SurfaceRequest request = surface_request(e, seed);
    const Microsurface s = generate_surface(request, path);
    // The surface is needed now, not with the command's outputs; it stays tied to the enclosing
    // transaction, which removes it if the run fails or is interrupted.
    OutputTransaction written;
    save_surface(s, path);
    written.place_provisionally();
    if (warnings) *warnings = surface_report(request, s, path, false).warnings;
  } catch (const UsageError& err) {
    throw ParameterError("{suite} " + literal_text(suite_file) + ": entry " + literal_text(e.name) + ": " +
                         message_template(err));
  }
  return load_surface(path);
}

void require_safe_entry_names(const Suite& suite, const std::string& path) {
  std::set<std::string> seen;
  for (const auto& e : suite.entries) {
    bool ok = !e.name.empty() && e.name.size() <= 100 && e.name[0] != '.' && e.name[0] != '-';
    for (char c : e.name) ok = ok && c != '/' && c != '\\' && static_cast<unsigned char>(c) >= 0x20;
    if (!ok)
      throw ParameterError("{suite} " + literal_text(path) + ": entry name '" + literal_text(e.name) + "' must be 1-100 characters "
                           "without '/', '\\', control characters or a leading '.' or '-'");
    if (!seen.insert(e.name).second)
      throw ParameterError("{suite} " + literal_text(path) + ": entry name '" + literal_text(e.name) + "' is used twice");
  }
}

}  // namespace microsim::validation
