// Checks shared by the measurement requests: counts as integers in range, with the message the
// command line's option validators give (the parameter named by its placeholder).
#pragma once
#include <string>
#include <string_view>

namespace microsim {

// Largest accepted rays: about a day of tracing at 10 Mrays/s on one direction.
constexpr long long kMaxRays = 1000000000000LL;
// Largest accepted replicates of the Monte Carlo estimators (measure/replicates.hpp).
constexpr int kMaxReplicates = 1 << 16;

// ParameterError "{rays}: must be an integer in [1, 1000000000000] (got '0')" unless
// lo <= value <= hi.
void require_integer_in(long long value, long long lo, long long hi, std::string_view parameter);
// ParameterError "{theta_o} is required" when a required list was not given (its text is empty).
void require_given(const std::string& text, std::string_view parameter);
// `x` with `decimals` fixed decimals, as messages and tables print angles ("85.00").
std::string fixed_text(double x, int decimals);

}  // namespace microsim
