#include "microsim/api/record_file.hpp"

#include "microsim/io/output.hpp"

namespace microsim {

void require_output_format(const std::string& path, std::initializer_list<const char*> allowed) {
  const std::string ext = extension_of(path);
  std::string list;
  for (const char* a : allowed) {
    if (ext == a) return;
    list += std::string(list.empty() ? "" : ", ") + "." + a;
  }
  throw ParameterError("{output} " + literal_text(path) + ": unsupported output format (use " + list + ")");
}

void write_record_file(const std::string& path, const Json& j) {
  if (extension_of(path) == "csv") write_csv_rows(path, j);
  else write_json(path, j);
}

}  // namespace microsim
