// Comma-separated number lists of the analysis programs' options ("0.2,0.5,1").
#pragma once
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace microsim::analysis {

inline std::vector<double> parse_list(const char* s) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(std::atof(item.c_str()));
  return v;
}

}  // namespace microsim::analysis
