#include "microsim/api/surface_input.hpp"

#include "microsim/surface/microsurface.hpp"
#include "microsim/surface/surface_io.hpp"

namespace microsim {

SurfaceInput surface_file(const std::string& path) {
  return {path, [path] { return std::make_shared<const Microsurface>(load_surface(path)); }};
}

SurfaceInput surface_held(const std::string& name, std::shared_ptr<const Microsurface> surface) {
  return {name, [surface] { return surface; }};
}

Json surface_names(const std::vector<SurfaceInput>& surfaces) {
  if (surfaces.size() == 1) return surfaces[0].name;
  Json names = Json::array();
  for (const SurfaceInput& s : surfaces) names.push_back(s.name);
  return names;
}

std::vector<Table> measure_each_surface(const std::vector<SurfaceInput>& surfaces,
                                        const std::function<Table(const Microsurface&, std::size_t)>& measure) {
  std::shared_ptr<const Microsurface> first = surfaces.at(0).get();
  for (std::size_t k = 1; k < surfaces.size(); ++k) surfaces[k].get();
  std::vector<Table> tables;
  for (std::size_t k = 0; k < surfaces.size(); ++k) {
    std::shared_ptr<const Microsurface> s = k == 0 ? std::move(first) : surfaces[k].get();
    tables.push_back(measure(*s, k));
  }
  return tables;
}

void put_rows(Json& j, const std::vector<SurfaceInput>& surfaces, const std::vector<Table>& per_surface) {
  if (surfaces.size() == 1) {
    j["rows"] = per_surface[0].rows;
    return;
  }
  std::vector<const Table*> parts;
  for (const Table& t : per_surface) parts.push_back(&t);
  j["rows"] = merge(parts).rows;
  Json ps = Json::array();
  for (std::size_t k = 0; k < surfaces.size(); ++k)
    ps.push_back({{"file", surfaces[k].name}, {"rows", per_surface[k].rows}});
  j["per_surface"] = ps;
}

}  // namespace microsim
