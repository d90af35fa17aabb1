#include "ensemble.hpp"

#include "cli_common.hpp"
#include "microsim/surface/microsurface.hpp"

namespace microsim::cli {

std::vector<Table> measure_over_surfaces(
    const GlobalOptions& g, const std::vector<std::string>& files,
    const std::function<Table(const Microsurface&, std::size_t)>& measure) {
  std::vector<Microsurface> first;
  first.push_back(input_surface(g, files.at(0)));
  for (std::size_t k = 1; k < files.size(); ++k) input_surface(g, files[k]);
  std::vector<Table> tables;
  for (std::size_t k = 0; k < files.size(); ++k) {
    Microsurface s = k == 0 ? std::move(first[0]) : input_surface(g, files[k]);
    tables.push_back(measure(s, k));
  }
  return tables;
}

void put_rows(Json& j, const std::vector<std::string>& files, const std::vector<Table>& per_surface) {
  if (files.size() == 1) {
    j["rows"] = per_surface[0].rows;
    return;
  }
  std::vector<const Table*> parts;
  for (const Table& t : per_surface) parts.push_back(&t);
  j["rows"] = merge(parts).rows;
  Json ps = Json::array();
  for (std::size_t k = 0; k < files.size(); ++k)
    ps.push_back({{"file", files[k]}, {"rows", per_surface[k].rows}});
  j["per_surface"] = ps;
}

}  // namespace microsim::cli
