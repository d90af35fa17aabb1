// EXR tables: named float channels of one size with a self-describing header (every parameter
// as an attribute), written atomically (io/atomic_write.hpp) and read back with their header
// checked before the pixels are allocated.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "microsim/common.hpp"

namespace microsim {

// A float image table: named channels of width x height, plus header attributes (numbers become
// double attributes, strings string attributes, anything else its JSON text).
struct ExrTable {
  int width = 0, height = 0;
  std::vector<std::string> channel_names;
  std::vector<std::vector<float>> channels;  // each width*height, row-major
  Json attributes = Json::object();
};
void write_exr(const std::string& path, const ExrTable& t);
// Reads a table; `check_header` (if given) sees the size, channel names and attributes (no pixels
// yet) and may refuse the file before its pixels are allocated. Width and height must be >= 1
// and the pixels must fit in memory (io/checks.hpp).
ExrTable read_exr(const std::string& path,
                  const std::function<void(const ExrTable&)>& check_header = {});
// write_exr with channel c's width x height row-major floats read from pixels[c] instead of
// t.channels (which is ignored): a large image (a heightfield's own heights) is written from
// where it is held, without a copy; OpenEXR compresses it a block of scanlines at a time.
void write_exr_pixels(const std::string& path, const ExrTable& t, const std::vector<const float*>& pixels);

}  // namespace microsim
