// Writing results: JSON records, CSV mirrors of JSON rows, EXR tables with self-describing
// headers (io/exr_table.hpp). Every write is atomic (io/atomic_write.hpp: temporary file in the
// same folder, checked, synced, then renamed): a failed write (a full disk) leaves neither the
// file nor a temporary.
#pragma once
#include <string>

#include "microsim/common.hpp"
#include "microsim/io/atomic_write.hpp"
#include "microsim/io/exr_table.hpp"

namespace microsim {

// Extension of a path, lower case, without the dot ("json", "csv", "exr"...).
std::string extension_of(const std::string& path);

void write_json(const std::string& path, const Json& j);
// One CSV line per element of j["rows"]; nested objects and arrays are skipped (CSV is flat).
void write_csv_rows(const std::string& path, const Json& j);

}  // namespace microsim
