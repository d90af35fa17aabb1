#include "microsim/common.hpp"

namespace microsim {

Estimate binomial_estimate(std::uint64_t k, std::uint64_t n) {
  Estimate e;
  e.n = n;
  if (n == 0) return e;
  e.mean = static_cast<double>(k) / static_cast<double>(n);
  e.stderr_ = std::sqrt(std::max(0.0, e.mean * (1.0 - e.mean)) / static_cast<double>(n));
  return e;
}

namespace {
bool is_parameter_char(char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_'; }
}  // namespace

std::string spell_parameters(std::string_view message, const ParameterSpeller& speller) {
  std::string out;
  std::size_t k = 0;
  while (k < message.size()) {
    const std::size_t open = message.find('{', k);
    if (open == std::string_view::npos) break;
    out.append(message.substr(k, open - k));
    if (open + 1 < message.size() && message[open + 1] == '{') {
      out += '{';
      k = open + 2;
      continue;
    }
    std::size_t end = open + 1;
    while (end < message.size() && is_parameter_char(message[end])) ++end;
    if (end > open + 1 && end < message.size() && message[end] == '}') {
      out += speller(message.substr(open + 1, end - open - 1));
      k = end + 1;
    } else {
      out += '{';
      k = open + 1;
    }
  }
  if (k < message.size()) out.append(message.substr(k));
  return out;
}

std::string spelled_message(const UsageError& e, const ParameterSpeller& speller) {
  if (dynamic_cast<const ParameterError*>(&e)) return spell_parameters(e.what(), speller);
  return e.what();
}

std::string placeholder(std::string_view name) { return "{" + std::string(name) + "}"; }

std::string literal_text(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    out += c;
    if (c == '{') out += '{';
  }
  return out;
}

std::string message_template(const UsageError& e) {
  if (dynamic_cast<const ParameterError*>(&e)) return e.what();
  return literal_text(e.what());
}

}  // namespace microsim
