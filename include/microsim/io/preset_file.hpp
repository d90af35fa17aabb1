// Preset files (surfaces/*.toml: `--config FILE` of the command line, a suite entry's "preset",
// read_surface_preset): the one reader and its rules, so that a preset is read the same way
// everywhere. A preset is a small part of TOML: `key = value` lines, '#' comments and blank
// lines. A key is bare (letters, digits, '-' and '_'); a value is one bare word (a number,
// true, false, or text without spaces, commas or '#') or one "double" or 'single' quoted string
// (taken as written: no escapes), followed by nothing but a comment. What the keys mean is the
// caller's (the command's options, or the surface spec's).
#pragma once
#include <string>
#include <vector>

namespace microsim {

// One `key = value` line.
struct PresetItem {
  std::string key;
  std::string value;  // the value's text, quotes removed
  int line = 0;       // in the file, from 1
};

// The items of the preset at `path`, in file order. UsageError, one line naming the file:
//   "PATH: no such preset file" (missing or not a regular file), "PATH: larger than 1 MiB, not a
//   preset", "PATH: cannot be read", "PATH: not a text TOML file (control byte at offset K)",
// or naming the line (see parse_preset_text).
std::vector<PresetItem> read_preset_file(const std::string& path);
// The same rules for a preset's text (`path` only names it). UsageError "PATH: line N: ..." for
// a section ("sections are not used in presets (keys only)", also for a dotted key), a line that
// is not `key = value` with a bare key and a value, an unterminated string, an array or more than
// one value ("key 'K': expected one value ..."), and a key given twice.
std::vector<PresetItem> parse_preset_text(const std::string& text, const std::string& path);
// "PATH: line N: ", the start of every message about one item.
std::string preset_line_where(const std::string& path, const PresetItem& item);

}  // namespace microsim
