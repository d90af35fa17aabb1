#include "option_checks.hpp"

#include <algorithm>
#include "output_paths.hpp"

#include "microsim/common.hpp"
#include "microsim/io/preset_file.hpp"

namespace microsim::cli {

std::string option_spelling(std::string_view parameter) {
  // The parameters whose option is not "--" and the name with '-' for '_'.
  static const std::pair<std::string_view, std::string_view> options_named_otherwise[] = {{"output", "-o"}};
  for (const auto& [name, option] : options_named_otherwise)
    if (parameter == name) return std::string(option);
  std::string option = "--" + std::string(parameter);
  std::replace(option.begin() + 2, option.end(), '_', '-');
  return option;
}

std::string cli_message(const UsageError& e) { return spelled_message(e, option_spelling); }

namespace {
// A validator running one of the checks.hpp parsers; its UsageError text becomes CLI11's message
// (CLI11 prefixes the option name).
CLI::Validator from_check(std::function<void(const std::string&)> check, const std::string& desc) {
  return CLI::Validator(
      [check](std::string& value) -> std::string {
        try {
          check(value);
        } catch (const UsageError& e) {
          return cli_message(e);
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

}  // namespace

// The file is read and checked by the library's preset reader (io/preset_file.hpp), as
// read_surface_preset reads it; here each key must be one of the command's options, and the
// messages about a key have the library's form ("PATH: line N: --alpha: must be ...").
void apply_preset(CLI::App& cmd) {
  CLI::Option* cfg = cmd.get_option_no_throw("--config");
  if (!cfg || cfg->count() == 0) return;
  const std::string path = cfg->results().at(0);
  std::vector<PresetItem> items;
  try {
    items = read_preset_file(path);
  } catch (const UsageError& e) {
    throw ParameterError("{config} " + message_template(e));
  }
  for (const PresetItem& item : items) {
    const std::string where = "--config " + preset_line_where(path, item);
    CLI::Option* op =
        item.key == "config" || item.key == "help" ? nullptr : cmd.get_option_no_throw("--" + item.key);
    if (!op || !op->get_configurable())
      throw UsageError(where + "unknown option '" + item.key + "' for '" + cmd.get_name() + "' (known: " +
                       option_names(cmd) + ")");
    // A preset holds a command's parameters; the files it reads and writes are the command
    // line's (a required option is checked before any preset is read, so it could not apply).
    if (op->get_required() || item.key == "output" || item.key == "input")
      throw UsageError(where + "'" + item.key + "' names a file of the run: give --" + item.key +
                       " on the command line, not in a preset");
    if (op->count() > 0) continue;  // the command line wins
    if (op->get_expected_min() == 0 && item.value != "true" && item.value != "false")  // a flag
      throw UsageError(where + "--" + item.key + ": expected true or false (got '" + item.value + "')");
    try {
      op->add_result(item.value);
      op->run_callback();
    } catch (const CLI::ParseError& e) {
      throw UsageError(where + e.what());
    }
  }
}

void on_run(CLI::App* cmd, std::function<void()> run) {
  cmd->callback([cmd, run] {
    apply_preset(*cmd);
    refuse_outputs_naming_inputs(*cmd, "");  // again: the preset may name an output
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
