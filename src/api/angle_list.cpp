#include "microsim/api/angle_list.hpp"

#include <cmath>
#include <stdexcept>

#include "microsim/common.hpp"
#include "microsim/api/request_checks.hpp"
#include "microsim/io/checks.hpp"

namespace microsim {

namespace {

// The whole of `item` as a finite number, or the list's ParameterError.
double list_number(const std::string& item, const std::string& text, const std::string& name) {
  try {
    std::size_t used = 0;
    double x = std::stod(item, &used);
    if (used != item.size() || !std::isfinite(x)) throw std::invalid_argument(item);
    return x;
  } catch (const std::exception&) {
    throw ParameterError(name + " '" + literal_text(text) + "': expected a number, a,b,c or start:stop:step");
  }
}

std::vector<double> angle_range(const std::string& text, const std::string& name) {
  const std::vector<std::string> parts = split_items(text, ':', name);
  if (parts.size() != 3) throw ParameterError(name + " '" + literal_text(text) + "': expected start:stop:step");
  double a = list_number(parts[0], text, name), b = list_number(parts[1], text, name),
         step = list_number(parts[2], text, name);
  if (!(step > 0) || b < a)
    throw ParameterError(name + " '" + literal_text(text) + "': need step > 0 and stop >= start");
  if ((b - a) / step > 100000) throw ParameterError(name + " '" + literal_text(text) + "': too many values");
  std::vector<double> out;
  for (int k = 0; a + k * step <= b + 1e-9; ++k) out.push_back(a + k * step);
  return out;
}

}  // namespace

AngleList angle_list(const std::string& text, std::string_view parameter) {
  const std::string name = placeholder(parameter);
  AngleList out{text, {}};
  if (text.find(':') != std::string::npos) {
    out.degrees = angle_range(text, name);
  } else {
    for (const std::string& p : split_items(text, ',', name)) out.degrees.push_back(list_number(p, text, name));
  }
  if (out.degrees.empty()) throw ParameterError(name + " is empty");
  return out;
}

AngleList azimuth_list(const std::string& text, std::string_view parameter) {
  AngleList phis = angle_list(text, parameter);
  for (double p : phis.degrees)
    if (!(std::abs(p) <= kMaxAzimuthDeg))
      throw ParameterError(placeholder(parameter) + " must be azimuths in [-" + number_text(kMaxAzimuthDeg) + ", " +
                           number_text(kMaxAzimuthDeg) + "] degrees (got " + number_text(p) + ")");
  return phis;
}

void require_above_horizon(const std::vector<double>& thetas, std::string_view parameter) {
  for (double t : thetas)
    if (!(t >= 0 && t < 90))
      throw ParameterError(placeholder(parameter) + " must be in [0, 90) degrees (got " + fixed_text(t, 2) + ")");
}

}  // namespace microsim
