#include "json_to_python.hpp"

#include <cstdint>
#include <limits>
#include <vector>

namespace py = pybind11;

namespace microsim::python {

namespace {

// Every element a number; `integers` tells whether all are integers that fit int64.
bool numeric(const Json& a, bool& integers) {
  integers = true;
  for (const auto& x : a) {
    if (!x.is_number()) return false;
    if (x.is_number_float()) integers = false;
    else if (x.is_number_unsigned() &&
             x.get<std::uint64_t>() > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
      integers = false;
  }
  return true;
}

py::object numeric_array(const Json& a, bool integers) {
  if (integers) {
    py::array_t<std::int64_t> out(static_cast<py::ssize_t>(a.size()));
    auto* p = out.mutable_data();
    for (std::size_t k = 0; k < a.size(); ++k) p[k] = a[k].get<std::int64_t>();
    return std::move(out);
  }
  py::array_t<double> out(static_cast<py::ssize_t>(a.size()));
  auto* p = out.mutable_data();
  for (std::size_t k = 0; k < a.size(); ++k) p[k] = a[k].get<double>();
  return std::move(out);
}

// Rows of equal length, all numeric: a 2D table.
py::object table(const Json& a) {
  const std::size_t cols = a[0].size();
  if (cols == 0) return py::none();
  bool all_int = true;
  for (const auto& row : a) {
    bool integers = false;
    if (!row.is_array() || row.size() != cols || !numeric(row, integers)) return py::none();
    all_int = all_int && integers;
  }
  const std::vector<py::ssize_t> shape = {static_cast<py::ssize_t>(a.size()), static_cast<py::ssize_t>(cols)};
  if (all_int) {
    py::array_t<std::int64_t> out(shape);
    auto* p = out.mutable_data();
    for (const auto& row : a)
      for (const auto& x : row) *p++ = x.get<std::int64_t>();
    return std::move(out);
  }
  py::array_t<double> out(shape);
  auto* p = out.mutable_data();
  for (const auto& row : a)
    for (const auto& x : row) *p++ = x.get<double>();
  return std::move(out);
}

}  // namespace

py::object to_python(const Json& j) {
  switch (j.type()) {
    case Json::value_t::null: return py::none();
    case Json::value_t::boolean: return py::bool_(j.get<bool>());
    case Json::value_t::number_integer: return py::int_(j.get<std::int64_t>());
    case Json::value_t::number_unsigned: return py::int_(j.get<std::uint64_t>());
    case Json::value_t::number_float: return py::float_(j.get<double>());
    case Json::value_t::string: return py::str(j.get<std::string>());
    case Json::value_t::object: {
      py::dict d;
      for (auto it = j.begin(); it != j.end(); ++it) d[py::str(it.key())] = to_python(it.value());
      return std::move(d);
    }
    case Json::value_t::array: {
      bool integers = false;
      if (!j.empty() && numeric(j, integers)) return numeric_array(j, integers);
      if (!j.empty() && j[0].is_array()) {
        py::object t = table(j);
        if (!t.is_none()) return t;
      }
      py::list l;
      for (const auto& x : j) l.append(to_python(x));
      return std::move(l);
    }
    default: return py::none();  // binary values do not occur in records
  }
}

}  // namespace microsim::python
