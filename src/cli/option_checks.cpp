#include "option_checks.hpp"

#include <sys/stat.h>

#include <fstream>
#include <set>
#include <sstream>

#include "microsim/common.hpp"

namespace microsim::cli {

namespace {
// A validator running one of the checks.hpp parsers; its UsageError text becomes CLI11's message
// (CLI11 prefixes the option name).
CLI::Validator from_check(std::function<void(const std::string&)> check, const std::string& desc) {
  return CLI::Validator(
      [check](std::string& value) -> std::string {
        try {
          check(value);
        } catch (const UsageError& e) {
          return e.what();
        }
        return {};
      },
      desc);
}
}  // namespace

CLI::Validator number_in(const Range& r) {
  return from_check([r](const std::string& v) { parse_number_in(v, r, ""); }, "in " + r.text());
}

CLI::Validator finite_number() {
  return from_check([](const std::string& v) { parse_number_in(v, {-1e300, 1e300}, ""); }, "");
}

CLI::Validator integer_in(long long lo, long long hi) {
  return from_check([lo, hi](const std::string& v) { parse_integer_in(v, lo, hi, ""); },
                    "in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

CLI::Validator seed_value() {
  return from_check([](const std::string& v) { parse_seed(v, ""); }, "in [0, 2^64-1]");
}

void add_preset_option(CLI::App& cmd, const std::string& help) {
  cmd.add_option("--config", help)->configurable(false);
}

namespace {
std::string option_names(const CLI::App& cmd) {
  std::string names;
  for (const CLI::Option* op : cmd.get_options()) {
    if (op->get_lnames().empty() || op->get_lnames()[0] == "config" || op->get_lnames()[0] == "help")
      continue;
    names += (names.empty() ? "" : ", ") + op->get_lnames()[0];
  }
  return names;
}

// Reads the preset's text, refusing what cannot be one: a missing or non-regular file, more than
// 1 MiB, control bytes (a binary file), a section header or a line that is not `key = value`.
std::string read_preset_text(const std::string& path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
    throw UsageError("--config " + path + ": no such preset file");
  if (st.st_size > (1 << 20)) throw UsageError("--config " + path + ": larger than 1 MiB, not a preset");
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  if (!f) throw UsageError("--config " + path + ": cannot be read");
  std::string text = ss.str();
  for (std::size_t k = 0; k < text.size(); ++k) {
    unsigned char c = text[k];
    if ((c < 0x20 && c != '\n' && c != '\r' && c != '\t') || c == 0x7f)
      throw UsageError("--config " + path + ": not a text TOML file (control byte at offset " +
                       std::to_string(k) + ")");
  }
  std::istringstream lines(text);
  std::string line;
  for (int n = 1; std::getline(lines, line); ++n) {
    line = CLI::detail::trim_copy(line);
    if (line.empty() || line[0] == '#') continue;
    const auto where = "--config " + path + ": line " + std::to_string(n) + ": ";
    if (line[0] == '[') throw UsageError(where + "sections are not used in presets (keys only)");
    auto eq = line.find('=');
    if (eq == std::string::npos || CLI::detail::trim_copy(line.substr(0, eq)).empty() ||
        CLI::detail::trim_copy(line.substr(eq + 1)).empty())
      throw UsageError(where + "expected key = value (got '" + line + "')");
  }
  return text;
}
}  // namespace

void apply_preset(CLI::App& cmd) {
  CLI::Option* cfg = cmd.get_option_no_throw("--config");
  if (!cfg || cfg->count() == 0) return;
  const std::string path = cfg->results().at(0);
  std::istringstream in(read_preset_text(path));
  std::vector<CLI::ConfigItem> items;
  try {
    items = CLI::ConfigTOML().from_config(in);
  } catch (const CLI::ParseError& e) {
    throw UsageError("--config " + path + ": " + e.what());
  }
  std::set<std::string> seen;
  for (const CLI::ConfigItem& item : items) {
    const std::string key = item.fullname();
    const std::string where = "--config " + path + ": key '" + key + "'";
    if (!item.parents.empty() || item.name == "--" || item.name == "++")
      throw UsageError(where + ": sections are not used in presets (keys only)");
    if (!seen.insert(key).second) throw UsageError(where + " is given twice");
    CLI::Option* op = key == "config" || key == "help" ? nullptr : cmd.get_option_no_throw("--" + key);
    if (!op || !op->get_configurable())
      throw UsageError(where + ": unknown key for '" + cmd.get_name() + "' (known: " +
                       option_names(cmd) + ")");
    if (op->count() > 0) continue;  // the command line wins
    std::vector<std::string> values = item.inputs;
    if (op->get_expected_min() == 0) {  // a flag: true or false
      if (values.size() != 1 || (values[0] != "true" && values[0] != "false"))
        throw UsageError(where + ": expected true or false");
    } else if (values.size() != 1 && op->get_items_expected_max() == 1) {
      throw UsageError(where + ": expected one value (got " + std::to_string(values.size()) + ")");
    }
    try {
      op->add_result(values);
      op->run_callback();
    } catch (const CLI::ParseError& e) {
      throw UsageError(where + ": " + e.what());
    }
  }
}

void on_run(CLI::App* cmd, std::function<void()> run) {
  cmd->callback([cmd, run] {
    apply_preset(*cmd);
    run();
  });
}

void add_replicates_option(CLI::App& cmd, int& replicates) {
  cmd.add_option("--replicates", replicates,
                 "Independent randomized replicates the rays are split into; the standard errors "
                 "are those of the replicate means (>= 2)")
      ->capture_default_str()
      ->check(integer_in(2, 1 << 16));
}

}  // namespace microsim::cli
