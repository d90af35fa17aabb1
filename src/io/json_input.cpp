#include "microsim/io/json_input.hpp"

#include <iterator>

namespace microsim {

namespace {
std::string bytes_text(std::size_t n) {
  return n >= (std::size_t(1) << 20) ? std::to_string(n >> 20) + " MiB" : std::to_string(n) + " bytes";
}
}  // namespace

Json parse_json_input(const std::string& text, const std::string& what, const JsonLimits& limits) {
  if (text.size() > limits.max_bytes)
    throw ParameterError(what + " is larger than " + bytes_text(limits.max_bytes) + ", the most accepted");
  // nlohmann's parser reports the depth of every event; refusing at the first object or array
  // that opens below the limit stops the parse before anything deeper is built.
  const Json::parser_callback_t depth_guard = [&](int depth, Json::parse_event_t event, Json&) {
    const bool opens = event == Json::parse_event_t::object_start ||
                       event == Json::parse_event_t::array_start;
    if (opens && depth >= limits.max_depth)
      throw ParameterError(what + " nests objects and arrays deeper than " +
                           std::to_string(limits.max_depth) + " levels, the most accepted");
    return true;
  };
  return Json::parse(text, depth_guard, /*allow_exceptions=*/true, limits.ignore_comments);
}

Json parse_json_input(std::istream& in, const std::string& what, const JsonLimits& limits) {
  std::string text;
  std::istreambuf_iterator<char> it(in), end;
  // One byte past the limit is enough to know the input is too large.
  for (; it != end && text.size() <= limits.max_bytes; ++it) text.push_back(*it);
  return parse_json_input(text, what, limits);
}

}  // namespace microsim
