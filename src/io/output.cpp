#include "microsim/io/output.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iomanip>

namespace microsim {

std::string extension_of(const std::string& path) {
  auto slash = path.find_last_of('/');
  auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string e = path.substr(dot + 1);
  std::transform(e.begin(), e.end(), e.begin(), ::tolower);
  return e;
}

void write_json(const std::string& path, const Json& j) {
  write_stream_atomically(path, [&](std::ofstream& f) { f << std::setw(2) << j << "\n"; });
}

void write_csv_rows(const std::string& path, const Json& j) {
  const auto& rows = j.at("rows");
  std::vector<std::string> cols;
  for (const auto& row : rows)
    for (auto it = row.begin(); it != row.end(); ++it)
      if (!it->is_structured() && std::find(cols.begin(), cols.end(), it.key()) == cols.end())
        cols.push_back(it.key());
  write_stream_atomically(path, [&](std::ofstream& f) {
    f << std::setprecision(10);
    for (std::size_t c = 0; c < cols.size(); ++c) f << (c ? "," : "") << cols[c];
    f << "\n";
    for (const auto& row : rows) {
      for (std::size_t c = 0; c < cols.size(); ++c) {
        if (c) f << ",";
        auto it = row.find(cols[c]);
        if (it == row.end() || it->is_null()) continue;
        if (it->is_string()) f << it->get<std::string>(); else f << *it;
      }
      f << "\n";
    }
  });
}

}  // namespace microsim
