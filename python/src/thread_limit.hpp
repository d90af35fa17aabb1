// The `threads` keyword of the Python functions: the TBB limit held while a request runs, as the
// command line's --threads sets it.
#pragma once
#include <tbb/global_control.h>

#include <memory>

#include "microsim/api/request_checks.hpp"

namespace microsim::python {

// No limit for 0 (all cores); ParameterError naming {threads} outside [0, 4096].
inline std::unique_ptr<tbb::global_control> thread_limit(int threads) {
  require_integer_in(threads, 0, 4096, "threads");
  if (threads == 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
}

}  // namespace microsim::python
