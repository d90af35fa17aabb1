// A surface held by Python (microsim.Surface): the geometry is shared (never copied) between
// Python objects and the requests that measure it.
#pragma once
#include <memory>
#include <optional>
#include <string>

#include "microsim/surface/microsurface.hpp"

namespace microsim::python {

struct Surface {
  std::shared_ptr<const Microsurface> s;
  std::optional<std::string> path;  // the file it was loaded from
};

}  // namespace microsim::python
