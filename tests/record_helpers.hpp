// Comparing records written by the microsim binary: a record without its timing fields, read
// from a file.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "cli_helpers.hpp"

namespace microsim::testing {

// The record without its timing fields (wall time, "..._seconds", rays per second) and the MPI
// `ranks` count: what must be equal between runs that split the same work differently.
inline nlohmann::json record_without_timings(nlohmann::json j) {
  if (j.is_object()) {
    nlohmann::json out = nlohmann::json::object();
    for (auto it = j.begin(); it != j.end(); ++it) {
      const std::string& k = it.key();
      const bool timing = (k.size() >= 7 && k.compare(k.size() - 7, 7, "seconds") == 0) ||
                          k.find("per_second") != std::string::npos;
      if (!timing && k != "ranks") out[k] = record_without_timings(it.value());
    }
    return out;
  }
  if (j.is_array())
    for (auto& e : j) e = record_without_timings(e);
  return j;
}

inline nlohmann::json read_record(const std::string& path) { return nlohmann::json::parse(slurp(path)); }

}  // namespace microsim::testing
