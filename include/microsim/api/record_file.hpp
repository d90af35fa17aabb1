// A measurement's record as a file: the formats its output path may name, and the writing (JSON,
// or CSV of its rows, by extension; atomically).
#pragma once
#include <initializer_list>
#include <string>

#include "microsim/common.hpp"

namespace microsim {

// ParameterError naming {output} and the accepted extensions unless `path` has one of them.
void require_output_format(const std::string& path, std::initializer_list<const char*> allowed);
// JSON or CSV (rows only) by the extension of `path`, atomically (io/output.hpp).
void write_record_file(const std::string& path, const Json& j);

}  // namespace microsim
