// Records (nlohmann JSON) as Python objects: objects -> dict (in order), arrays of numbers ->
// numpy arrays (int64 when every element is an integer, else float64; arrays of equal-length
// numeric arrays -> 2D), other arrays -> list, null -> None. Numbers keep their exact value, so
// a record equals json.load of the file the command line writes, element by element.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "microsim/common.hpp"

namespace microsim::python {

pybind11::object to_python(const Json& j);

}  // namespace microsim::python
