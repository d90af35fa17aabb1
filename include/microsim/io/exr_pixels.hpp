// Writing an EXR image from pixels held elsewhere (a heightfield's own heights), without a copy.
#pragma once
#include <string>
#include <vector>

#include "microsim/io/output.hpp"

namespace microsim {

// write_exr with channel c's width x height row-major floats read from pixels[c] instead of
// t.channels (which is ignored): a large image is written from where it is held, without a
// copy; OpenEXR compresses it a block of scanlines at a time.
void write_exr_pixels(const std::string& path, const ExrTable& t, const std::vector<const float*>& pixels);

}  // namespace microsim
