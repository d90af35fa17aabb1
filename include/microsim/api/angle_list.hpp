// Lists of angles as a request gives them: "a", "a,b,c" or "start:stop:step" in degrees. The
// text is kept beside the values because records echo the parameter as it was given.
#pragma once
#include <string>
#include <string_view>
#include <vector>

namespace microsim {

struct AngleList {
  std::string text;             // as given ("0:85:5"); the record's parameters echo it
  std::vector<double> degrees;  // the values it names, in order
};

// Parses `text` ("a:b:step" inclusive, "a,b,c" or "a"); ParameterError naming `parameter`
// ("{theta} '1,x': expected a number, a,b,c or start:stop:step").
AngleList angle_list(const std::string& text, std::string_view parameter);

// Largest accepted |azimuth| in degrees (ten turns): a larger one has lost its fractional degrees
// to rounding, and 1e308 makes no direction at all.
constexpr double kMaxAzimuthDeg = 3600;
// angle_list, then ParameterError naming `parameter` unless every |azimuth| <= kMaxAzimuthDeg.
AngleList azimuth_list(const std::string& text, std::string_view parameter);
// ParameterError naming `parameter` unless every angle is in [0, 90).
void require_above_horizon(const std::vector<double>& thetas_deg, std::string_view parameter);

}  // namespace microsim
