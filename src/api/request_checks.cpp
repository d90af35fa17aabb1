#include "microsim/api/request_checks.hpp"

#include <iomanip>
#include <sstream>

#include "microsim/common.hpp"

namespace microsim {

void require_integer_in(long long value, long long lo, long long hi, std::string_view parameter) {
  if (value >= lo && value <= hi) return;
  throw ParameterError(placeholder(parameter) + ": must be an integer in [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "] (got '" + std::to_string(value) + "')");
}

void require_given(const std::string& text, std::string_view parameter) {
  if (text.empty()) throw ParameterError(placeholder(parameter) + " is required");
}

std::string fixed_text(double x, int decimals) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(decimals) << x;
  return os.str();
}

}  // namespace microsim
