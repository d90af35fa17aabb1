#include "microsim/io/preset_file.hpp"
#include "microsim/io/checks.hpp"

#include <sys/stat.h>

#include <cctype>
#include <fstream>
#include <map>
#include <sstream>

#include "microsim/common.hpp"

namespace microsim {

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r"), e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

bool bare_key(const std::string& key) {
  for (const char c : key)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') return false;
  return !key.empty();
}

// The value of one line after its '=', quotes removed: one quoted string or one bare word,
// then nothing but a comment. `where` starts the messages ("PATH: line N: ").
std::string line_value(const std::string& rest, const std::string& key, const std::string& where) {
  const std::string about = where + "key '" + key + "': ";
  if (rest[0] == '"' || rest[0] == '\'') {
    const auto close = rest.find(rest[0], 1);
    if (close == std::string::npos) throw UsageError(about + "unterminated string (got " + rest + ")");
    const std::string after = trim(rest.substr(close + 1));
    if (!after.empty() && after[0] != '#') throw UsageError(about + "expected one value (got " + rest + ")");
    return rest.substr(1, close - 1);
  }
  const std::string value = trim(rest.substr(0, rest.find('#')));
  if (!value.empty() && value[0] == '[') throw UsageError(about + "expected one value, not an array");
  if (value.find_first_of(" \t,") != std::string::npos)
    throw UsageError(about + "expected one value (got " + value + "; quote text that holds spaces or commas)");
  return value;
}

}  // namespace

std::string preset_line_where(const std::string& path, const PresetItem& item) {
  return path + ": line " + std::to_string(item.line) + ": ";
}

std::vector<PresetItem> parse_preset_text(const std::string& text, const std::string& path) {
  std::vector<PresetItem> items;
  std::map<std::string, int> first_line;
  std::istringstream lines(text);
  std::string raw;
  for (int n = 1; std::getline(lines, raw); ++n) {
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#') continue;
    PresetItem item;
    item.line = n;
    const std::string where = preset_line_where(path, item);
    if (line[0] == '[') throw UsageError(where + "sections are not used in presets (keys only)");
    const auto eq = line.find('=');
    item.key = eq == std::string::npos ? "" : trim(line.substr(0, eq));
    const std::string rest = eq == std::string::npos ? "" : trim(line.substr(eq + 1));
    // A dotted key is a table in TOML: a section by another name.
    if (item.key.find('.') != std::string::npos)
      throw UsageError(where + "sections are not used in presets (keys only)");
    if (bare_key(item.key) && !rest.empty() && rest[0] != '#') item.value = line_value(rest, item.key, where);
    if (item.value.empty()) throw UsageError(where + "expected key = value (got '" + line + "')");
    const auto [first, inserted] = first_line.emplace(item.key, n);
    if (!inserted)
      throw UsageError(where + "key '" + item.key + "' is given twice (first on line " +
                       std::to_string(first->second) + ")");
    items.push_back(std::move(item));
  }
  return items;
}

std::vector<PresetItem> read_preset_file(const std::string& path) {
  require_regular_input(path, "");
  struct stat st;
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) throw UsageError(path + ": no such preset file");
  if (st.st_size > (1 << 20)) throw UsageError(path + ": larger than 1 MiB, not a preset");
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  if (!f) throw UsageError(path + ": cannot be read");
  const std::string text = ss.str();
  for (std::size_t k = 0; k < text.size(); ++k) {
    const unsigned char c = text[k];
    if ((c < 0x20 && c != '\n' && c != '\r' && c != '\t') || c == 0x7f)
      throw UsageError(path + ": not a text TOML file (control byte at offset " + std::to_string(k) + ")");
  }
  return parse_preset_text(text, path);
}

}  // namespace microsim
