// Measuring an ensemble of independent surfaces of the same statistics from the command line
// (docs/theory/error-bars.md): one surface in memory at a time, one Table per surface,
// merged by the library (measure/table.hpp) into rows with between-surface errors.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/measure/table.hpp"

namespace microsim {
class Microsurface;
}

namespace microsim::cli {

struct GlobalOptions;

// Loads every file (input_surface) first (a bad file is reported before the long run starts), then calls
// measure(surface, k) for each surface k in turn (one surface in memory at a time) and collects
// the tables it returns.
std::vector<Table> measure_over_surfaces(
    const GlobalOptions& g, const std::vector<std::string>& files,
    const std::function<Table(const Microsurface&, std::size_t)>& measure);

// Fills j["rows"] (and for several surfaces j["per_surface"]): one surface's rows as they are;
// for several, the rows of merge(per_surface).
void put_rows(Json& j, const std::vector<std::string>& files, const std::vector<Table>& per_surface);

}  // namespace microsim::cli
