// The surfaces a measurement request names: files loaded when measured, or surfaces already in
// memory (the Python module's), each with the name its record gives it ("file").
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/measure/table.hpp"

namespace microsim {

class Microsurface;

struct SurfaceInput {
  std::string name;  // the record's "file": the path, or the name of a surface in memory
  // The surface (loaded from the file on each call, or the one held).
  std::function<std::shared_ptr<const Microsurface>()> get;
};

// The surface file at `path`, loaded when measured.
SurfaceInput surface_file(const std::string& path);
// A surface in memory, named `name` in the record.
SurfaceInput surface_held(const std::string& name, std::shared_ptr<const Microsurface> surface);

// The record's "file": the one name, or the list of an ensemble's.
Json surface_names(const std::vector<SurfaceInput>& surfaces);

// Measures an ensemble of independent surfaces of the same statistics (docs/theory/error-bars.md):
// gets every surface first (a bad file is reported before the long run starts), then calls
// measure(surface, k) for each in turn (one surface in memory at a time) and collects its tables.
std::vector<Table> measure_each_surface(const std::vector<SurfaceInput>& surfaces,
                                        const std::function<Table(const Microsurface&, std::size_t)>& measure);

// Fills j["rows"] (and for several surfaces j["per_surface"]): one surface's rows as they are;
// for several, the rows of merge(per_surface) with between-surface errors.
void put_rows(Json& j, const std::vector<SurfaceInput>& surfaces, const std::vector<Table>& per_surface);

}  // namespace microsim
