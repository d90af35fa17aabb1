#include "microsim/version.hpp"

namespace microsim {

// MICROSIM_VERSION_STRING is set for this file only, from the CMake project version.
const char* version() { return MICROSIM_VERSION_STRING; }

}  // namespace microsim
