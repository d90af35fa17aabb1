// Writing results: JSON records, CSV mirrors of JSON rows, EXR tables with self-describing
// headers. Every write is atomic (temporary file in the same folder, then rename).
#pragma once
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "microsim/common.hpp"

namespace microsim {

// Extension of a path, lower case, without the dot ("json", "csv", "exr"...).
std::string extension_of(const std::string& path);

// Calls write(tmp_path) and renames tmp_path to path; removes tmp_path if write throws.
void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write);

void write_json(const std::string& path, const Json& j);
// One CSV line per element of j["rows"]; nested objects and arrays are skipped (CSV is flat).
void write_csv_rows(const std::string& path, const Json& j);

// A float image table: named channels of width x height, plus header attributes (numbers become
// double attributes, strings string attributes, anything else its JSON text).
struct ExrTable {
  int width = 0, height = 0;
  std::vector<std::string> channel_names;
  std::vector<std::vector<float>> channels;  // each width*height, row-major
  Json attributes = Json::object();
};
void write_exr(const std::string& path, const ExrTable& t);
ExrTable read_exr(const std::string& path);

}  // namespace microsim
