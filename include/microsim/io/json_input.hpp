// JSON that comes from a user's file (suites, mesh sidecars, merge parts) or from a file's header
// (the descriptions stored in EXR and RGL files) is parsed with two limits, so that no input can
// drive the program deeper or larger than it was built for: a nesting depth and a size. Beyond
// either the input is refused with a UsageError naming it (exit 2), before the document is built.
//
// Why a depth limit: parsing itself is iterative, but everything done afterwards with a document
// (copying, printing, converting to Python) recurses once per level, so a file nested 100,000
// levels deep would overflow the stack there. Records written by microsim nest at most 6 levels.
#pragma once
#include <cstddef>
#include <istream>
#include <string>

#include "microsim/common.hpp"

namespace microsim {

struct JsonLimits {
  int max_depth = 64;                      // objects and arrays nested inside each other
  std::size_t max_bytes = std::size_t(64) << 20;  // the text's size
  bool ignore_comments = false;            // suites allow // and /* */ comments
};

// Parses `text`; `what` names the input in the messages ("part p1.json", "x.exr header"): a
// ParameterError's message template (common.hpp), a path in it given as literal_text(path).
// Limits: ParameterError. Malformed JSON: Json::parse_error, as Json::parse throws it, for the
// caller's own message.
Json parse_json_input(const std::string& text, const std::string& what, const JsonLimits& limits = {});
// Reads at most limits.max_bytes + 1 bytes of `in` and parses them as above.
Json parse_json_input(std::istream& in, const std::string& what, const JsonLimits& limits = {});

}  // namespace microsim
